// Edge-adaptive supersampling of the direct light (see raster/edges.rs).
//
// `find_edges` lists the pixels whose 3×3 neighbourhood of pixel-centre G-buffer samples
// crosses a discontinuity (coverage, a point off the centre's tangent plane, a normal or
// material change): only there can the box-filtered mean of the sub-pixel samples differ
// from the centre sample by more than the curvature of smooth shading. `store_samples`
// keeps each sub-pixel sample's G-buffer values at the listed pixels (one dispatch per
// sample, after its G-buffer pass), and `shade_edges` writes the mean of their direct light
// over the centre's, so that lights can change without re-rasterizing the samples.

struct EdgeParams {
    // The sub-pixel sample that `store_samples` keeps.
    sample: u32,
    samples: u32,
    // Listed pixels the buffers hold; more are counted but not listed.
    capacity: u32,
    width: u32,
    height: u32,
}

@group(2) @binding(0) var<storage, read_write> edges: array<u32>;
@group(2) @binding(1) var<storage, read_write> edge_count: array<atomic<u32>>;
// Per sample and listed pixel, four texels: position, normals, packed f16 materials,
// emission.
@group(2) @binding(2) var<storage, read_write> cache: array<vec4<u32>>;
@group(2) @binding(3) var accum_out: texture_storage_2d<rgba32float, write>;
@group(2) @binding(4) var<storage, read_write> args: array<u32>;
@group(2) @binding(5) var<uniform> params: EdgeParams;

// Whether the centre samples `c` (geometric and shading normals `ng`, `ns`) and `n` of two
// neighbouring pixels lie on different surfaces or on either side of a crease or material
// boundary.
fn differs(c: GSample, ng: vec3<f32>, ns: vec3<f32>, n: GSample) -> bool {
    if (c.position.w > 0.0) != (n.position.w > 0.0) {
        return true;
    }
    if c.position.w == 0.0 {
        return false;
    }
    // Off the tangent plane: another surface (or a step).
    if !on_plane(c.position.xyz, ng, n.position) {
        return true;
    }
    if dot(ng, oct_decode(n.normals.zw)) < 0.95 || dot(ns, oct_decode(n.normals.xy)) < 0.95 {
        return true;
    }
    let dm = max(abs(c.diffuse - n.diffuse), abs(c.specular - n.specular));
    if max(max(dm.x, dm.y), max(dm.z, dm.w)) > 0.1 {
        return true;
    }
    // An emitter's edge (emission differing by more than 10%).
    let de = abs(c.emission.xyz - n.emission.xyz);
    return max3(de) > 0.1 * max(max3(c.emission.xyz), max3(n.emission.xyz));
}

@compute @workgroup_size(8, 8)
fn find_edges(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.width || id.y >= params.height {
        return;
    }
    let px = vec2<i32>(id.xy);
    let c = load_sample(px);
    let ng = oct_decode(c.normals.zw);
    let ns = oct_decode(c.normals.xy);
    let size = vec2<i32>(i32(params.width), i32(params.height));
    var edge = false;
    for (var dy = -1; dy <= 1 && !edge; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let q = px + vec2<i32>(dx, dy);
            if (dx == 0 && dy == 0) || any(q < vec2<i32>(0)) || any(q >= size) {
                continue;
            }
            if differs(c, ng, ns, load_sample(q)) {
                edge = true;
                break;
            }
        }
    }
    if edge {
        let slot = atomicAdd(&edge_count[0], 1u);
        if slot < params.capacity {
            edges[slot] = id.y * params.width + id.x;
        }
    }
}

fn listed() -> u32 {
    return min(atomicLoad(&edge_count[0]), params.capacity);
}

// The indirect dispatch arguments of the passes over the listed pixels, then (from word 4)
// the indirect draw arguments of the edge mask: one point per listed pixel.
@compute @workgroup_size(1)
fn edge_args() {
    args[0] = (listed() + 63u) / 64u;
    args[1] = 1u;
    args[2] = 1u;
    args[4] = listed();
    args[5] = 1u;
    args[6] = 0u;
    args[7] = 0u;
}

fn pixel_of(slot: u32) -> vec2<i32> {
    let i = edges[slot];
    return vec2<i32>(i32(i % params.width), i32(i / params.width));
}

@compute @workgroup_size(64)
fn store_samples(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= listed() {
        return;
    }
    let g = load_sample(pixel_of(id.x));
    let base = (params.sample * params.capacity + id.x) * 4u;
    cache[base] = bitcast<vec4<u32>>(g.position);
    cache[base + 1u] = bitcast<vec4<u32>>(g.normals);
    // The diffuse and specular targets are f16: packing them loses nothing.
    cache[base + 2u] = vec4<u32>(
        pack2x16float(g.diffuse.xy),
        pack2x16float(g.diffuse.zw),
        pack2x16float(g.specular.xy),
        pack2x16float(g.specular.zw),
    );
    // Kept only where some material emits (else it is zero and `shade_edges` reads none).
    if EMISSION {
        cache[base + 3u] = bitcast<vec4<u32>>(g.emission);
    }
}

@compute @workgroup_size(64)
fn shade_edges(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= listed() {
        return;
    }
    var sum = vec3<f32>(0.0);
    // Samples without a surface see the environment along the pixel centre's ray.
    var ray = vec3<f32>(0.0);
    if BACKGROUND {
        ray = view_ray(vec2<f32>(pixel_of(id.x)) + 0.5);
    }
    for (var s = 0u; s < params.samples; s++) {
        let base = (s * params.capacity + id.x) * 4u;
        let m = cache[base + 2u];
        var g: GSample;
        g.position = bitcast<vec4<f32>>(cache[base]);
        g.normals = bitcast<vec4<f32>>(cache[base + 1u]);
        g.diffuse = vec4<f32>(unpack2x16float(m.x), unpack2x16float(m.y));
        g.specular = vec4<f32>(unpack2x16float(m.z), unpack2x16float(m.w));
        if EMISSION {
            g.emission = bitcast<vec4<f32>>(cache[base + 3u]);
        }
        g.ray = ray;
        sky_edge_sample(s);
        sum += shade(g);
    }
    // Equal weights: the box filter of the full supersampling (direct.wgsl `fs_main`).
    textureStore(accum_out, pixel_of(id.x), vec4<f32>(sum / f32(params.samples), 1.0));
}
