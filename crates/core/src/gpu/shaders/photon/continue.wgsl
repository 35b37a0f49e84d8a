// The photon continuation pass (`gpu::photon::trace`): each thread follows one photon ray
// (the bounce maps' first-scatter rays) through the scene's BVH as
// `photon::trace::follow` does: at every hit on a surface with a non-delta lobe it stores
// a photon record (the CPU's `Photon` layout, the path's index in the pad word so the CPU
// can restore the CPU trace's order), then scatters (`photon_scatter`) until absorbed,
// escaped or at the bounce limit. Random numbers: a PCG stream per path (not the CPU's
// generator: the two traces agree in distribution, not photon by photon). No photon
// differentials: `footprint_radius` stays 0. After `types.wgsl`, `bsdf.wgsl`,
// `scatter.wgsl` and `bvh/bvh.wgsl` (group 1).

struct PhotonRay {
    origin: vec3<f32>,
    bounce: u32,
    direction: vec3<f32>,
    path_density: f32,
    power: vec3<f32>,
    pad: u32,
}

struct PhotonRecord {
    position: vec3<f32>,
    bounce: u32,
    incident: vec3<f32>,
    path_density: f32,
    power: vec3<f32>,
    path: u32,
    normal: vec3<f32>,
    footprint_radius: f32,
}

// A flat scene triangle in world space: corners (w of p0: the material index's bits) and
// vertex normals.
struct PhotonTri {
    p0: vec4<f32>,
    p1: vec4<f32>,
    p2: vec4<f32>,
    n0: vec4<f32>,
    n1: vec4<f32>,
    n2: vec4<f32>,
}

struct TraceParams {
    max_bounces: u32,
    store_direct: u32,
    seed: u32,
    capacity: u32,
}

// Counters: photons stored (also past `capacity`: the size to retry with), paths absorbed,
// escaped, truncated, traversal-stack overflows.
const COUNT_STORED: u32 = 0u;
const COUNT_ABSORBED: u32 = 1u;
const COUNT_ESCAPED: u32 = 2u;
const COUNT_TRUNCATED: u32 = 3u;
const COUNT_OVERFLOW: u32 = 4u;

@group(0) @binding(0) var<storage, read> trace_rays: array<PhotonRay>;
@group(0) @binding(1) var<storage, read> trace_tris: array<PhotonTri>;
@group(0) @binding(2) var<storage, read> trace_materials: array<Material>;
@group(0) @binding(3) var<uniform> trace_params: TraceParams;
@group(0) @binding(4) var<storage, read_write> trace_records: array<PhotonRecord>;
@group(0) @binding(5) var<storage, read_write> trace_counts: array<atomic<u32>, 8>;

var<private> rng_state: u32;

fn pcg_hash(x: u32) -> u32 {
    let s = x * 747796405u + 2891336453u;
    let w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return (w >> 22u) ^ w;
}

fn rng_next() -> f32 {
    rng_state = rng_state * 747796405u + 2891336453u;
    let w = ((rng_state >> ((rng_state >> 28u) + 4u)) ^ rng_state) * 277803737u;
    return f32(((w >> 22u) ^ w) >> 8u) * (1.0 / 16777216.0);
}

// `sampling::Frame::new`: an orthonormal basis around unit `n` (Duff et al.).
struct ShadingFrame {
    t: vec3<f32>,
    b: vec3<f32>,
    n: vec3<f32>,
}

fn shading_frame(n: vec3<f32>) -> ShadingFrame {
    // copysign(1, n.z): -1 for -0 too.
    let s = select(1.0, -1.0, (bitcast<u32>(n.z) & 0x80000000u) != 0u);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    return ShadingFrame(
        vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x),
        vec3<f32>(b, s + n.y * n.y * a, -n.y),
        n,
    );
}

fn to_local(f: ShadingFrame, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(v, f.t), dot(v, f.b), dot(v, f.n));
}

fn to_world(f: ShadingFrame, v: vec3<f32>) -> vec3<f32> {
    return f.t * v.x + f.b * v.y + f.n * v.z;
}

// `trace::Interaction` without textures: the hit point, geometric normal, shading normal
// (interpolated, on the winding's side, the geometric one where they disagree about the
// side `d` came from), material, and the front a one-sided material faces (`front_normal`:
// the interpolated vertex normal before any flip, else the winding's).
struct Surface {
    position: vec3<f32>,
    material: u32,
    ng: vec3<f32>,
    ns: vec3<f32>,
    front: vec3<f32>,
}

fn safe_normalize(v: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    return select(vec3<f32>(0.0), v / l, l > 0.0 && l < 3.0e38);
}

fn surface_at(h: BvhHit, d: vec3<f32>) -> Surface {
    let tri = trace_tris[h.triangle];
    let w = 1.0 - h.u - h.v;
    let ng = safe_normalize(cross(tri.p1.xyz - tri.p0.xyz, tri.p2.xyz - tri.p0.xyz));
    var ns = safe_normalize(tri.n0.xyz * w + tri.n1.xyz * h.u + tri.n2.xyz * h.v);
    let front = select(ns, ng, all(ns == vec3<f32>(0.0)));
    if all(ns == vec3<f32>(0.0)) {
        ns = ng;
    } else if dot(ns, ng) < 0.0 {
        ns = -ns;
    }
    if dot(d, ns) * dot(d, ng) <= 0.0 {
        ns = ng;
    }
    let p = tri.p0.xyz * w + tri.p1.xyz * h.u + tri.p2.xyz * h.v;
    return Surface(p, bitcast<u32>(tri.p0.w), ng, ns, front);
}

// Rust's signum: +1 for +0.
fn signum(x: f32) -> f32 {
    return select(1.0, -1.0, x < 0.0);
}

// `Interaction::spawn`.
fn spawn(s: Surface, dir: vec3<f32>) -> vec3<f32> {
    let a = abs(s.position);
    let eps = 1e-4 * (1.0 + max(a.x, max(a.y, a.z)));
    return s.position + s.ng * eps * signum(dot(dir, s.ng));
}

fn store_photon(r: PhotonRecord) {
    let i = atomicAdd(&trace_counts[COUNT_STORED], 1u);
    if i < trace_params.capacity {
        trace_records[i] = r;
    }
}

@compute @workgroup_size(64)
fn continue_paths(@builtin(global_invocation_id) id: vec3<u32>) {
    let path = id.x;
    if path >= arrayLength(&trace_rays) {
        return;
    }
    rng_state = pcg_hash(pcg_hash(path) ^ trace_params.seed);
    let ray = trace_rays[path];
    var o = ray.origin;
    var d = ray.direction;
    var power = ray.power;
    var density = ray.path_density;
    var bounce = ray.bounce;
    if !(max3(power) > 0.0) || any(power != power) {
        atomicAdd(&trace_counts[COUNT_ABSORBED], 1u);
        return;
    }
    loop {
        let h = bvh_closest(o, d, BVH_INF);
        if bvh_overflowed {
            atomicAdd(&trace_counts[COUNT_OVERFLOW], 1u);
            bvh_overflowed = false;
        }
        if h.triangle == BVH_NONE {
            atomicAdd(&trace_counts[COUNT_ESCAPED], 1u);
            return;
        }
        let s = surface_at(h, d);
        var m = trace_materials[s.material];
        let wo = -d;
        // A one-sided material seen from behind stores and scatters nothing (Interaction::new).
        if one_sided_back(m, s.front, wo) {
            m = without_lobes(m);
        }
        if stores_photons(m) && (bounce > 0u || trace_params.store_direct != 0u) {
            let normal = s.ns * signum(dot(s.ng, wo));
            store_photon(PhotonRecord(s.position, bounce, wo, density, power, path, normal, 0.0));
        }
        if bounce >= trace_params.max_bounces {
            atomicAdd(&trace_counts[COUNT_TRUNCATED], 1u);
            return;
        }
        let f = shading_frame(s.ns);
        let u = vec4<f32>(rng_next(), rng_next(), rng_next(), rng_next());
        let sc = photon_scatter(m, to_local(f, wo), to_local(f, s.ng), power, u);
        if sc.lobe == LOBE_NONE {
            atomicAdd(&trace_counts[COUNT_ABSORBED], 1u);
            return;
        }
        let wi = to_world(f, sc.wi);
        power = sc.power;
        density *= path_density_factor(m, sc.lobe);
        bounce += 1u;
        o = spawn(s, wi);
        d = wi;
    }
}
