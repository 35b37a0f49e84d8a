// Shadow maps: depth only, one draw per spot light and per point-light cube face.

@group(0) @binding(0) var<uniform> view: View;

@vertex
fn vs_main(
    @location(0) position: vec3<f32>,
    @location(6) model0: vec4<f32>,
    @location(7) model1: vec4<f32>,
    @location(8) model2: vec4<f32>,
    @location(9) model3: vec4<f32>,
) -> @builtin(position) vec4<f32> {
    // The mesh vertex placed by its instance's object -> world (as `scene_vertex`).
    let world = mat4x4<f32>(model0, model1, model2, model3) * vec4<f32>(position, 1.0);
    return view.view_proj * vec4<f32>(world.xyz, 1.0);
}
