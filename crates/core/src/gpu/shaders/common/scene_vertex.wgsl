// The scene's vertices as the passes that rasterize it read them (`gpu::raw::VertexRaw`),
// and what they carry to the fragment stage: world position, shading and geometric normal,
// material, texture coordinates and tangent.

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) geometric_normal: vec3<f32>,
    @location(3) material: u32,
    @location(4) uv: vec2<f32>,
    @location(5) tangent: vec4<f32>,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) geometric_normal: vec3<f32>,
    @location(3) @interpolate(flat) material: u32,
    @location(4) uv: vec2<f32>,
    @location(5) @interpolate(flat) tangent: vec4<f32>,
}

// Vertex `v` projected by `view_proj` (world -> clip), its attributes carried along.
fn scene_vertex(v: VertexIn, view_proj: mat4x4<f32>) -> VertexOut {
    var o: VertexOut;
    o.clip = view_proj * vec4<f32>(v.position, 1.0);
    o.world = v.position;
    o.normal = v.normal;
    o.geometric_normal = v.geometric_normal;
    o.material = v.material;
    o.uv = v.uv;
    o.tangent = v.tangent;
    return o;
}
