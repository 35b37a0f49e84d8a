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

// Percentage-closer filtering of `p` in `layer` of `maps` (world -> clip `m`): 3×3 bilinear
// comparison taps one texel apart (a 4×4-texel tent), so the lit fraction varies smoothly
// across a shadow edge.
fn shadow_pcf(maps: texture_depth_2d_array, smp: sampler_comparison, m: mat4x4<f32>, layer: u32, p: vec3<f32>) -> f32 {
    let clip = m * vec4<f32>(p, 1.0);
    if clip.w <= 0.0 {
        return 0.0;
    }
    let ndc = clip.xyz / clip.w;
    let uv = ndc.xy * vec2<f32>(0.5, -0.5) + 0.5;
    let texel = 1.0 / vec2<f32>(textureDimensions(maps));
    var lit = 0.0;
    for (var y = -1; y <= 1; y++) {
        for (var x = -1; x <= 1; x++) {
            let o = vec2<f32>(f32(x), f32(y)) * texel;
            lit += textureSampleCompareLevel(maps, smp, uv + o, layer, ndc.z);
        }
    }
    return lit / 9.0;
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
