// Shadow-map lookups shared by the lighting passes. The including file declares
// `shadow_views` (world -> clip per layer), `shadow_maps` (a depth 2D array) and
// `shadow_sampler` (a comparison sampler). A point source (a point light or a VPL) has six
// cube-face layers (+x -x +y -y +z -z) from `first_layer`; a spot light one.

// The shadow layer of a source at `origin` with `layers` layers that sees `p`: the cube face
// of the major axis of p − origin when there are six.
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

// Percentage-closer filtering: 3×3 bilinear comparison taps one texel apart (a 4×4-texel
// tent), so the lit fraction varies smoothly across a shadow edge.
fn shadow_visibility(first_layer: u32, layers: u32, origin: vec3<f32>, p: vec3<f32>) -> f32 {
    let layer = shadow_layer_of(first_layer, layers, p - origin);
    let clip = shadow_views[layer] * vec4<f32>(p, 1.0);
    if clip.w <= 0.0 {
        return 0.0;
    }
    let ndc = clip.xyz / clip.w;
    let uv = ndc.xy * vec2<f32>(0.5, -0.5) + 0.5;
    let texel = 1.0 / vec2<f32>(textureDimensions(shadow_maps));
    var lit = 0.0;
    for (var y = -1; y <= 1; y++) {
        for (var x = -1; x <= 1; x++) {
            let o = vec2<f32>(f32(x), f32(y)) * texel;
            lit += textureSampleCompareLevel(shadow_maps, shadow_sampler, uv + o, layer, ndc.z);
        }
    }
    return lit / 9.0;
}
