// ISPM bounce map (section 4.2): rasterizes the scene from a light's view (one perspective
// view per spot light, six exact 90° cube faces per point light). Every covered texel is one
// photon leaving the light through that texel: its power is I(ω)·dω with the texel's solid
// angle dω = A_texel·cos³θ on a unit-distance image plane (A_texel already carries the
// per-light round-off correction, so all texels of a light sum to its power). The hit it
// lands on is direct light (not stored); the first scatter is sampled on the CPU from the
// position, normals and material written here.

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
}

@group(0) @binding(0) var<uniform> view: BounceView;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) geometric_normal: vec3<f32>,
    @location(3) material: u32,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) geometric_normal: vec3<f32>,
    @location(3) @interpolate(flat) material: u32,
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var o: VertexOut;
    o.clip = view.view_proj * vec4<f32>(v.position, 1.0);
    o.world = v.position;
    o.normal = v.normal;
    o.geometric_normal = v.geometric_normal;
    o.material = v.material;
    return o;
}

struct BounceOut {
    // Hit position xyz, material index (exact as f32 below 2^24).
    @location(0) position: vec4<f32>,
    // Octahedral shading normal (xy) and geometric normal (zw), both facing the light.
    @location(1) normals: vec4<f32>,
    // Photon power (W) arriving at the hit; w = 1 marks a covered texel.
    @location(2) power: vec4<f32>,
}

fn falloff(cos_t: f32) -> f32 {
    if cos_t >= view.cos_inner {
        return 1.0;
    }
    if cos_t <= view.cos_outer {
        return 0.0;
    }
    let t = (cos_t - view.cos_outer) / (view.cos_inner - view.cos_outer);
    return t * t * (3.0 - 2.0 * t);
}

@fragment
fn fs_main(in: VertexOut) -> BounceOut {
    let to_light = view.light_position - in.world;
    let wo = normalize(to_light);
    // Normals as in the eye G-buffer, oriented towards the light.
    var ng = in.geometric_normal;
    var ns = in.normal;
    let len = length(ns);
    if !(len > 0.0) {
        ns = ng;
    } else {
        ns = ns / len;
        if dot(ns, ng) < 0.0 {
            ns = -ns;
        }
    }
    if dot(wo, ns) * dot(wo, ng) <= 0.0 {
        ns = ng;
    }
    if dot(wo, ng) < 0.0 {
        ng = -ng;
        ns = -ns;
    }
    let d = -wo;
    let c = max(dot(d, view.forward), 0.0);
    var intensity = view.intensity;
    if view.kind == 1u {
        intensity *= falloff(dot(d, view.spot_direction));
    }
    var o: BounceOut;
    o.position = vec4<f32>(in.world, f32(in.material));
    o.normals = vec4<f32>(oct_encode(ns), oct_encode(ng));
    o.power = vec4<f32>(intensity * view.texel_area * c * c * c, 1.0);
    return o;
}
