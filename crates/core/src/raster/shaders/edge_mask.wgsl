// The edge mask of the sub-pixel G-buffer passes (`raster/edges.rs`, `EdgePass::record_mask`):
// after the depth buffer is cleared to 0 (no fragment passes a `less` test there), one point
// per listed edge pixel writes depth 1 (`gbuffer::CLEAR_DEPTH`, the G-buffer pass's start)
// at that pixel, so the next G-buffer pass runs its fragment stage and writes its targets
// only there.

struct MaskParams {
    // Image width and height (pixels).
    size: vec2<u32>,
    _pad: vec2<u32>,
}

@group(0) @binding(0) var<uniform> mask: MaskParams;

// `pixel`: a listed pixel's index (y·width + x), read from the edge list as a vertex buffer.
@vertex
fn mask_vs(@location(0) pixel: u32) -> @builtin(position) vec4<f32> {
    let size = vec2<f32>(mask.size);
    let xy = vec2<f32>(f32(pixel % mask.size.x), f32(pixel / mask.size.x)) + 0.5;
    // A point at the pixel's centre covers that pixel alone.
    return vec4<f32>(xy.x / size.x * 2.0 - 1.0, 1.0 - xy.y / size.y * 2.0, 0.5, 1.0);
}

@fragment
fn mask_fs() -> @builtin(frag_depth) f32 {
    return 1.0;
}
