// The light views of the ISPM bounce maps and `bidir`'s reflective shadow maps (one
// perspective view per spot light, six 90° cube faces per point light): the view uniform,
// the scene's vertices carried to the fragment, and the spot falloff.

struct BounceView {
    view_proj: mat4x4<f32>,
    light_position: vec3<f32>,
    // Texel area on the unit-distance image plane times the round-off correction.
    texel_area: f32,
    // The view's optical axis (cos θ is measured from it).
    forward: vec3<f32>,
    // 0 = point, 1 = spot.
    kind: u32,
    intensity: vec3<f32>,
    cos_inner: f32,
    spot_direction: vec3<f32>,
    cos_outer: f32,
    seed: u32,
    layer: u32,
}

@group(0) @binding(0) var<uniform> view: BounceView;

@vertex
fn vs_main(v: VertexIn, i: InstanceIn) -> VertexOut {
    return scene_vertex(v, i, view.view_proj);
}

fn falloff(cos_t: f32) -> f32 {
    return cone_falloff(cos_t, view.cos_inner, view.cos_outer);
}

// The light's power (W) through the texel seen in direction `wo` (from the surface towards
// the light): intensity (times the spot falloff) × the texel's solid angle, which on the
// unit-distance image plane is texel_area · cos³θ from the optical axis.
fn texel_flux(wo: vec3<f32>) -> vec3<f32> {
    let d = -wo;
    let c = max(dot(d, view.forward), 0.0);
    var intensity = view.intensity;
    if view.kind == 1u {
        intensity *= falloff(dot(d, view.spot_direction));
    }
    return intensity * view.texel_area * c * c * c;
}
