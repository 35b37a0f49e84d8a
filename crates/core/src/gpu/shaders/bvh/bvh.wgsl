// Closest-hit and any-hit ray queries over the scene's two-level BVH, flattened by
// `trace/bvh_flat.rs` (binary trees as obvhs's PLOC builds them): a top level over the
// instances, each instance's mesh tree in its local frame. The same Möller–Trumbore test
// as the CPU's `trace/bvh.rs` on the same floats (corner 0 and two edges computed on the
// CPU), over the open segment (0, tmax). The stack lives in private memory.
//
// Group 1 of the passes that trace (`gpu::bvh::GpuBvh`). No alpha masks: a scene with
// masks is traced on the CPU.

struct BvhNode {
    lo: vec3<f32>,
    // > 0: a leaf of `count` triangles (instances at the top level) from `first`;
    // 0: children at `first` and `first + 1`.
    count: u32,
    hi: vec3<f32>,
    first: u32,
}

struct BvhTri {
    // Corner 0, and the triangle's index in its mesh (read as an integer, never as a
    // float: small indices are denormal floats).
    v0: vec3<f32>,
    id: u32,
    // The edges to corners 1 and 2 (w: 0).
    e1: vec4<f32>,
    e2: vec4<f32>,
}

struct BvhInstance {
    // World -> mesh: local.i = dot(row_i.xyz, p) + row_i.w.
    row0: vec4<f32>,
    row1: vec4<f32>,
    row2: vec4<f32>,
    // The mesh's root node (BVH_NONE: empty), the instance's first flat triangle, 1 when
    // mirrored (the flat triangles swap corners 1 and 2, so the barycentrics swap), 0.
    refs: vec4<u32>,
}

struct BvhInfo {
    top_root: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(1) @binding(0) var<storage, read> bvh_nodes: array<BvhNode>;
@group(1) @binding(1) var<storage, read> bvh_tris: array<BvhTri>;
@group(1) @binding(2) var<storage, read> bvh_instances: array<BvhInstance>;
@group(1) @binding(3) var<uniform> bvh_info: BvhInfo;

const BVH_NONE: u32 = 0xffffffffu;
const BVH_INF: f32 = 3.0e38;
// The CPU's traversal (obvhs's CWBVH) culls boxes the ray leaves within t < 1e-4 of its
// origin (`cwbvh::node::EPSILON`), so hits that close are not found there; the same here,
// for parity (the callers offset their origins well beyond it).
const BVH_TMIN: f32 = 1e-4;
// Deeper than the PLOC trees of the scenes gi loads (a full tree of 2^64 leaves); a push
// past it sets `bvh_overflowed` (the parity test checks it stays false).
const BVH_STACK: u32 = 64u;

// A hit: distance, triangle (BVH_NONE: none; the flat scene index from `bvh_closest`) and
// the barycentrics of corners 1 and 2.
struct BvhHit {
    t: f32,
    triangle: u32,
    u: f32,
    v: f32,
}

// Nodes still to visit, each with the entry distance of its box.
struct BvhStack {
    node: array<u32, BVH_STACK>,
    t: array<f32, BVH_STACK>,
    size: u32,
}

var<private> bvh_overflowed: bool = false;

// 1/d, with components below 1e-30 (zeros of either sign) as 1e30: the slabs then span
// everything or nothing, as for a parallel ray, without 0·inf.
fn bvh_inv_dir(d: vec3<f32>) -> vec3<f32> {
    let tiny = vec3<f32>(1e-30);
    return 1.0 / select(d, tiny, abs(d) < tiny);
}

// Entry distance of the ray into box [lo, hi] within [BVH_TMIN, tmax], or BVH_INF. The
// exit distance is widened by 4 ulps (Ize, "Robust BVH ray traversal") so that rounding
// never culls a box whose triangle the exact test would hit.
fn bvh_box(lo: vec3<f32>, hi: vec3<f32>, o: vec3<f32>, inv: vec3<f32>, tmax: f32) -> f32 {
    let a = (lo - o) * inv;
    let b = (hi - o) * inv;
    let near = min(a, b);
    let far = max(a, b);
    let t0 = max(max(near.x, near.y), max(near.z, BVH_TMIN));
    let t1 = min(min(far.x, far.y), min(far.z, tmax)) * 1.0000005;
    return select(BVH_INF, t0, t0 <= t1);
}

fn bvh_node_box(i: u32, o: vec3<f32>, inv: vec3<f32>, tmax: f32) -> f32 {
    return bvh_box(bvh_nodes[i].lo, bvh_nodes[i].hi, o, inv, tmax);
}

fn bvh_push(s: ptr<function, BvhStack>, node: u32, t: f32) {
    if t >= BVH_INF {
        return;
    }
    if (*s).size == BVH_STACK {
        bvh_overflowed = true;
        return;
    }
    (*s).node[(*s).size] = node;
    (*s).t[(*s).size] = t;
    (*s).size += 1u;
}

// Pushes the children of inner node `n` that the ray enters before `tmax`, the nearer last
// (visited first).
fn bvh_push_children(s: ptr<function, BvhStack>, n: BvhNode, o: vec3<f32>, inv: vec3<f32>, tmax: f32) {
    let ta = bvh_node_box(n.first, o, inv, tmax);
    let tb = bvh_node_box(n.first + 1u, o, inv, tmax);
    if ta <= tb {
        bvh_push(s, n.first + 1u, tb);
        bvh_push(s, n.first, ta);
    } else {
        bvh_push(s, n.first, ta);
        bvh_push(s, n.first + 1u, tb);
    }
}

// The next node whose box the ray enters before `tmax` (BVH_NONE: done).
fn bvh_pop(s: ptr<function, BvhStack>, tmax: f32) -> u32 {
    loop {
        if (*s).size == 0u {
            return BVH_NONE;
        }
        (*s).size -= 1u;
        if (*s).t[(*s).size] <= tmax {
            return (*s).node[(*s).size];
        }
    }
    return BVH_NONE;
}

// A stack holding `root` if the ray enters its box before `tmax`.
fn bvh_start(root: u32, o: vec3<f32>, inv: vec3<f32>, tmax: f32) -> BvhStack {
    var s: BvhStack;
    s.size = 0u;
    bvh_push(&s, root, bvh_node_box(root, o, inv, tmax));
    return s;
}

// Möller–Trumbore as `Tri::intersect` (trace/bvh.rs): (t, u, v), or t = -1 outside (0, tmax).
fn bvh_triangle(tri: BvhTri, o: vec3<f32>, d: vec3<f32>, tmax: f32) -> vec3<f32> {
    let e1 = tri.e1.xyz;
    let e2 = tri.e2.xyz;
    let p = cross(d, e2);
    let det = dot(e1, p);
    if abs(det) < 1e-12 {
        return vec3<f32>(-1.0);
    }
    let inv = 1.0 / det;
    let s = o - tri.v0;
    let u = dot(s, p) * inv;
    if u < 0.0 || u > 1.0 {
        return vec3<f32>(-1.0);
    }
    let q = cross(s, e1);
    let v = dot(d, q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return vec3<f32>(-1.0);
    }
    let t = dot(e2, q) * inv;
    if t > 0.0 && t < tmax {
        return vec3<f32>(t, u, v);
    }
    return vec3<f32>(-1.0);
}

// Stack entries besides node indices: an instance to enter (`BVH_INSTANCE | k`, pushed
// by the top level's leaves) and the return to the world ray (`BVH_LEAVE`, below an
// entered instance's nodes).
const BVH_INSTANCE: u32 = 0x80000000u;
const BVH_LEAVE: u32 = 0xfffffffeu;

// The ray of one level: origin, direction, their inverse; the instance it is in (BVH_NONE:
// the world, at the top level).
struct BvhRay {
    o: vec3<f32>,
    d: vec3<f32>,
    inv: vec3<f32>,
    instance: u32,
}

fn bvh_ray(o: vec3<f32>, d: vec3<f32>, instance: u32) -> BvhRay {
    return BvhRay(o, d, bvh_inv_dir(d), instance);
}

// Enters instance `k`: the ray in its mesh's frame (the same parameter t: the direction is
// not renormalised), its root pushed above a BVH_LEAVE.
fn bvh_enter(s: ptr<function, BvhStack>, k: u32, world: BvhRay, tmax: f32) -> BvhRay {
    let inst = bvh_instances[k];
    let p = vec4<f32>(world.o, 1.0);
    let o = vec3<f32>(dot(inst.row0, p), dot(inst.row1, p), dot(inst.row2, p));
    let d = vec3<f32>(dot(inst.row0.xyz, world.d), dot(inst.row1.xyz, world.d), dot(inst.row2.xyz, world.d));
    let r = bvh_ray(o, d, k);
    bvh_push(s, BVH_LEAVE, -1.0);
    let root = inst.refs.x;
    if root != BVH_NONE {
        bvh_push(s, root, bvh_node_box(root, r.o, r.inv, tmax));
    }
    return r;
}

// The hit `h` (t, u, v) on BVH triangle `k` of instance `instance`, as a flat scene
// triangle with barycentrics in its corner order.
fn bvh_scene_hit(h: vec3<f32>, k: u32, instance: u32) -> BvhHit {
    let inst = bvh_instances[instance];
    let triangle = inst.refs.y + bvh_tris[k].id;
    if inst.refs.z != 0u {
        return BvhHit(h.x, triangle, h.z, h.y);
    }
    return BvhHit(h.x, triangle, h.y, h.z);
}

// The closest hit (any hit when `any`) along o + t·d, t in (0, tmax), over the whole scene:
// one loop over one stack through both levels (an instance's nodes sit above a BVH_LEAVE
// that restores the world ray).
fn bvh_query(o: vec3<f32>, d: vec3<f32>, tmax: f32, any: bool) -> BvhHit {
    var best = BvhHit(tmax, BVH_NONE, 0.0, 0.0);
    let root = bvh_info.top_root;
    if root == BVH_NONE {
        return best;
    }
    let world = bvh_ray(o, d, BVH_NONE);
    var r = world;
    var s = bvh_start(root, o, r.inv, tmax);
    loop {
        let i = bvh_pop(&s, best.t);
        if i == BVH_NONE {
            break;
        }
        if i == BVH_LEAVE {
            r = world;
            continue;
        }
        if (i & BVH_INSTANCE) != 0u {
            r = bvh_enter(&s, i & ~BVH_INSTANCE, world, best.t);
            continue;
        }
        let n = bvh_nodes[i];
        if n.count == 0u {
            bvh_push_children(&s, n, r.o, r.inv, best.t);
            continue;
        }
        for (var k = n.first; k < n.first + n.count; k += 1u) {
            if r.instance == BVH_NONE {
                // A top-level leaf: its instances, entered when popped.
                bvh_push(&s, BVH_INSTANCE | k, 0.0);
                continue;
            }
            let h = bvh_triangle(bvh_tris[k], r.o, r.d, best.t);
            if h.x > 0.0 {
                best = bvh_scene_hit(h, k, r.instance);
                if any {
                    return best;
                }
            }
        }
    }
    return best;
}

// The closest hit along o + t·d within (0, tmax) (`triangle` BVH_NONE: none).
fn bvh_closest(o: vec3<f32>, d: vec3<f32>, tmax: f32) -> BvhHit {
    return bvh_query(o, d, tmax, false);
}

// Whether anything blocks the open segment (0, tmax) of o + t·d.
fn bvh_occluded(o: vec3<f32>, d: vec3<f32>, tmax: f32) -> bool {
    return bvh_query(o, d, tmax, true).triangle != BVH_NONE;
}
