// A batch of `photon_scatter` calls on given random numbers (`gpu::photon::scatter_query`):
// the CPU/GPU parity test of the sampling formulas. After `scatter.wgsl`.

struct ScatterInput {
    material: Material,
    // Local directions and the power (w unused); the random numbers u, u2, u_rr.
    wo: vec4<f32>,
    ng: vec4<f32>,
    power: vec4<f32>,
    u: vec4<f32>,
}

@group(0) @binding(0) var<storage, read> scatter_inputs: array<ScatterInput>;
@group(0) @binding(1) var<storage, read_write> scatter_outputs: array<Scattered>;

@compute @workgroup_size(64)
fn scatter_query(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&scatter_inputs) {
        return;
    }
    let s = scatter_inputs[i];
    scatter_outputs[i] = photon_scatter(s.material, s.wo.xyz, s.ng.xyz, s.power.xyz, s.u);
}
