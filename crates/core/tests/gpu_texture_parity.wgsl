// Samples textures at given (texture, uv, lod) queries with `tex_sample` of texture.wgsl.

struct Query {
    uv: vec2<f32>,
    lod: f32,
    texture: u32,
}

@group(0) @binding(0) var<storage, read> queries: array<Query>;
@group(0) @binding(1) var<storage, read_write> results: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&queries) {
        return;
    }
    let q = queries[i];
    results[i] = tex_sample(q.texture, q.uv, q.lod);
}
