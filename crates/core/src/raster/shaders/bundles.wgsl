// Builds one global ray bundle: every fragment of the scene under the bundle's parallel
// projection is prepended to its pixel's list (Yang et al. 2010) with one atomic counter and
// an atomic exchange of the head pointer. Fragments beyond the buffer's capacity are
// dropped (and counted: the counter keeps running). No depth test, no culling.

@group(0) @binding(0) var<uniform> bundle: BundleView;
@group(0) @binding(1) var<storage, read> materials: array<Material>;
@group(0) @binding(2) var<storage, read_write> heads: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> nodes: array<Node>;
@group(0) @binding(4) var<storage, read_write> counter: atomic<u32>;

@vertex
fn vs_main(v: VertexIn, i: InstanceIn) -> VertexOut {
    return scene_vertex(v, i, bundle.view_proj);
}

@fragment
fn fs_main(in: VertexOut) {
    insert(in, false);
}

@fragment
fn fs_textured(in: VertexOut) {
    insert(in, true);
}

@fragment
fn fs_masked(in: VertexOut) {
    if alpha_cut(material_maps[in.material], in.uv) {
        discard;
    }
    insert(in, true);
}

fn insert(in: VertexOut, textured: bool) {
    let duvdx = dpdx(in.uv);
    let duvdy = dpdy(in.uv);
    let ng = in.geometric_normal;
    let surface = fragment_surface(in, materials[in.material], textured, duvdx, duvdy);
    let ns = surface.ns;
    let m = surface.m;
    let slot = atomicAdd(&counter, 1u);
    if slot >= bundle.capacity {
        return;
    }
    let px = vec2<u32>(in.clip.xy);
    let head = bundle.index * bundle.res * bundle.res + px.y * bundle.res + px.x;
    var node: Node;
    node.x = in.world.x;
    node.y = in.world.y;
    node.z = in.world.z;
    node.ns = pack2x16snorm(oct_encode(ns));
    node.ng = pack2x16snorm(oct_encode(ng));
    node.m0 = pack2x16float(m.diffuse.xy);
    // A one-sided material's roughness is stored negative (at least the smallest normal
    // half float, so that its sign survives): bidir.wgsl's `node_material` reads it back.
    let one_sided = (m.two_sided & MATERIAL_ONE_SIDED) != 0u;
    let roughness = select(m.roughness, -max(m.roughness, 6.2e-5), one_sided);
    node.m1 = pack2x16float(vec2<f32>(m.diffuse.z, roughness));
    node.m2 = pack2x16float(m.specular.xy);
    // Specular b (16-bit float) and, above it, the material word: the Fresnel flag and the
    // material's index + 1 for bidir_models.wgsl's exact models (0 past 2^15 − 1 materials:
    // the uber stand-in then).
    let index = select(0u, in.material + 1u, in.material + 1u < 32768u);
    let word = m.fresnel | (index << 1u);
    node.m3 = (pack2x16float(vec2<f32>(m.specular.z, 0.0)) & 0xffffu) | (word << 16u);
    node.next = atomicExchange(&heads[head], slot + 1u);
    nodes[slot] = node;
}
