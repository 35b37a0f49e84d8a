// Structs shared by the passes; layouts match the `*Raw` types in crates/core/src/gpu/raw.rs.

struct Material {
    diffuse: vec3<f32>,
    roughness: f32,
    specular: vec3<f32>,
    fresnel: u32,
    transmission: vec3<f32>,
    ior: f32,
}

// kind: 0 = point, 1 = spot, 2 = directional (not shaded by the raster passes yet).
// Shadow layers `first_layer .. first_layer + layers` (6 for a
// point light's cube faces, +x -x +y -y +z -z; 1 for a spot light).
struct Light {
    position: vec3<f32>,
    kind: u32,
    intensity: vec3<f32>,
    cos_inner: f32,
    direction: vec3<f32>,
    cos_outer: f32,
    first_layer: u32,
    layers: u32,
    // World size of one shadow texel at unit distance from the light.
    texel_scale: f32,
    _pad: f32,
}

// A camera or shadow view: world -> clip, and the eye position.
struct View {
    view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    weight: f32,
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
