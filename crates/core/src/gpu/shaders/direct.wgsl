// Deferred direct lighting: for every G-buffer sample, the sum over lights of
// f(wo, wi)·|cos θi|·I(−wi)/d² times the PCF shadow-map visibility, weighted by the
// sample's share of the pixel and added (blend) into the accumulation target.

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var<storage, read> shadow_views: array<mat4x4<f32>>;
@group(0) @binding(3) var shadow_maps: texture_depth_2d_array;
@group(0) @binding(4) var shadow_sampler: sampler_comparison;
@group(1) @binding(0) var g_position: texture_2d<f32>;
@group(1) @binding(1) var g_normals: texture_2d<f32>;
@group(1) @binding(2) var g_diffuse: texture_2d<f32>;
@group(1) @binding(3) var g_specular: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle covering the screen.
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

// Spot falloff: smoothstep in cos θ from the outer to the inner cone (Light::intensity_towards).
fn spot_falloff(l: Light, cos_t: f32) -> f32 {
    if cos_t >= l.cos_inner {
        return 1.0;
    }
    if cos_t <= l.cos_outer {
        return 0.0;
    }
    let t = (cos_t - l.cos_outer) / (l.cos_inner - l.cos_outer);
    return t * t * (3.0 - 2.0 * t);
}

// Shadow-map visibility of `p` from light `l` (common/shadow_lookup.wgsl).
fn visibility(l: Light, p: vec3<f32>) -> f32 {
    let layer = shadow_layer_of(l.first_layer, l.layers, p - l.position);
    return shadow_pcf(shadow_maps, shadow_sampler, shadow_views[layer], layer, p);
}

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let px = vec2<i32>(frag.xy);
    let pos = textureLoad(g_position, px, 0);
    if pos.w == 0.0 {
        return vec4<f32>(0.0, 0.0, 0.0, view.weight);
    }
    let p = pos.xyz;
    let nn = textureLoad(g_normals, px, 0);
    let ns = oct_decode(nn.xy);
    let ng = oct_decode(nn.zw);
    let d = textureLoad(g_diffuse, px, 0);
    let s = textureLoad(g_specular, px, 0);
    var m: Material;
    m.diffuse = d.xyz;
    m.roughness = d.w;
    m.specular = s.xyz;
    m.fresnel = u32(s.w > 0.5);
    let wo = normalize(view.eye - p);
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < arrayLength(&lights); i++) {
        let l = lights[i];
        let to_light = l.position - p;
        let dist2 = dot(to_light, to_light);
        let dist = sqrt(dist2);
        let wi = to_light / dist;
        // Reflection only: the light must be on the viewer's side of the geometry.
        if dot(wi, ng) <= 0.0 {
            continue;
        }
        var li = l.intensity / dist2;
        if l.kind == 1u {
            li *= spot_falloff(l, dot(-wi, l.direction));
        }
        let f = bsdf_eval(m, ns, wo, wi);
        if max3(f * li) <= 0.0 {
            continue;
        }
        // Normal offset of about one shadow texel against acne on surfaces at grazing light.
        let offset = ng * (l.texel_scale * dist * (1.0 - dot(wi, ng)) + 1e-4 * dist);
        sum += f * abs(dot(ns, wi)) * li * visibility(l, p + offset);
    }
    return vec4<f32>(sum * view.weight, view.weight);
}
