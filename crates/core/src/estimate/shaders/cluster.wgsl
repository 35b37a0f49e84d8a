// The view-sample cluster hierarchy of Moreau et al. 2016 (section 4), appended to
// tiled.wgsl (its bindings, photon loads, tile ranges and scan):
// 1. `cluster_leaves`: each leaf cluster (the view samples of a screen tile, split by depth
//    slice and by normal: up to CLUSTERS_PER_TILE clusters a tile) gets its bounding box, normal cone
//    and whether it is *simple* (every sample purely diffuse and facing the eye, so that a
//    photon's BSDF term is ρ/π for all of them);
// 2. `cluster_parents` (once per upper level): boxes, cones and flags of 4×4 children;
// 3. `cluster_{top,mid,low}_count` / `scan` / `cluster_{top,mid,low}_fill`: each photon
//    walks the hierarchy top-down, one level per sub-pass over job lists (below),
//    rejecting nodes by bounds and normal cone; a node wholly inside its ellipsoid whose
//    cone passes the normal and hemisphere tests, and that is simple, *trivially accepts*
//    the photon (its accept list; no descent); a leaf it only overlaps gets it in its test
//    list;
// 4. `cluster_accumulate`: each node sums its accepted photons' kernels exactly, as a
//    quadratic in the sample position (below);
// 5. `cluster_shade`: each view sample evaluates the quadratics of its leaf and the leaf's
//    ancestors and sums the photon-volume term of its leaf's test list.
//
// Exact trivial acceptance. For a simple node, Σ f·Φᵢ·κᵢ(x) = ρ(x)/π · Σ Φᵢ κᵢ(x), and
// κᵢ(x) = aᵢ − bᵢ dᵢ²(x) with aᵢ = 2/(πrᵢ²), bᵢ = aᵢ/rᵢ², dᵢ² = (y−uᵢ)ᵀMᵢ(y−uᵢ), y = x − o,
// uᵢ = cᵢ − o (o the node's centre, so that no term is large), Mᵢ = I − nᵢnᵢᵀ. Hence per
// channel Σ Φᵢκᵢ = A + B·y − yᵀCy with A = Σ Φᵢ(aᵢ − bᵢ uᵢᵀMᵢuᵢ), B = Σ 2Φᵢbᵢ Mᵢuᵢ,
// C = Σ Φᵢbᵢ Mᵢ: the same estimate as the per-photon sum, up to float rounding.

const CLUSTERS_PER_TILE: u32 = 8u;
// Depth ranks of a tile's clusters (each split in two by normal).
const DEPTH_RANKS: u32 = 4u;
// cos 45°: a sample whose normal is farther than this from its tile's reference normal
// goes to the second cluster of its depth rank.
const COS_NORMAL_SPLIT: f32 = 0.70710678;
// Child nodes per side of a parent.
const FANOUT: u32 = 4u;
// Angles (radians) of the cone tests: 60° is the normal agreement (cos = 0.5), 90° the
// hemisphere; decisions keep this margin from them so rounding never flips one.
const NORMAL_LIMIT: f32 = 1.0471975512;
const HEMISPHERE_LIMIT: f32 = 1.5707963268;
const ANGLE_MARGIN: f32 = 1e-3;
// The box must lie this far inside the ellipsoid (relative) to be accepted whole.
const INSIDE_MARGIN: f32 = 1e-4;
const NO_CONE: f32 = 4.0;
// cos and sin of the limits with their margins (classify).
const COS_NORMAL_OUT: f32 = 0.49913372; // cos(60° + 0.001)
const SIN_NORMAL_OUT: f32 = 0.86652497;
const COS_NORMAL_IN: f32 = 0.50086578; // cos(60° - 0.001)
const SIN_NORMAL_IN: f32 = 0.86552497;
const COS_HEMI_IN: f32 = 0.00100000; // cos(90° - 0.001)
const SIN_HEMI_IN: f32 = 0.99999950;
// vec4s per node: the cluster's quadratic (A, B per channel, C per channel: 10) or the
// directional buckets (flux and mean direction per octant: 16), then the centroid.
const COEFFS: u32 = 17u;

struct Node {
    lo: vec3<f32>,
    hi: vec3<f32>,
    axis: vec3<f32>,
    // Cone half-angle (radians); NO_CONE when the samples' normals span too much.
    half: f32,
    cos_half: f32,
    simple: bool,
    // Leaf clusters of the tile in use (on a tile's first leaf only).
    used: u32,
}

fn node_empty(n: Node) -> bool {
    return any(n.lo > n.hi);
}

fn load_node(k: u32) -> Node {
    let a = nodes[3u * k];
    let b = nodes[3u * k + 1u];
    let c = nodes[3u * k + 2u];
    var n: Node;
    n.lo = a.xyz;
    n.simple = (u32(a.w) & 1u) != 0u;
    n.used = u32(a.w) >> 1u;
    n.hi = b.xyz;
    n.half = b.w;
    n.axis = c.xyz;
    n.cos_half = c.w;
    return n;
}

// `load_node` from the node texture (a copy made after the hierarchy is built: texture
// reads are the fast ones on lavapipe).
fn fetch_node(k: u32) -> Node {
    let base = vec2<i32>(i32((k % NODE_ROW) * 3u), i32(k / NODE_ROW));
    let a = textureLoad(node_texels, base, 0);
    let b = textureLoad(node_texels, base + vec2<i32>(1, 0), 0);
    let c = textureLoad(node_texels, base + vec2<i32>(2, 0), 0);
    var n: Node;
    n.lo = a.xyz;
    n.simple = (u32(a.w) & 1u) != 0u;
    n.used = u32(a.w) >> 1u;
    n.hi = b.xyz;
    n.half = b.w;
    n.axis = c.xyz;
    n.cos_half = c.w;
    return n;
}

fn store_node(k: u32, n: Node) {
    nodes[3u * k] = vec4<f32>(n.lo, f32(u32(n.simple) + 2u * n.used));
    nodes[3u * k + 1u] = vec4<f32>(n.hi, n.half);
    nodes[3u * k + 2u] = vec4<f32>(n.axis, cos(min(n.half, PI)));
}

// The mean position of a node's samples and their count, in the last slot of its
// coefficients (the directional approximation evaluates kernels there: on the surface,
// where a box's centre need not be).
const CENTROID: u32 = 16u;

fn store_centroid(k: u32, sum: vec4<f32>) {
    coeffs[k * COEFFS + CENTROID] = vec4<f32>(sum.xyz / max(sum.w, 1.0), sum.w);
}

fn angle_between(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return acos(clamp(dot(a, b), -1.0, 1.0));
}

// Depth slice of a view sample: log-spaced in distance from the eye, 4 slices per doubling
// (19% apart), so that a tile's samples on one surface share a slice or two.
fn depth_slice(p: vec3<f32>) -> u32 {
    let d = max(length(p - params.eye), 1e-6);
    return u32(clamp(log2(d) * 4.0 + 1024.0, 0.0, 4095.0));
}

var<workgroup> wg_first: atomic<u32>;
var<workgroup> wg_used: atomic<u32>;
// The tile's first covered sample (local index) and its normal.
var<workgroup> wg_ref: atomic<u32>;
var<workgroup> wg_ref_normal: vec3<f32>;
var<workgroup> wg_lo: array<vec3<f32>, 64>;
var<workgroup> wg_hi: array<vec3<f32>, 64>;
var<workgroup> wg_n: array<vec3<f32>, 64>;
var<workgroup> wg_dot: array<f32, 64>;
var<workgroup> wg_ok: array<u32, 64>;
// Sum of the positions (xyz) and count (w) of the samples.
var<workgroup> wg_p: array<vec4<f32>, 64>;

// Reduction over the workgroup of this thread's box, normal sum and simplicity.
fn reduce_node(li: u32) {
    for (var s = 32u; s > 0u; s >>= 1u) {
        if li < s {
            wg_lo[li] = min(wg_lo[li], wg_lo[li + s]);
            wg_hi[li] = max(wg_hi[li], wg_hi[li + s]);
            wg_n[li] = wg_n[li] + wg_n[li + s];
            wg_ok[li] = wg_ok[li] & wg_ok[li + s];
            wg_p[li] = wg_p[li] + wg_p[li + s];
        }
        workgroupBarrier();
    }
}

fn reduce_min_dot(li: u32) {
    for (var s = 32u; s > 0u; s >>= 1u) {
        if li < s {
            wg_dot[li] = min(wg_dot[li], wg_dot[li + s]);
        }
        workgroupBarrier();
    }
}

// The leaf clusters of one tile, keyed by depth and normal (Moreau et al. §4.1): the tile's
// samples are split by depth slice, counted from the tile's nearest (slices
// 0 .. DEPTH_RANKS - 2 get a rank each, the farther samples share the last: a depth
// discontinuity separates fore- and background), and each rank in two by normal: within
// 45° of the tile's reference normal (its first covered sample's) or not. Where two walls
// meet in a tile, each wall gets a cluster with a narrow normal cone, which can accept
// photons whole; one cluster spanning both has a 90° cone and never can.
@compute @workgroup_size(8, 8)
fn cluster_leaves(
    @builtin(workgroup_id) tile: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let texel = tile.xy * TILE + lid.xy;
    var valid = false;
    var pos = vec3<f32>(0.0);
    var ns = vec3<f32>(0.0);
    var simple = true;
    var slice = 0xffffffffu;
    if all(texel < params.low_size) {
        let px = sample_pixel(texel);
        let p = textureLoad(g_position, px, 0);
        if p.w != 0.0 {
            valid = true;
            let s = view_sample(g_position, g_normals, g_diffuse, g_specular, px, params.eye);
            pos = s.position;
            ns = s.normal;
            let m = s.material;
            // bsdf_eval is exactly diffuse/π here: no specular lobe, no Fresnel coupling,
            // and the eye on the normal's side.
            simple = all(m.specular == vec3<f32>(0.0)) && m.fresnel == 0u
                && dot(ns, s.wo) > 0.0;
            slice = depth_slice(pos);
        }
    }
    if li == 0u {
        atomicStore(&wg_first, 0xffffffffu);
        atomicStore(&wg_ref, 0xffffffffu);
    }
    workgroupBarrier();
    atomicMin(&wg_first, slice);
    if valid {
        atomicMin(&wg_ref, li);
    }
    workgroupBarrier();
    if li == atomicLoad(&wg_ref) {
        wg_ref_normal = ns;
    }
    workgroupBarrier();
    let rank = min(slice - atomicLoad(&wg_first), DEPTH_RANKS - 1u);
    let cluster = 2u * rank + u32(dot(ns, wg_ref_normal) < COS_NORMAL_SPLIT);
    if li == 0u {
        atomicStore(&wg_used, 0u);
    }
    workgroupBarrier();
    if valid {
        atomicMax(&wg_used, cluster + 1u);
    }
    workgroupBarrier();
    let t = tile.y * params.tiles.x + tile.x;
    for (var c = 0u; c < CLUSTERS_PER_TILE; c++) {
        let mine = valid && cluster == c;
        wg_lo[li] = select(vec3<f32>(3.4e38), pos, mine);
        wg_hi[li] = select(vec3<f32>(-3.4e38), pos, mine);
        wg_n[li] = select(vec3<f32>(0.0), ns, mine);
        wg_ok[li] = select(1u, u32(simple), mine);
        wg_p[li] = select(vec4<f32>(0.0), vec4<f32>(pos, 1.0), mine);
        workgroupBarrier();
        reduce_node(li);
        let sum = wg_n[0];
        let axis = select(vec3<f32>(0.0, 0.0, 1.0), normalize(sum), length(sum) > 1e-6);
        wg_dot[li] = select(1.0, dot(axis, ns), mine);
        workgroupBarrier();
        reduce_min_dot(li);
        if li == 0u {
            var n: Node;
            n.lo = wg_lo[0];
            n.hi = wg_hi[0];
            n.axis = axis;
            n.half = select(NO_CONE, acos(clamp(wg_dot[0], -1.0, 1.0)), length(sum) > 1e-6);
            n.simple = wg_ok[0] != 0u;
            n.used = select(0u, atomicLoad(&wg_used), c == 0u);
            store_node(t * CLUSTERS_PER_TILE + c, n);
            store_centroid(t * CLUSTERS_PER_TILE + c, wg_p[0]);
        }
        workgroupBarrier();
    }
    // The sample's leaf, for the shading pass.
    if all(texel < params.low_size) {
        cluster_of[texel.y * params.low_size.x + texel.x] = t * CLUSTERS_PER_TILE + cluster;
    }
}

// First node of level `l` (0 = leaves) and its nodes per row and rows.
fn level_first(l: u32) -> u32 {
    return params.level_first[l];
}

fn level_dims(l: u32) -> vec2<u32> {
    if l == 0u {
        return params.tiles;
    }
    if l == 1u {
        return params.l1;
    }
    return params.l2;
}

// The leaves of tile (x, y), or the node (x, y) of level l ≥ 1.
fn node_index(l: u32, xy: vec2<u32>) -> u32 {
    return level_first(l) + (xy.y * level_dims(l).x + xy.x) * select(1u, CLUSTERS_PER_TILE, l == 0u);
}

// Parents of level `l` from the level below: union of boxes, a cone around the children's
// cones, simple when every non-empty child is.
@compute @workgroup_size(64)
fn cluster_parents1(@builtin(global_invocation_id) gid: vec3<u32>) {
    parents(1u, gid.x);
}

@compute @workgroup_size(64)
fn cluster_parents2(@builtin(global_invocation_id) gid: vec3<u32>) {
    parents(2u, gid.x);
}

fn parents(l: u32, index: u32) {
    let dims = level_dims(l);
    if index >= dims.x * dims.y {
        return;
    }
    let xy = vec2<u32>(index % dims.x, index / dims.x);
    let below = level_dims(l - 1u);
    let per = select(1u, CLUSTERS_PER_TILE, l == 1u);
    var n: Node;
    n.lo = vec3<f32>(3.4e38);
    n.hi = vec3<f32>(-3.4e38);
    n.simple = true;
    var sum = vec3<f32>(0.0);
    var centroid = vec4<f32>(0.0);
    var cone_ok = true;
    let c0 = xy * FANOUT;
    let c1 = min(c0 + FANOUT, below);
    for (var y = c0.y; y < c1.y; y++) {
        for (var x = c0.x; x < c1.x; x++) {
            for (var c = 0u; c < per; c++) {
                let child = load_node(node_index(l - 1u, vec2<u32>(x, y)) + c);
                if node_empty(child) {
                    continue;
                }
                n.lo = min(n.lo, child.lo);
                n.hi = max(n.hi, child.hi);
                n.simple = n.simple && child.simple;
                let cc = coeffs[(node_index(l - 1u, vec2<u32>(x, y)) + c) * COEFFS + CENTROID];
                centroid += vec4<f32>(cc.xyz * cc.w, cc.w);
                cone_ok = cone_ok && child.half < NO_CONE;
                sum += child.axis;
            }
        }
    }
    n.axis = select(vec3<f32>(0.0, 0.0, 1.0), normalize(sum), length(sum) > 1e-6);
    n.half = 0.0;
    for (var y = c0.y; y < c1.y; y++) {
        for (var x = c0.x; x < c1.x; x++) {
            for (var c = 0u; c < per; c++) {
                let child = load_node(node_index(l - 1u, vec2<u32>(x, y)) + c);
                if !node_empty(child) {
                    n.half = max(n.half, angle_between(n.axis, child.axis) + child.half);
                }
            }
        }
    }
    if !cone_ok || length(sum) <= 1e-6 {
        n.half = NO_CONE;
    }
    store_node(node_index(l, xy), n);
    store_centroid(node_index(l, xy), centroid);
}

// What a photon does at a node: 0 = reject, 1 = descend (or test, at a leaf), 2 = accept.
fn classify(p: VolumePhoton, wi: vec3<f32>, n: Node) -> u32 {
    if node_empty(n) {
        return 0u;
    }
    let d = p.center - clamp(p.center, n.lo, n.hi);
    let rb = p.radius * max(1.0, params.z_ratio) * (1.0 + SLACK);
    if dot(d, d) > rb * rb {
        return 0u;
    }
    // Angle tests on cosines: θ ± h against a limit L, with cos(L ± h) from the node's
    // cos h and sin h.
    let cos_normal = dot(n.axis, p.normal);
    let cone = n.half < NO_CONE;
    let sin_half = sqrt(max(1.0 - n.cos_half * n.cos_half, 0.0));
    // Reject when θ − h > L + margin for the normal test (no sample agrees); possible only
    // while L + margin + h < π.
    if cone && n.half + NORMAL_LIMIT + ANGLE_MARGIN < PI
        && cos_normal < COS_NORMAL_OUT * n.cos_half - SIN_NORMAL_OUT * sin_half {
        return 0u;
    }
    if !n.simple || !cone {
        return 1u;
    }
    // Accept needs θ + h < L − margin for the normal test and the hemisphere of wi.
    if n.half >= NORMAL_LIMIT - ANGLE_MARGIN
        || cos_normal <= COS_NORMAL_IN * n.cos_half + SIN_NORMAL_IN * sin_half
        || dot(n.axis, wi) <= COS_HEMI_IN * n.cos_half + SIN_HEMI_IN * sin_half {
        return 1u;
    }
    // Every corner of the box inside the ellipsoid (convex: then the whole box is).
    let r2 = p.radius * p.radius;
    let rz = p.radius * params.z_ratio;
    for (var i = 0u; i < 8u; i++) {
        let corner = select(n.lo, n.hi, vec3<bool>((i & 1u) != 0u, (i & 2u) != 0u, (i & 4u) != 0u));
        let v = corner - p.center;
        let dz = dot(v, p.normal);
        let d2 = max(dot(v, v) - dz * dz, 0.0);
        if d2 / r2 + dz * dz / (rz * rz) >= 1.0 - INSIDE_MARGIN {
            return 1u;
        }
    }
    return 2u;
}

// List slot of node k's accepted photons, and of leaf k's photons to test.
fn accept_slot(k: u32) -> u32 {
    return k;
}

fn test_slot(leaf: u32) -> u32 {
    return params.nodes + leaf;
}

// ---- The walk in sub-passes with job lists (Moreau et al. section 4.3) ----
// The walk runs level by level: `top` takes each photon through the top level, `mid` is
// one thread per (photon, level-2 node) job the top level descended into, `low` one per
// (photon, level-1 node) job of the middle level. A photon that overlaps many nodes spreads
// its work over as many threads, instead of one thread walking them all while its
// neighbours idle. Each level runs twice: counting, which also appends the next level's
// jobs, and (after the prefix sum) filling the lists from the same jobs. The job counts and
// the indirect dispatch arguments of the two job passes follow the list total in `counts`:
// [slots] total, [slots + 1 + l] jobs of job level l (0: level-2 nodes, 1: level-1 nodes),
// [slots + 4 + 3l ..] that level's (x, y, z) workgroups.

@group(0) @binding(16) var<storage, read_write> jobs: array<vec2<u32>>;

// wgpu's default `max_compute_workgroups_per_dimension`.
const MAX_GROUPS: u32 = 65535u;

fn job_count_slot(level: u32) -> u32 {
    return params.slots + 1u + level;
}

fn job_args_slot(level: u32) -> u32 {
    return params.slots + 4u + 3u * level;
}

fn push_job(level: u32, job: vec2<u32>) {
    let at = atomicAdd(&counts[job_count_slot(level)], 1u);
    if at < params.jobs {
        jobs[level * params.jobs + at] = job;
    }
}

// Jobs of `level` that were kept (the count beyond the capacity is an overflow the CPU
// sees, and redoes the frame with room).
fn job_total(level: u32) -> u32 {
    return min(atomicLoad(&counts[job_count_slot(level)]), params.jobs);
}

// (x, y) of node `k` of level `l` ≥ 1.
fn node_xy(l: u32, k: u32) -> vec2<u32> {
    let idx = k - level_first(l);
    let w = level_dims(l).x;
    return vec2<u32>(idx % w, idx / w);
}

// A photon with its light, and its tile range as (t0, t1); t0.x > t1.x when it covers none.
struct WalkPhoton {
    p: VolumePhoton,
    t0: vec2<u32>,
    t1: vec2<u32>,
    covers: bool,
}

fn walk_photon(i: u32) -> WalkPhoton {
    var p = load_photon_shape(i);
    load_photon_light(&p, i);
    var w: WalkPhoton;
    w.p = p;
    let r = tile_range(p);
    w.covers = r.x <= r.z;
    w.t0 = vec2<u32>(max(r.xy, vec2<i32>(0)));
    w.t1 = vec2<u32>(max(r.zw, vec2<i32>(0)));
    return w;
}

fn walk_top(i: u32, fill: bool) {
    let w = walk_photon(i);
    if !w.covers {
        return;
    }
    let per2 = FANOUT * FANOUT;
    for (var y2 = w.t0.y / per2; y2 <= w.t1.y / per2; y2++) {
        for (var x2 = w.t0.x / per2; x2 <= w.t1.x / per2; x2++) {
            let k2 = node_index(2u, vec2<u32>(x2, y2));
            let c = classify(w.p, w.p.incident, fetch_node(k2));
            if c == 2u {
                emit(accept_slot(k2), i, fill);
            } else if c == 1u && !fill {
                push_job(0u, vec2<u32>(i, k2));
            }
        }
    }
}

fn walk_mid(job: vec2<u32>, fill: bool) {
    let i = job.x;
    let w = walk_photon(i);
    let xy2 = node_xy(2u, job.y);
    let a1 = max(xy2 * FANOUT, w.t0 / FANOUT);
    let b1 = min(xy2 * FANOUT + FANOUT - 1u, w.t1 / FANOUT);
    for (var y1 = a1.y; y1 <= b1.y; y1++) {
        for (var x1 = a1.x; x1 <= b1.x; x1++) {
            let k1 = node_index(1u, vec2<u32>(x1, y1));
            let c = classify(w.p, w.p.incident, fetch_node(k1));
            if c == 2u {
                emit(accept_slot(k1), i, fill);
            } else if c == 1u && !fill {
                push_job(1u, vec2<u32>(i, k1));
            }
        }
    }
}

fn walk_low(job: vec2<u32>, fill: bool) {
    let i = job.x;
    let w = walk_photon(i);
    let xy1 = node_xy(1u, job.y);
    let a0 = max(xy1 * FANOUT, w.t0);
    let b0 = min(xy1 * FANOUT + FANOUT - 1u, w.t1);
    for (var y = a0.y; y <= b0.y; y++) {
        for (var x = a0.x; x <= b0.x; x++) {
            let leaves = node_index(0u, vec2<u32>(x, y));
            var used = 1u;
            for (var c = 0u; c < used; c++) {
                let k = leaves + c;
                let leaf = fetch_node(k);
                if c == 0u {
                    used = leaf.used;
                }
                let r = classify(w.p, w.p.incident, leaf);
                if r == 2u {
                    emit(accept_slot(k), i, fill);
                } else if r == 1u {
                    emit(test_slot(k), i, fill);
                }
            }
        }
    }
}

fn emit(slot: u32, i: u32, fill: bool) {
    if fill {
        let at = atomicAdd(&cursor[slot], 1u);
        if at < params.capacity {
            list[at] = i;
        }
    } else {
        atomicAdd(&counts[slot], 1u);
    }
}

// The indirect dispatch of job level `level`: 64 jobs a workgroup, rows of MAX_GROUPS.
fn write_job_args(level: u32) {
    let groups = (job_total(level) + 63u) / 64u;
    let s = job_args_slot(level);
    atomicStore(&counts[s], min(groups, MAX_GROUPS));
    atomicStore(&counts[s + 1u], max((groups + MAX_GROUPS - 1u) / MAX_GROUPS, 1u));
    atomicStore(&counts[s + 2u], 1u);
}

@compute @workgroup_size(1)
fn cluster_jobs0() {
    write_job_args(0u);
}

@compute @workgroup_size(1)
fn cluster_jobs1() {
    write_job_args(1u);
}

@compute @workgroup_size(64)
fn cluster_top_count(inv: ListInvocation) {
    let i = photon_index(inv);
    if i < params.photons {
        walk_top(i, false);
    }
}

@compute @workgroup_size(64)
fn cluster_top_fill(inv: ListInvocation) {
    let i = photon_index(inv);
    if i < params.photons {
        walk_top(i, true);
    }
}

@compute @workgroup_size(64)
fn cluster_mid_count(inv: ListInvocation) {
    let j = photon_index(inv);
    if j < job_total(0u) {
        walk_mid(jobs[j], false);
    }
}

@compute @workgroup_size(64)
fn cluster_mid_fill(inv: ListInvocation) {
    let j = photon_index(inv);
    if j < job_total(0u) {
        walk_mid(jobs[j], true);
    }
}

@compute @workgroup_size(64)
fn cluster_low_count(inv: ListInvocation) {
    let j = photon_index(inv);
    if j < job_total(1u) {
        walk_low(jobs[params.jobs + j], false);
    }
}

@compute @workgroup_size(64)
fn cluster_low_fill(inv: ListInvocation) {
    let j = photon_index(inv);
    if j < job_total(1u) {
        walk_low(jobs[params.jobs + j], true);
    }
}

fn node_centre(n: Node) -> vec3<f32> {
    return 0.5 * (n.lo + n.hi);
}

// Each node's quadratic from its accepted photons (module comment), in list order.
@compute @workgroup_size(64)
fn cluster_accumulate(inv: ListInvocation) {
    let k = photon_index(inv);
    if k >= params.nodes {
        return;
    }
    // Fixed-point sums: the list's order varies between runs (atomics).
    var a_sum = fixed_zero();
    var b_sum = array<FixedSum, 3>(fixed_zero(), fixed_zero(), fixed_zero());
    var c_diag = array<FixedSum, 3>(fixed_zero(), fixed_zero(), fixed_zero());
    var c_off = array<FixedSum, 3>(fixed_zero(), fixed_zero(), fixed_zero());
    let begin = offsets[accept_slot(k)];
    let end = min(begin + atomicLoad(&counts[accept_slot(k)]), params.capacity);
    if end > begin {
        let o = node_centre(fetch_node(k));
        for (var j = begin; j < end; j++) {
            let i = list_entry(j);
            var p = load_photon_shape(i);
            load_photon_light(&p, i);
            let r2 = p.radius * p.radius;
            let a = 2.0 / (PI * r2);
            let b = a / r2;
            let u = p.center - o;
            let nu = dot(p.normal, u);
            let mu = u - p.normal * nu;
            let umu = dot(u, u) - nu * nu;
            let n = p.normal;
            let diag = vec3<f32>(1.0) - n * n;
            let off = -vec3<f32>(n.x * n.y, n.x * n.z, n.y * n.z);
            a_sum = fixed_add_signed(a_sum, p.power * (a - b * umu));
            for (var c = 0u; c < 3u; c++) {
                let w = p.power[c] * b;
                b_sum[c] = fixed_add_signed(b_sum[c], 2.0 * w * mu);
                c_diag[c] = fixed_add_signed(c_diag[c], w * diag);
                c_off[c] = fixed_add_signed(c_off[c], w * off);
            }
        }
    }
    let base = k * COEFFS;
    coeffs[base] = vec4<f32>(fixed_value_signed(a_sum), 0.0);
    for (var c = 0u; c < 3u; c++) {
        coeffs[base + 1u + c] = vec4<f32>(fixed_value_signed(b_sum[c]), 0.0);
        coeffs[base + 4u + 2u * c] = vec4<f32>(fixed_value_signed(c_diag[c]), 0.0);
        coeffs[base + 5u + 2u * c] = vec4<f32>(fixed_value_signed(c_off[c]), 0.0);
    }
}

// Σ Φᵢκᵢ(x) over node k's accepted photons, per channel.
fn accepted_flux(k: u32, x: vec3<f32>) -> vec3<f32> {
    let base = k * COEFFS;
    let a = coeffs[base].xyz;
    if all(a == vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    let y = x - node_centre(fetch_node(k));
    let yy = y * y;
    let yo = vec3<f32>(y.x * y.y, y.x * y.z, y.y * y.z);
    var out = a;
    for (var c = 0u; c < 3u; c++) {
        let quad = dot(coeffs[base + 4u + 2u * c].xyz, yy) + 2.0 * dot(coeffs[base + 5u + 2u * c].xyz, yo);
        out[c] += dot(coeffs[base + 1u + c].xyz, y) - quad;
    }
    return out;
}

@compute @workgroup_size(8, 8)
fn cluster_shade(
    @builtin(workgroup_id) tile: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
) {
    let texel = tile.xy * TILE + lid.xy;
    if any(texel >= params.low_size) {
        return;
    }
    let px = sample_pixel(texel);
    var sum = vec3<f32>(0.0);
    if textureLoad(g_position, px, 0).w != 0.0 {
        let s = view_sample(g_position, g_normals, g_diffuse, g_specular, px, params.eye);
        let leaf = cluster_of[texel.y * params.low_size.x + texel.x];
        // Trivially accepted photons of the leaf and its ancestors (simple nodes only, so
        // the BSDF is ρ/π).
        var flux = accepted_flux(leaf, s.position);
        flux += accepted_flux(node_index(1u, tile.xy / FANOUT), s.position);
        flux += accepted_flux(node_index(2u, tile.xy / (FANOUT * FANOUT)), s.position);
        sum = s.material.diffuse / PI * flux;
        sum += list_sum(test_slot(leaf), s);
    }
    textureStore(low, vec2<i32>(texel), vec4<f32>(sum, 0.0));
}

// ---- Directional approximation (Moreau et al. section 4.7) ----
// The same walk, but no per-sample photon loop: each node keeps, per octant of the incident
// direction, the photons' flux density Φκ at the node's centroid and their mean incident
// direction (weighted by luminance) — the photons of its accept list and, at a leaf, of its
// test list, with the normal test against the node's cone axis. A view sample sums, over
// its leaf and the leaf's ancestors, f(wo, ω̄)·E·w for each octant's mean direction ω̄ with
// the 2·cos weighting w = clamp(½ + 2 cos θ, 0, 1) of θ between ω̄ and the sample's normal
// (the octant's light counts in full when it arrives from more than 14.5° above the
// tangent plane, not at all from more than 14.5° below). Irradiance is constant per node.
// As in the paper, the approximation is for diffuse surfaces: samples of clusters that are
// not simple (glossy) sum their leaf's photons exactly.

fn octant_of(w: vec3<f32>) -> u32 {
    return u32(w.x >= 0.0) | (u32(w.y >= 0.0) << 1u) | (u32(w.z >= 0.0) << 2u);
}

fn add_to_buckets(
    buckets: ptr<function, array<FixedSum, 16>>,
    begin: u32,
    end: u32,
    n: Node,
    o: vec3<f32>,
) {
    for (var j = begin; j < end; j++) {
        let i = list_entry(j);
        var p = load_photon_shape(i);
        let k = volume_kernel(p, o, params.z_ratio);
        if k.y == 0.0 || dot(n.axis, p.normal) <= 0.5 {
            continue;
        }
        load_photon_light(&p, i);
        let b = octant_of(p.incident);
        let e = p.power * k.x;
        (*buckets)[2u * b] = fixed_add((*buckets)[2u * b], e);
        let lum = dot(e, vec3<f32>(0.2126, 0.7152, 0.0722));
        (*buckets)[2u * b + 1u] = fixed_add_signed((*buckets)[2u * b + 1u], lum * p.incident);
    }
}

@compute @workgroup_size(64)
fn directional_accumulate(inv: ListInvocation) {
    let k = photon_index(inv);
    if k >= params.nodes {
        return;
    }
    // Fixed-point sums: the lists' order varies between runs (atomics).
    var buckets: array<FixedSum, 16>;
    for (var o = 0u; o < 16u; o++) {
        buckets[o] = fixed_zero();
    }
    let n = fetch_node(k);
    let o = coeffs[k * COEFFS + CENTROID].xyz;
    if !node_empty(n) {
        let a0 = offsets[accept_slot(k)];
        let a1 = min(a0 + atomicLoad(&counts[accept_slot(k)]), params.capacity);
        add_to_buckets(&buckets, a0, a1, n, o);
        if k < params.level_first[1] {
            let t0 = offsets[test_slot(k)];
            let t1 = min(t0 + atomicLoad(&counts[test_slot(k)]), params.capacity);
            add_to_buckets(&buckets, t0, t1, n, o);
        }
    }
    for (var o = 0u; o < 8u; o++) {
        coeffs[k * COEFFS + 2u * o] = vec4<f32>(fixed_value(buckets[2u * o]), 0.0);
        coeffs[k * COEFFS + 2u * o + 1u] = vec4<f32>(fixed_value_signed(buckets[2u * o + 1u]), 0.0);
    }
}

fn directional_radiance(k: u32, s: ViewSample) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    for (var o = 0u; o < 8u; o++) {
        let e = coeffs[k * COEFFS + 2u * o].xyz;
        let d = coeffs[k * COEFFS + 2u * o + 1u].xyz;
        if all(e == vec3<f32>(0.0)) || all(d == vec3<f32>(0.0)) {
            continue;
        }
        var wi = normalize(d);
        let c = dot(s.normal, wi);
        let w = clamp(0.5 + 2.0 * c, 0.0, 1.0);
        if w == 0.0 {
            continue;
        }
        // Light arriving about along the tangent plane: evaluate the BSDF just above it.
        if c < 0.05 {
            wi = normalize(wi + (0.05 - c) * s.normal);
        }
        sum += bsdf_eval(s.material, s.normal, s.wo, wi) * e * w;
    }
    return sum;
}

@compute @workgroup_size(8, 8)
fn directional_shade(
    @builtin(workgroup_id) tile: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
) {
    let texel = tile.xy * TILE + lid.xy;
    if any(texel >= params.low_size) {
        return;
    }
    let px = sample_pixel(texel);
    var sum = vec3<f32>(0.0);
    if textureLoad(g_position, px, 0).w != 0.0 {
        let s = view_sample(g_position, g_normals, g_diffuse, g_specular, px, params.eye);
        let leaf = cluster_of[texel.y * params.low_size.x + texel.x];
        if fetch_node(leaf).simple {
            sum = directional_radiance(leaf, s)
                + directional_radiance(node_index(1u, tile.xy / FANOUT), s)
                + directional_radiance(node_index(2u, tile.xy / (FANOUT * FANOUT)), s);
        } else {
            // Glossy (or otherwise not simple) clusters: 8 directions cannot stand for a
            // lobe, so their samples sum their leaf's photons exactly (no ancestor of a
            // non-simple leaf accepts photons).
            sum = list_sum(test_slot(leaf), s);
        }
    }
    textureStore(low, vec2<i32>(texel), vec4<f32>(sum, 0.0));
}
