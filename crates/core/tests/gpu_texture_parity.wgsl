// Samples textures at given (texture, uv, lod) queries with `tex_sample` of texture.wgsl;
// run by common/kernel.wgsl.

struct Query {
    uv: vec2<f32>,
    lod: f32,
    texture: u32,
}

alias Item = Query;

fn evaluate(q: Query) -> vec4<f32> {
    return tex_sample(q.texture, q.uv, q.lod);
}
