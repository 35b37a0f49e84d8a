// ISPM photon volumes (section 5): each stored photon is an ellipsoid with radius r in its
// surface plane and z_ratio·r along its normal, splatted with one of two bounding shapes
// (Mara et al. 2013), both instanced, both shaded by the same `fs_main`:
// - `vs_icosahedron`: an icosahedron scaled to bound the ellipsoid. Only back faces are drawn
//   (front faces culled), so every pixel the volume covers gets exactly one fragment, also
//   with the eye inside the volume.
// - `vs_quad`: a screen-aligned rectangle (4-vertex triangle strip) bounding the projection
//   of the ellipsoid's oriented bounding box; the whole screen when the box reaches behind
//   the eye, nothing when it lies entirely behind it. Cheaper for small volumes: 2 triangles
//   instead of 20, at the price of more rejected fragments.
// There is no depth attachment: the fragment reads the eye G-buffer and adds the estimate
// term of common/photon_volume.wgsl (zero outside the exact ellipsoid or facing away from the
// photon's normal). The shape only decides which pixels are tested, so as long as it is
// conservative the image does not depend on it. Blending adds the photons up. At subsample k the
// target is 1/k the size and each texel shades the G-buffer pixel at the centre of its k×k
// block.

struct VolumeParams {
    view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    // Radius (m) of a photon of path density 1 (informational: radii come with the photons).
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
// The G-buffer's emission (w: the material's index + 1) and the materials' exact models
// (photon_volume.wgsl `view_sample`, raster/shaders/common/exact_models.wgsl).
@group(0) @binding(5) var g_emission: texture_2d<f32>;
@group(0) @binding(6) var<storage, read> model_materials: array<ModelMaterial>;

// The photon attributes (an instance-rate vertex buffer); location 0 is the icosahedron's
// corner.
struct PhotonIn {
    @location(1) position: vec3<f32>,
    @location(2) incident: vec3<f32>,
    @location(3) path_density: f32,
    @location(4) power: vec3<f32>,
    @location(5) normal: vec3<f32>,
    // Volume radius (m), set on the CPU.
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

// Right-handed basis (t, b, n) with t × b = n, Duff et al.
fn tangent_frame(n: vec3<f32>) -> mat3x3<f32> {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let bb = n.x * n.y * a;
    let t = vec3<f32>(1.0 + s * n.x * n.x * a, s * bb, -s * n.x);
    let b = vec3<f32>(bb, s + n.y * n.y * a, -n.y);
    return mat3x3<f32>(t, b, n);
}

// Maps a point of the unit cube [-1, 1]³ (or of a unit-sphere bounding shape) to world space
// on the photon's ellipsoid: axes t·r, b·r, n·z_ratio·r.
fn ellipsoid_axes(p: PhotonIn, r: f32) -> mat3x3<f32> {
    let f = tangent_frame(p.normal);
    return mat3x3<f32>(f[0] * r, f[1] * r, f[2] * (r * params.z_ratio));
}

// The CPU decides every radius (`VolumeRadius::of`: path density or differentials).
fn volume_radius(p: PhotonIn) -> f32 {
    return min(p.footprint, params.r_max);
}

fn volume_out(p: PhotonIn, clip: vec4<f32>, r: f32) -> VolumeOut {
    var o: VolumeOut;
    o.clip = clip;
    o.center = p.position;
    o.incident = p.incident;
    o.power = p.power;
    o.normal = p.normal;
    o.radius = r;
    return o;
}

@vertex
fn vs_icosahedron(@location(0) corner: vec3<f32>, p: PhotonIn) -> VolumeOut {
    let r = volume_radius(p);
    let world = p.position + ellipsoid_axes(p, r) * corner;
    var clip = params.view_proj * vec4<f32>(world, 1.0);
    // The back faces of a volume at the far end of the scene lie behind it and may pass the
    // far plane (fit to the scene's bounds): clamp their depth onto it instead of clipping
    // them away (measured: up to 2% of a pixel lost in the Cornell box's back corners at
    // kernel_scale 3). Only depths beyond the far plane change (z < w for the points behind
    // the eye), and no volume spans from the near plane to the far plane, so the near-plane
    // clipping of edges is unaffected.
    clip.z = min(clip.z, clip.w);
    return volume_out(p, clip, r);
}

// Smallest clip w of a box corner that still gets a finite rectangle; nearer corners (the box
// reaches the eye plane) make the quad cover the whole screen.
const QUAD_MIN_W: f32 = 1e-6;

@vertex
fn vs_quad(@builtin(vertex_index) vi: u32, p: PhotonIn) -> VolumeOut {
    let r = volume_radius(p);
    let axes = ellipsoid_axes(p, r);
    let center = params.view_proj * vec4<f32>(p.position, 1.0);
    // Clip-space images of the box's half-axes: corner = center ± ex ± ey ± ez (linear).
    let ex = params.view_proj * vec4<f32>(axes[0], 0.0);
    let ey = params.view_proj * vec4<f32>(axes[1], 0.0);
    let ez = params.view_proj * vec4<f32>(axes[2], 0.0);
    var lo = vec2<f32>(1.0);
    var hi = vec2<f32>(-1.0);
    var w_min = 3.4e38;
    var w_max = -3.4e38;
    for (var i = 0u; i < 8u; i++) {
        let sx = select(-1.0, 1.0, (i & 1u) != 0u);
        let sy = select(-1.0, 1.0, (i & 2u) != 0u);
        let sz = select(-1.0, 1.0, (i & 4u) != 0u);
        let c = center + sx * ex + sy * ey + sz * ez;
        w_min = min(w_min, c.w);
        w_max = max(w_max, c.w);
        let ndc = c.xy / max(c.w, QUAD_MIN_W);
        lo = min(lo, ndc);
        hi = max(hi, ndc);
    }
    // The projection of a convex box in front of the eye is the hull of its projected
    // corners. A box reaching behind the eye plane may cover any pixel (its projection wraps
    // through infinity): cover the whole screen. A box wholly behind it holds no visible
    // surface point (those have w ≥ near > 0): cover nothing.
    if w_min <= QUAD_MIN_W {
        lo = vec2<f32>(-1.0);
        hi = vec2<f32>(1.0);
    }
    if w_max <= 0.0 {
        hi = lo;
    }
    // Pixels outside the viewport are never drawn: clamping keeps the corners finite.
    lo = clamp(lo, vec2<f32>(-1.0), vec2<f32>(1.0));
    hi = clamp(hi, vec2<f32>(-1.0), vec2<f32>(1.0));
    // Triangle strip 0..4: (lo.x, lo.y), (hi.x, lo.y), (lo.x, hi.y), (hi.x, hi.y). Any depth
    // inside the clip volume will do (no depth attachment).
    let q = vec2<f32>(select(lo.x, hi.x, (vi & 1u) != 0u), select(lo.y, hi.y, (vi & 2u) != 0u));
    return volume_out(p, vec4<f32>(q, 0.5, 1.0), r);
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
    var p: VolumePhoton;
    p.center = in.center;
    p.incident = in.incident;
    p.power = in.power;
    p.normal = in.normal;
    p.radius = in.radius;
    // The cheap ellipsoid test first: most fragments of a bounding shape fail it.
    if volume_kernel(p, pos.xyz, params.z_ratio).y == 0.0 {
        discard;
    }
    let s = view_sample(g_position, g_normals, g_diffuse, g_specular, px, params.eye);
    return vec4<f32>(volume_term(p, s, params.z_ratio), 0.0);
}
