// A batch of ray queries (`gpu::bvh::query`): for the CPU/GPU parity tests and the rays/s
// measurement. After `bvh.wgsl`.

// origin_tmax: the origin and the segment's end; dir_any: the direction, and w = 1 for an
// occlusion (any-hit) query, 0 for a closest-hit one.
struct QueryRay {
    origin_tmax: vec4<f32>,
    dir_any: vec4<f32>,
}

@group(0) @binding(0) var<storage, read> query_rays: array<QueryRay>;
// Per ray: t, the triangle's bits (BVH_NONE: no hit), u, v.
@group(0) @binding(1) var<storage, read_write> query_hits: array<vec4<f32>>;
// Rays whose traversal stack overflowed (a hit may be missing).
@group(0) @binding(2) var<storage, read_write> query_overflows: atomic<u32>;

@compute @workgroup_size(64)
fn query(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&query_rays) {
        return;
    }
    let r = query_rays[i];
    let h = bvh_query(r.origin_tmax.xyz, r.dir_any.xyz, r.origin_tmax.w, r.dir_any.w != 0.0);
    query_hits[i] = vec4<f32>(h.t, bitcast<f32>(h.triangle), h.u, h.v);
    if bvh_overflowed {
        atomicAdd(&query_overflows, 1u);
    }
}
