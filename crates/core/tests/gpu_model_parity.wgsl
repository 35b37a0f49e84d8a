// Test kernel: evaluates Mitsuba's models of models.wgsl times |cos θi| for a table of
// cases. Prepended at load time: common/types.wgsl, common/bsdf.wgsl, common/models.wgsl.

struct Case {
    material: ModelMaterial,
    normal: vec3<f32>,
    wo: vec3<f32>,
    wi: vec3<f32>,
}

@group(0) @binding(0) var<storage, read> cases: array<Case>;
@group(0) @binding(1) var<storage, read_write> results: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&cases) {
        return;
    }
    let c = cases[i];
    let f = model_eval(c.material, c.normal, c.wo, c.wi);
    results[i] = vec4<f32>(f * abs(dot(c.normal, c.wi)), 0.0);
}
