// The frame's final radiance: the direct light accumulated over the sub-pixel samples
// (radiance·weight in rgb, Σ weight in alpha), plus the light of mirrors and glass traced on
// the CPU and the indirect light of the photon estimate, both at pixel centres.

@group(0) @binding(0) var accum: texture_2d<f32>;
@group(0) @binding(1) var specular: texture_2d<f32>;
@group(0) @binding(2) var indirect: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let px = vec2<i32>(frag.xy);
    let a = textureLoad(accum, px, 0);
    var direct = vec3<f32>(0.0);
    if a.w > 0.0 {
        direct = a.xyz / a.w;
    }
    let c = direct + textureLoad(specular, px, 0).xyz + textureLoad(indirect, px, 0).xyz;
    return vec4<f32>(c, 1.0);
}
