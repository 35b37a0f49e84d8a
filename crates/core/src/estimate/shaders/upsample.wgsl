// ISPM joint bilateral upsampling (section 5.2): the indirect light splatted at 1/k
// resolution is brought to full resolution by weighting the 2×2 nearest low-resolution
// texels with bilinear weights times a normal term (cos^32) and a plane-distance term, both
// measured between this pixel's G-buffer sample and the one each low-res texel shaded;
// 0 on surfaces whose BSDF has no non-delta lobe; on Lambertian surfaces the samples' light is
// rescaled by the ratio of this pixel's albedo to theirs (texture detail at full resolution).
// The light estimated at full resolution (`full`: the caustic photons' splat, whose detail
// the low-resolution samples would alias) is added as it is; a 1x1 texture adds nothing.

struct UpsampleParams {
    eye: vec3<f32>,
    subsample: u32,
}

@group(0) @binding(0) var<uniform> params: UpsampleParams;
@group(0) @binding(1) var g_position: texture_2d<f32>;
@group(0) @binding(2) var g_normals: texture_2d<f32>;
@group(0) @binding(3) var low: texture_2d<f32>;
@group(0) @binding(4) var g_diffuse: texture_2d<f32>;
@group(0) @binding(5) var g_specular: texture_2d<f32>;
@group(0) @binding(6) var full: texture_2d<f32>;

// This pixel's light estimated at full resolution (0 where no such estimate is bound).
fn full_resolution(px: vec2<i32>) -> vec3<f32> {
    let fdims = vec2<i32>(textureDimensions(full));
    if any(fdims != vec2<i32>(textureDimensions(g_position))) {
        return vec3<f32>(0.0);
    }
    return textureLoad(full, px, 0).xyz;
}

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let px = vec2<i32>(frag.xy);
    let pos = textureLoad(g_position, px, 0);
    if pos.w == 0.0 {
        return vec4<f32>(0.0);
    }
    // A surface without a non-delta lobe (a mirror, clear glass) scatters no photon light
    // towards the eye (the estimate term has its f = 0): its indirect light is 0, whatever
    // the low-resolution samples around it, on other surfaces, carry (a mirror's rim next
    // to a lit floor took the floor's light before).
    let diffuse = textureLoad(g_diffuse, px, 0);
    let specular = textureLoad(g_specular, px, 0);
    let own = full_resolution(px);
    if max3(diffuse.xyz) == 0.0 && (max3(specular.xyz) == 0.0 || diffuse.w < MIRROR_ROUGHNESS) {
        return vec4<f32>(own, 0.0);
    }
    // Lambertian pixels take their neighbours' light demodulated by the neighbours' albedo
    // and modulated by their own (the irradiance is what varies smoothly; a texture's
    // detail is the pixel's): a sample contributes v·ρ_pixel/ρ_sample where both surfaces are
    // Lambertian (no specular lobe, no Fresnel coupling) and the sample's albedo is not ~0.
    let lambertian = max3(specular.xyz) == 0.0 && specular.w <= 0.5;
    let n = oct_decode(textureLoad(g_normals, px, 0).xy);
    let k = i32(params.subsample);
    let dims = vec2<i32>(textureDimensions(g_position));
    let ldims = vec2<i32>(textureDimensions(low));
    // Low-res texel i shaded full-res pixel i·k + k/2.
    let c = (frag.xy - 0.5 - f32(k / 2)) / f32(k);
    let base = vec2<i32>(floor(c));
    let fr = c - floor(c);
    // Plane-distance tolerance: 1% of the distance to the eye.
    let tol = 0.01 * length(params.eye - pos.xyz) + 1e-6;
    var sum = vec3<f32>(0.0);
    var wsum = 0.0;
    var nearest = vec3<f32>(0.0);
    var best = -1.0;
    for (var j = 0; j < 2; j++) {
        for (var i = 0; i < 2; i++) {
            let l = clamp(base + vec2<i32>(i, j), vec2<i32>(0), ldims - 1);
            let q = min(l * k + k / 2, dims - 1);
            let qp = textureLoad(g_position, q, 0);
            if qp.w == 0.0 {
                continue;
            }
            let qn = oct_decode(textureLoad(g_normals, q, 0).xy);
            let bx = select(1.0 - fr.x, fr.x, i == 1);
            let by = select(1.0 - fr.y, fr.y, j == 1);
            let dz = abs(dot(qp.xyz - pos.xyz, n)) / tol;
            let wn = pow(max(dot(n, qn), 0.0), 32.0);
            let w = max(bx * by, 1e-3) * wn / (1.0 + dz * dz);
            var v = textureLoad(low, l, 0).xyz;
            let qs = textureLoad(g_specular, q, 0);
            let qd = textureLoad(g_diffuse, q, 0).xyz;
            if lambertian && max3(qs.xyz) == 0.0 && qs.w <= 0.5 && min(min(qd.x, qd.y), qd.z) > 1e-3 {
                v *= diffuse.xyz / qd;
            }
            sum += w * v;
            wsum += w;
            if w > best {
                best = w;
                nearest = v;
            }
        }
    }
    if wsum > 1e-6 {
        return vec4<f32>(sum / wsum + own, 1.0);
    }
    return vec4<f32>(nearest + own, 1.0);
}
