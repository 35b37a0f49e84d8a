// The light of emitters smaller than a pixel (raster/subpixel.rs, raster/splat.rs): one
// point per splat at its pixel adds radiance × covered share into the direct light's
// accumulation (additive blending, alpha 0: the pixel's weight stays), unless the centre
// G-buffer's surface there is nearer than the emitter (the depth test).

struct SplatParams {
    // The eye (xyz) and 0.
    eye: vec4<f32>,
    // Image width and height (pixels).
    size: vec2<f32>,
    _pad: vec2<f32>,
}

@group(0) @binding(0) var<uniform> splat: SplatParams;
@group(1) @binding(0) var g_position: texture_2d<f32>;

struct SplatOut {
    @builtin(position) clip: vec4<f32>,
    // Radiance × coverage (rgb) and the emitter's hiding distance (w).
    @location(0) @interpolate(flat) light: vec4<f32>,
}

// `pixel`: column, row, hiding distance; `light`: radiance × coverage (`subpixel::Splat`).
@vertex
fn splat_vs(@location(0) pixel: vec4<f32>, @location(1) light: vec4<f32>) -> SplatOut {
    let xy = pixel.xy + 0.5;
    var out: SplatOut;
    // A point at the pixel's centre covers that pixel alone.
    out.clip = vec4<f32>(xy.x / splat.size.x * 2.0 - 1.0, 1.0 - xy.y / splat.size.y * 2.0, 0.5, 1.0);
    out.light = vec4<f32>(light.xyz, pixel.z);
    return out;
}

@fragment
fn splat_fs(in: SplatOut) -> @location(0) vec4<f32> {
    let g = textureLoad(g_position, vec2<i32>(in.clip.xy), 0);
    if g.w > 0.0 && distance(g.xyz, splat.eye.xyz) < in.light.w {
        discard;
    }
    return vec4<f32>(in.light.xyz, 0.0);
}
