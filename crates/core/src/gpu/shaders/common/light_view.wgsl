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

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) geometric_normal: vec3<f32>,
    @location(3) material: u32,
    @location(4) uv: vec2<f32>,
    @location(5) tangent: vec4<f32>,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) geometric_normal: vec3<f32>,
    @location(3) @interpolate(flat) material: u32,
    @location(4) uv: vec2<f32>,
    @location(5) @interpolate(flat) tangent: vec4<f32>,
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var o: VertexOut;
    o.clip = view.view_proj * vec4<f32>(v.position, 1.0);
    o.world = v.position;
    o.normal = v.normal;
    o.geometric_normal = v.geometric_normal;
    o.material = v.material;
    o.uv = v.uv;
    o.tangent = v.tangent;
    return o;
}

fn falloff(cos_t: f32) -> f32 {
    return cone_falloff(cos_t, view.cos_inner, view.cos_outer);
}
