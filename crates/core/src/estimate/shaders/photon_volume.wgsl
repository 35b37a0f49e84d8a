// The photon-volume estimate term of ISPM (section 5), shared by every estimator that splats
// the same photons (the raster volumes in volume.wgsl, the compute estimators in tiled.wgsl)
// so that they give the same image: a photon is an ellipsoid with radius r in its surface
// plane and z_ratio·r along its normal; a view sample inside it whose shading normal agrees
// with the photon's (photon::estimate::NORMAL_AGREEMENT) receives f(wo, wi)·Φ·κ with the 2D
// Epanechnikov kernel κ = 2/(πr²)(1 − d²/r²), d the distance in the photon's surface plane.

// The photon's data as the estimators read it.
struct VolumePhoton {
    center: vec3<f32>,
    incident: vec3<f32>,
    power: vec3<f32>,
    normal: vec3<f32>,
    radius: f32,
}

// A view sample of the eye G-buffer: position, shading normal, material, direction to the eye.
struct ViewSample {
    position: vec3<f32>,
    normal: vec3<f32>,
    material: Material,
    wo: vec3<f32>,
}

// Kernel weight κ of photon `p` at `x`, and whether `x` lies inside its ellipsoid.
fn volume_kernel(p: VolumePhoton, x: vec3<f32>, z_ratio: f32) -> vec2<f32> {
    let d = x - p.center;
    let dz = dot(d, p.normal);
    let r = p.radius;
    let d2 = max(dot(d, d) - dz * dz, 0.0);
    let r2 = r * r;
    // Inside the ellipsoid (not merely its bounding cylinder), which every bounding shape
    // contains: the result does not depend on the shape drawn.
    let rz = r * z_ratio;
    if d2 / r2 + dz * dz / (rz * rz) >= 1.0 {
        return vec2<f32>(0.0, 0.0);
    }
    return vec2<f32>(2.0 / (PI * r2) * (1.0 - d2 / r2), 1.0);
}

// Whether the sample's normal `ns` faces the photon's surface (rejects the far side of thin
// walls and corners).
fn volume_normal_agrees(p: VolumePhoton, ns: vec3<f32>) -> bool {
    return dot(ns, p.normal) > 0.5;
}

// The estimate term of photon `p` at view sample `s` for its kernel weight `kernel`.
fn volume_shade(p: VolumePhoton, s: ViewSample, kernel: f32) -> vec3<f32> {
    let f = exact_eval(s.material, s.normal, s.wo, p.incident);
    return f * p.power * kernel;
}

// The estimate term of photon `p` at view sample `s` (zero outside its volume).
fn volume_term(p: VolumePhoton, s: ViewSample, z_ratio: f32) -> vec3<f32> {
    let k = volume_kernel(p, s.position, z_ratio);
    if k.y == 0.0 || !volume_normal_agrees(p, s.normal) {
        return vec3<f32>(0.0);
    }
    return volume_shade(p, s, k.x);
}

// The view sample of G-buffer pixel `px`; `valid` is false where the pixel saw no surface.
fn view_sample(
    g_position: texture_2d<f32>,
    g_normals: texture_2d<f32>,
    g_diffuse: texture_2d<f32>,
    g_specular: texture_2d<f32>,
    px: vec2<i32>,
    eye: vec3<f32>,
) -> ViewSample {
    var s: ViewSample;
    let pos = textureLoad(g_position, px, 0);
    s.position = pos.xyz;
    s.normal = oct_decode(textureLoad(g_normals, px, 0).xy);
    let dm = textureLoad(g_diffuse, px, 0);
    let sp = textureLoad(g_specular, px, 0);
    s.material.diffuse = dm.xyz;
    s.material.roughness = dm.w;
    s.material.specular = sp.xyz;
    s.material.fresnel = u32(sp.w > 0.5);
    s.wo = normalize(eye - pos.xyz);
    // Mitsuba's exact model of the sample's material, if it has one (its index + 1 in the
    // G-buffer's emission.w; raster/shaders/common/exact_models.wgsl): `exact_eval`.
    exact_load(textureLoad(g_emission, px, 0).w, dm.xyz);
    return s;
}
