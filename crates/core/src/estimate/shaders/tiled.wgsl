// Tiled photon splatting in compute (Mara et al. 2013; Moreau et al. 2016, section 3.2) over
// the same photons, kernels and view samples as the raster photon volumes (volume.wgsl):
// 1. `tile_bounds`: the world-space bounding box of each screen tile's view samples;
// 2. `bin_count`: each photon counts itself into every tile whose box meets its bounding
//    sphere, among the tiles under the screen rectangle of its ellipsoid's bounding box;
// 3. `scan`: the lists' offsets (exclusive prefix sum of the counts) and the total;
// 4. `bin_fill`: each photon writes its index into those tiles' lists;
// 5. (the lists are copied into a texture: on lavapipe, loops that read textures run
//    10-35x faster than loops over storage buffers)
// 6. `shade`: each view sample sums the estimate term (common/photon_volume.wgsl) of the
//    photons in its tile's list, in fixed point (common/fixed_sum.wgsl), so that the image
//    does not depend on the list order the atomics of step 4 leave.
// Every step is conservative, so a sample gets exactly the photons whose ellipsoid holds it:
// the image equals the raster splat's up to float rounding, and is bitwise reproducible.
//
// Photons live in an Rgba32Float texture, 4 texels each (the 64-byte `Photon` as stored on
// the CPU: position|bounce, incident|path density, power|pad, normal|radius), PHOTON_ROW
// photons a row. The low-resolution target has one texel per G-buffer sample at the centre
// of a subsample × subsample block, as in volume.wgsl.

const TILE: u32 = 8u;
const PHOTON_ROW: u32 = 1024u;
const NODE_ROW: u32 = 1024u;
// Width of the list texture (entries a row).
const LIST_ROW: u32 = 4096u;
const SCAN_THREADS: u32 = 256u;
// Relative slack of the sphere-box test, so that rounding never drops a photon (a photon
// wrongly kept costs one rejected test; one wrongly dropped would change the image).
const SLACK: f32 = 1e-4;

struct TiledParams {
    // World -> clip of the low-resolution target (with volume.wgsl's half-pixel shift).
    view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    r_max: f32,
    low_size: vec2<u32>,
    tiles: vec2<u32>,
    subsample: u32,
    photons: u32,
    capacity: u32,
    z_ratio: f32,
    // The cluster hierarchy (cluster.wgsl): nodes per row and rows of levels 1 and 2, the
    // first node of each level and the node count.
    l1: vec2<u32>,
    l2: vec2<u32>,
    level_first: vec4<u32>,
    nodes: u32,
    // Photon lists (tiled: one per tile; cluster: accept lists, then leaf test lists).
    slots: u32,
    // Capacity of each of the cluster walk's two job lists (cluster.wgsl).
    jobs: u32,
}

@group(0) @binding(0) var<uniform> params: TiledParams;
@group(0) @binding(1) var g_position: texture_2d<f32>;
@group(0) @binding(2) var g_normals: texture_2d<f32>;
@group(0) @binding(3) var g_diffuse: texture_2d<f32>;
@group(0) @binding(4) var g_specular: texture_2d<f32>;
@group(0) @binding(5) var photon_texels: texture_2d<f32>;
// Per node (here a tile), 3 vec4s: min corner of its view samples | flags, max corner |
// cone half-angle, cone axis (cluster.wgsl). min > max: no sample.
@group(0) @binding(6) var<storage, read_write> nodes: array<vec4<f32>>;
// Per tile: photons in its list; the last entry is the total (set by `scan`).
@group(0) @binding(7) var<storage, read_write> counts: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> offsets: array<u32>;
@group(0) @binding(9) var<storage, read_write> cursor: array<atomic<u32>>;
@group(0) @binding(10) var<storage, read_write> list: array<u32>;
@group(0) @binding(11) var list_texels: texture_2d<u32>;
@group(0) @binding(12) var low: texture_storage_2d<rgba32float, write>;
// The cluster hierarchy's per-node quadratics and per-texel leaf (cluster.wgsl).
@group(0) @binding(13) var<storage, read_write> coeffs: array<vec4<f32>>;
@group(0) @binding(14) var<storage, read_write> cluster_of: array<u32>;
// A copy of `nodes` made once they are built (NODE_ROW nodes a row, 3 texels each).
@group(0) @binding(15) var node_texels: texture_2d<f32>;
// The G-buffer's emission (w: the material's index + 1) and the materials' exact models
// (photon_volume.wgsl `view_sample`, raster/shaders/common/exact_models.wgsl).
@group(0) @binding(17) var g_emission: texture_2d<f32>;
@group(0) @binding(18) var<storage, read> model_materials: array<ModelMaterial>;

fn sample_pixel(texel: vec2<u32>) -> vec2<i32> {
    let k = params.subsample;
    let dims = vec2<i32>(textureDimensions(g_position));
    return min(vec2<i32>(texel * k + k / 2u), dims - 1);
}

fn photon_texel(i: u32) -> vec2<i32> {
    return vec2<i32>(i32((i % PHOTON_ROW) * 4u), i32(i / PHOTON_ROW));
}

// Position, normal and radius of photon `i`: what the bounds and kernel tests need.
fn load_photon_shape(i: u32) -> VolumePhoton {
    let base = photon_texel(i);
    let a = textureLoad(photon_texels, base, 0);
    let d = textureLoad(photon_texels, base + vec2<i32>(3, 0), 0);
    var p: VolumePhoton;
    p.center = a.xyz;
    p.normal = d.xyz;
    // volume.wgsl's `volume_radius`.
    p.radius = min(d.w, params.r_max);
    return p;
}

// The rest of photon `i`: what shading needs.
fn load_photon_light(p: ptr<function, VolumePhoton>, i: u32) {
    let base = photon_texel(i);
    (*p).incident = textureLoad(photon_texels, base + vec2<i32>(1, 0), 0).xyz;
    (*p).power = textureLoad(photon_texels, base + vec2<i32>(2, 0), 0).xyz;
}

var<workgroup> wg_min: array<vec3<f32>, 64>;
var<workgroup> wg_max: array<vec3<f32>, 64>;

@compute @workgroup_size(8, 8)
fn tile_bounds(
    @builtin(workgroup_id) tile: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let texel = tile.xy * TILE + lid.xy;
    var lo = vec3<f32>(3.4e38);
    var hi = vec3<f32>(-3.4e38);
    if all(texel < params.low_size) {
        let pos = textureLoad(g_position, sample_pixel(texel), 0);
        if pos.w != 0.0 {
            lo = pos.xyz;
            hi = pos.xyz;
        }
    }
    wg_min[li] = lo;
    wg_max[li] = hi;
    workgroupBarrier();
    for (var s = 32u; s > 0u; s >>= 1u) {
        if li < s {
            wg_min[li] = min(wg_min[li], wg_min[li + s]);
            wg_max[li] = max(wg_max[li], wg_max[li + s]);
        }
        workgroupBarrier();
    }
    if li == 0u {
        let t = tile.y * params.tiles.x + tile.x;
        nodes[3u * t] = vec4<f32>(wg_min[0], 0.0);
        nodes[3u * t + 1u] = vec4<f32>(wg_max[0], 0.0);
    }
}

// Right-handed basis (t, b, n) with t × b = n (volume.wgsl's).
fn tangent_frame(n: vec3<f32>) -> mat3x3<f32> {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let bb = n.x * n.y * a;
    let t = vec3<f32>(1.0 + s * n.x * n.x * a, s * bb, -s * n.x);
    let b = vec3<f32>(bb, s + n.y * n.y * a, -n.y);
    return mat3x3<f32>(t, b, n);
}

// Tiles (x0, y0, x1, y1, inclusive) under the screen rectangle of the photon's ellipsoid
// box (volume.wgsl's `vs_quad`, widened by a texel); x0 > x1 when it covers none.
fn tile_range(p: VolumePhoton) -> vec4<i32> {
    let f = tangent_frame(p.normal);
    let r = p.radius;
    let center = params.view_proj * vec4<f32>(p.center, 1.0);
    let ex = params.view_proj * vec4<f32>(f[0] * r, 0.0);
    let ey = params.view_proj * vec4<f32>(f[1] * r, 0.0);
    let ez = params.view_proj * vec4<f32>(f[2] * (r * params.z_ratio), 0.0);
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
        let ndc = c.xy / max(c.w, 1e-6);
        lo = min(lo, ndc);
        hi = max(hi, ndc);
    }
    if w_max <= 0.0 {
        return vec4<i32>(1, 0, 0, 0);
    }
    if w_min <= 1e-6 {
        lo = vec2<f32>(-1.0);
        hi = vec2<f32>(1.0);
    }
    lo = clamp(lo, vec2<f32>(-1.0), vec2<f32>(1.0));
    hi = clamp(hi, vec2<f32>(-1.0), vec2<f32>(1.0));
    let size = vec2<f32>(params.low_size);
    // NDC -> texel coordinates (y down), one texel of slack on each side.
    let x0 = (lo.x * 0.5 + 0.5) * size.x - 1.0;
    let x1 = (hi.x * 0.5 + 0.5) * size.x + 1.0;
    let y0 = (0.5 - hi.y * 0.5) * size.y - 1.0;
    let y1 = (0.5 - lo.y * 0.5) * size.y + 1.0;
    let last = vec2<i32>(params.tiles) - 1;
    let t0 = clamp(vec2<i32>(floor(vec2<f32>(x0, y0) / f32(TILE))), vec2<i32>(0), last);
    let t1 = clamp(vec2<i32>(floor(vec2<f32>(x1, y1) / f32(TILE))), vec2<i32>(0), last);
    return vec4<i32>(t0, t1);
}

// Whether the photon's bounding sphere meets tile `t`'s box.
fn meets(p: VolumePhoton, t: u32) -> bool {
    let base = vec2<i32>(i32((t % NODE_ROW) * 3u), i32(t / NODE_ROW));
    let lo = textureLoad(node_texels, base, 0).xyz;
    let hi = textureLoad(node_texels, base + vec2<i32>(1, 0), 0).xyz;
    if any(lo > hi) {
        return false;
    }
    let d = p.center - clamp(p.center, lo, hi);
    let r = p.radius * max(1.0, params.z_ratio) * (1.0 + SLACK);
    return dot(d, d) <= r * r;
}

// The builtins of an invocation of a pass over a list (photons, jobs, nodes): 64-wide
// workgroups laid out over x, then rows of them over y.
struct ListInvocation {
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
}

// The list entry of invocation `inv`.
fn photon_index(inv: ListInvocation) -> u32 {
    return (inv.gid.y * inv.groups.x * 64u) + inv.gid.x;
}

// Photon `i` binned into the tiles its volume meets: counted there (`fill` false), or
// written into their lists at the cursors the scan left (`fill` true).
fn bin_photon(i: u32, fill: bool) {
    let p = load_photon_shape(i);
    let r = tile_range(p);
    for (var y = r.y; y <= r.w; y++) {
        for (var x = r.x; x <= r.z; x++) {
            let t = u32(y) * params.tiles.x + u32(x);
            if !meets(p, t) {
                continue;
            }
            if fill {
                let slot = atomicAdd(&cursor[t], 1u);
                if slot < params.capacity {
                    list[slot] = i;
                }
            } else {
                atomicAdd(&counts[t], 1u);
            }
        }
    }
}

@compute @workgroup_size(64)
fn bin_count(inv: ListInvocation) {
    let i = photon_index(inv);
    if i < params.photons {
        bin_photon(i, false);
    }
}

var<workgroup> wg_sum: array<u32, SCAN_THREADS>;

@compute @workgroup_size(256)
fn scan(@builtin(local_invocation_index) li: u32) {
    let n = params.slots;
    let per = (n + SCAN_THREADS - 1u) / SCAN_THREADS;
    let begin = min(li * per, n);
    let end = min(begin + per, n);
    var own = 0u;
    for (var t = begin; t < end; t++) {
        own += atomicLoad(&counts[t]);
    }
    wg_sum[li] = own;
    workgroupBarrier();
    // Inclusive Hillis-Steele scan of the threads' sums.
    for (var o = 1u; o < SCAN_THREADS; o <<= 1u) {
        var v = 0u;
        if li >= o {
            v = wg_sum[li - o];
        }
        workgroupBarrier();
        wg_sum[li] += v;
        workgroupBarrier();
    }
    var run = wg_sum[li] - own;
    for (var t = begin; t < end; t++) {
        offsets[t] = run;
        atomicStore(&cursor[t], run);
        run += atomicLoad(&counts[t]);
    }
    if li == SCAN_THREADS - 1u {
        atomicStore(&counts[n], wg_sum[li]);
    }
}

@compute @workgroup_size(64)
fn bin_fill(inv: ListInvocation) {
    let i = photon_index(inv);
    if i < params.photons {
        bin_photon(i, true);
    }
}

fn list_entry(j: u32) -> u32 {
    return textureLoad(list_texels, vec2<i32>(i32(j % LIST_ROW), i32(j / LIST_ROW)), 0).x;
}

// The estimate terms of list `slot`'s photons at sample `s`: `volume_term`, loading a
// photon's light only for samples inside its volume, summed in fixed point (the list's order
// varies between runs).
fn list_sum(slot: u32, s: ViewSample) -> vec3<f32> {
    var acc = fixed_zero();
    let begin = offsets[slot];
    let end = min(begin + atomicLoad(&counts[slot]), params.capacity);
    for (var j = begin; j < end; j++) {
        let i = list_entry(j);
        var p = load_photon_shape(i);
        let k = volume_kernel(p, s.position, params.z_ratio);
        if k.y != 0.0 && volume_normal_agrees(p, s.normal) {
            load_photon_light(&p, i);
            acc = fixed_add(acc, volume_shade(p, s, k.x));
        }
    }
    return fixed_value(acc);
}

@compute @workgroup_size(8, 8)
fn shade(
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
        sum = list_sum(tile.y * params.tiles.x + tile.x, s);
    }
    textureStore(low, vec2<i32>(texel), vec4<f32>(sum, 0.0));
}
