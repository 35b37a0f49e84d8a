// Shadow-map lookups shared by the lighting passes. A point source (a point light or a VPL)
// has six cube-face layers (+x -x +y -y +z -z) from `first_layer`; a spot light one.

// The layer of a source with `layers` layers from `first_layer` that sees direction `d`
// (from the source): the cube face of the major axis when there are six.
fn shadow_layer_of(first_layer: u32, layers: u32, d: vec3<f32>) -> u32 {
    if layers == 1u {
        return first_layer;
    }
    let a = abs(d);
    var face = 0u;
    if a.x >= a.y && a.x >= a.z {
        face = select(1u, 0u, d.x >= 0.0);
    } else if a.y >= a.z {
        face = select(3u, 2u, d.y >= 0.0);
    } else {
        face = select(5u, 4u, d.z >= 0.0);
    }
    return first_layer + face;
}

// Percentage-closer filtering of `p` in `layer` of `maps` (world -> clip `m`): the mean of
// 3×3 bilinear comparison taps one texel apart, so the lit fraction varies smoothly across
// a shadow edge. The nine taps read a 4×4-texel window with per-axis weights
// (1 − f, 1, 1, f)/3 (f: the bilinear fraction); four comparison gathers read the same 16
// texels, weighted here: the same value from 4 texture reads instead of 9.
fn shadow_pcf(maps: texture_depth_2d_array, smp: sampler_comparison, m: mat4x4<f32>, layer: u32, p: vec3<f32>) -> f32 {
    let clip = m * vec4<f32>(p, 1.0);
    if clip.w <= 0.0 {
        return 0.0;
    }
    let ndc = clip.xyz / clip.w;
    let uv = ndc.xy * vec2<f32>(0.5, -0.5) + 0.5;
    let size = vec2<f32>(textureDimensions(maps));
    let st = uv * size - 0.5;
    let base = floor(st);
    let f = st - base;
    // A gather at texel coordinate c reads columns floor(c − 0.5) and the next, rows alike:
    // c = base reads base − 1 and base; c = base + 2 reads base + 1 and base + 2. Its
    // components are (first column, second row), (second, second), (second, first),
    // (first, first).
    let lo = textureGatherCompare(maps, smp, base / size, layer, ndc.z);
    let hx = textureGatherCompare(maps, smp, (base + vec2<f32>(2.0, 0.0)) / size, layer, ndc.z);
    let hy = textureGatherCompare(maps, smp, (base + vec2<f32>(0.0, 2.0)) / size, layer, ndc.z);
    let hi = textureGatherCompare(maps, smp, (base + 2.0) / size, layer, ndc.z);
    let g = 1.0 - f;
    let lit = gather_weighted(lo, vec2<f32>(g.x, 1.0), vec2<f32>(g.y, 1.0))
        + gather_weighted(hx, vec2<f32>(1.0, f.x), vec2<f32>(g.y, 1.0))
        + gather_weighted(hy, vec2<f32>(g.x, 1.0), vec2<f32>(1.0, f.y))
        + gather_weighted(hi, vec2<f32>(1.0, f.x), vec2<f32>(1.0, f.y));
    return lit / 9.0;
}

// A comparison gather `t` weighted by column weights `a` and row weights `b`.
fn gather_weighted(t: vec4<f32>, a: vec2<f32>, b: vec2<f32>) -> f32 {
    return t.w * a.x * b.x + t.z * a.y * b.x + t.x * a.x * b.y + t.y * a.y * b.y;
}

// One bilinear comparison tap (2×2 texels): for the many VPL and bundle-hit lookups of
// `bidir`, where the average over many lights already smooths the edges and nine taps
// would cost nine times the texture reads.
fn shadow_tap(maps: texture_depth_2d_array, smp: sampler_comparison, m: mat4x4<f32>, layer: u32, p: vec3<f32>) -> f32 {
    let clip = m * vec4<f32>(p, 1.0);
    if clip.w <= 0.0 {
        return 0.0;
    }
    let ndc = clip.xyz / clip.w;
    let uv = ndc.xy * vec2<f32>(0.5, -0.5) + 0.5;
    return textureSampleCompareLevel(maps, smp, uv, layer, ndc.z);
}
