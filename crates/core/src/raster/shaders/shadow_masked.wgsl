// Shadow maps of scenes with alpha-masked materials: depth only, fragments cut out by the
// mask are discarded (finest level, as the CPU's any-hit test and the G-buffer).

@group(0) @binding(0) var<uniform> view: View;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) material: u32,
}

@vertex
fn vs_main(
    @location(0) position: vec3<f32>,
    @location(3) material: u32,
    @location(4) uv: vec2<f32>,
    @location(6) model0: vec4<f32>,
    @location(7) model1: vec4<f32>,
    @location(8) model2: vec4<f32>,
    @location(9) model3: vec4<f32>,
    @location(13) instance_material: u32,
) -> VertexOut {
    // The mesh vertex placed by its instance (as `scene_vertex`).
    let world = mat4x4<f32>(model0, model1, model2, model3) * vec4<f32>(position, 1.0);
    var o: VertexOut;
    o.clip = view.view_proj * vec4<f32>(world.xyz, 1.0);
    o.uv = uv;
    o.material = material + instance_material;
    return o;
}

@fragment
fn fs_main(in: VertexOut) {
    if alpha_cut(material_maps[in.material], in.uv) {
        discard;
    }
}
