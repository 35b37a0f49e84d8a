// Shadow maps: depth only, one draw per spot light and per point-light cube face.

@group(0) @binding(0) var<uniform> view: View;

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return view.view_proj * vec4<f32>(position, 1.0);
}
