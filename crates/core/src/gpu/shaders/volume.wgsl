// ISPM photon volumes (section 5): one instanced icosahedron per stored photon, scaled to
// bound an ellipsoid with radius r in the photon's surface plane and z_ratio·r along its
// normal. Only back faces are drawn (front faces culled), so every pixel the volume covers
// gets exactly one fragment, also with the eye inside the volume. The fragment reads the eye
// G-buffer, rejects surface points outside the ellipsoid or facing away from the photon's
// normal (photon::estimate::NORMAL_AGREEMENT), and adds the photon-map estimate term
// f(wo, wi)·Φ·κ with the 2D Epanechnikov kernel κ = 2/(πr²)(1 − d²/r²) over the disc.
// Blending adds the photons up. At subsample k the target is 1/k the size and each texel
// shades the G-buffer pixel at the centre of its k×k block.

struct VolumeParams {
    view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    // Radius (m) of a photon of path density 1.
    r_base: f32,
    // Largest radius (m).
    r_max: f32,
    // r_z / r_xy.
    z_ratio: f32,
    subsample: u32,
    _pad: f32,
}

@group(0) @binding(0) var<uniform> params: VolumeParams;
@group(0) @binding(1) var g_position: texture_2d<f32>;
@group(0) @binding(2) var g_normals: texture_2d<f32>;
@group(0) @binding(3) var g_diffuse: texture_2d<f32>;
@group(0) @binding(4) var g_specular: texture_2d<f32>;

struct PhotonIn {
    @location(0) corner: vec3<f32>,
    @location(1) position: vec3<f32>,
    @location(2) incident: vec3<f32>,
    @location(3) path_density: f32,
    @location(4) power: vec3<f32>,
    @location(5) normal: vec3<f32>,
    // Footprint radius from photon differentials (m); 0 = use the path density.
    @location(6) footprint: f32,
}

struct VolumeOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) center: vec3<f32>,
    @location(1) @interpolate(flat) incident: vec3<f32>,
    @location(2) @interpolate(flat) power: vec3<f32>,
    @location(3) @interpolate(flat) normal: vec3<f32>,
    @location(4) @interpolate(flat) radius: f32,
}

// Radius from path density (section 5.1): dense (caustic) paths get the base radius, a
// diffuse bounce (ρ ≈ 1e-3) widens it about 4×, and no photon gets more than 4× (wider
// discs lose energy off the edges of finite surfaces: measured 6% too little indirect
// light in the Cornell box with a 64× cap).
fn photon_radius(density: f32) -> f32 {
    let g = clamp(pow(max(density, 1e-30), -0.2), 1.0, 4.0);
    return min(params.r_base * g, params.r_max);
}

@vertex
fn vs_main(p: PhotonIn) -> VolumeOut {
    let n = p.normal;
    // Right-handed basis (t × b = n), Duff et al.
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let bb = n.x * n.y * a;
    let t = vec3<f32>(1.0 + s * n.x * n.x * a, s * bb, -s * n.x);
    let b = vec3<f32>(bb, s + n.y * n.y * a, -n.y);
    let r = select(photon_radius(p.path_density), min(p.footprint, params.r_max), p.footprint > 0.0);
    let world = p.position + t * (p.corner.x * r) + b * (p.corner.y * r) + n * (p.corner.z * r * params.z_ratio);
    var o: VolumeOut;
    o.clip = params.view_proj * vec4<f32>(world, 1.0);
    o.center = p.position;
    o.incident = p.incident;
    o.power = p.power;
    o.normal = n;
    o.radius = r;
    return o;
}

@fragment
fn fs_main(in: VolumeOut) -> @location(0) vec4<f32> {
    let k = params.subsample;
    let dims = vec2<i32>(textureDimensions(g_position));
    let px = min(vec2<i32>(vec2<u32>(in.clip.xy) * k + k / 2u), dims - 1);
    let pos = textureLoad(g_position, px, 0);
    if pos.w == 0.0 {
        discard;
    }
    let d = pos.xyz - in.center;
    let dz = dot(d, in.normal);
    let r = in.radius;
    if abs(dz) > r * params.z_ratio {
        discard;
    }
    let d2 = max(dot(d, d) - dz * dz, 0.0);
    let r2 = r * r;
    if d2 >= r2 {
        discard;
    }
    let nn = textureLoad(g_normals, px, 0);
    let ns = oct_decode(nn.xy);
    if dot(ns, in.normal) <= 0.5 {
        discard;
    }
    let dm = textureLoad(g_diffuse, px, 0);
    let sp = textureLoad(g_specular, px, 0);
    var m: Material;
    m.diffuse = dm.xyz;
    m.roughness = dm.w;
    m.specular = sp.xyz;
    m.fresnel = u32(sp.w > 0.5);
    let wo = normalize(params.eye - pos.xyz);
    let kernel = 2.0 / (PI * r2) * (1.0 - d2 / r2);
    let f = bsdf_eval(m, ns, wo, in.incident);
    return vec4<f32>(f * in.power * kernel, 0.0);
}
