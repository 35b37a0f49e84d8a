// Full-screen deferred direct lighting over a G-buffer (common/direct_shade.wgsl).
// `fs_main` adds one sub-pixel sample, weighted by its share of the pixel, into the
// accumulation target (additive blend; full supersampling); `fs_centre` writes the
// pixel's light box-filtered over its footprint on the centre sample's tangent plane
// (edge-adaptive supersampling: direct_edges.wgsl then overwrites the pixels on geometric
// edges with the mean of their sub-pixel samples).

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    var g = load_sample(vec2<i32>(frag.xy));
    if BACKGROUND && g.position.w == 0.0 {
        g.ray = view_ray(frag.xy);
    }
    sky_quad_prepare(frag.xy, g);
    let sum = shade(g);
    return vec4<f32>(sum * view.weight, view.weight);
}

@fragment
fn fs_centre(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    var g = load_sample(vec2<i32>(frag.xy));
    if BACKGROUND && g.position.w == 0.0 {
        g.ray = view_ray(frag.xy);
    }
    // The pixel's footprint on its surface: across a discontinuity the difference is
    // meaningless, but such pixels are edge pixels, overwritten by direct_edges.wgsl.
    var fp: Footprint;
    fp.dx = dpdxFine(g.position.xyz);
    fp.dy = dpdyFine(g.position.xyz);
    let ns = oct_decode(g.normals.xy);
    fp.dndx = dpdxFine(ns);
    fp.dndy = dpdyFine(ns);
    fp.taps = penumbra_taps.x;
    sky_quad_prepare(frag.xy, g);
    return vec4<f32>(shade_pixel(g, fp), 1.0);
}
