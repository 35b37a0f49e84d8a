// Structs shared by the passes; layouts match the `*Raw` types in crates/core/src/gpu/raw.rs.

struct Material {
    diffuse: vec3<f32>,
    roughness: f32,
    specular: vec3<f32>,
    fresnel: u32,
    transmission: vec3<f32>,
    ior: f32,
    // Radiance emitted by the front face (the side of the winding's normal); both faces
    // when bit 0 of `two_sided` is set (MATERIAL_EMITS_BACK); bit 1 (MATERIAL_ONE_SIDED):
    // the back face reflects and transmits nothing (`one_sided_back`).
    emission: vec3<f32>,
    two_sided: u32,
}

// Bits of `Material::two_sided` (gpu/raw.rs `MaterialRaw::two_sided`).
const MATERIAL_EMITS_BACK: u32 = 1u;
const MATERIAL_ONE_SIDED: u32 = 2u;

// Whether `wo` (pointing away from the surface, towards the viewer or the light) sees the
// back of a one-sided material `m`, the side away from `front` (`front_normal` in
// scene_vertex.wgsl: as Mitsuba, the interpolated vertex normal, else the winding's):
// `bsdf::Material::seen_from`, which makes it black there (`without_lobes`).
fn one_sided_back(m: Material, front: vec3<f32>, wo: vec3<f32>) -> bool {
    return (m.two_sided & MATERIAL_ONE_SIDED) != 0u && dot(wo, front) < 0.0;
}

// `bsdf::Material::back`: no lobe, the same emission.
fn without_lobes(m: Material) -> Material {
    var o = m;
    o.diffuse = vec3<f32>(0.0);
    o.specular = vec3<f32>(0.0);
    o.fresnel = 0u;
    o.transmission = vec3<f32>(0.0);
    return o;
}

// kind: 0 = point, 1 = spot, 2 = directional (`intensity` its irradiance, `direction` the
// way its light travels, `cos_inner` the cosine of its disc's half angle).
// Shadow layers `first_layer .. first_layer + layers` (6 for a
// point light's cube faces, +x -x +y -y +z -z; 1 for a spot light or a directional light's
// orthographic view).
struct Light {
    position: vec3<f32>,
    kind: u32,
    intensity: vec3<f32>,
    cos_inner: f32,
    direction: vec3<f32>,
    cos_outer: f32,
    first_layer: u32,
    layers: u32,
    // World size of one shadow texel, at unit distance from the light for perspective views.
    texel_scale: f32,
    // Directional: the world depth of its orthographic view (depth 0 to 1).
    depth_extent: f32,
}

// A camera or shadow view: world -> clip, and the eye position.
struct View {
    view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    weight: f32,
    // Clip -> world.
    inv_view_proj: mat4x4<f32>,
}

// Spot falloff: smoothstep in cos θ from the outer to the inner cone
// (`Light::intensity_towards`).
fn cone_falloff(cos_t: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if cos_t >= cos_inner {
        return 1.0;
    }
    if cos_t <= cos_outer {
        return 0.0;
    }
    let t = (cos_t - cos_outer) / (cos_inner - cos_outer);
    return t * t * (3.0 - 2.0 * t);
}

// Octahedral mapping of a unit vector to [-1, 1]^2 (and back).
fn oct_encode(n: vec3<f32>) -> vec2<f32> {
    let p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if n.z >= 0.0 {
        return p;
    }
    return (vec2<f32>(1.0) - abs(p.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
}

fn oct_decode(e: vec2<f32>) -> vec3<f32> {
    var n = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    let t = max(-n.z, 0.0);
    n.x += select(t, -t, n.x >= 0.0);
    n.y += select(t, -t, n.y >= 0.0);
    return normalize(n);
}
