// Test kernel: evaluates a WGSL BSDF times |cos θi| for a table of cases. A template:
// `MATERIAL_T` and `EVAL_FN` are replaced at load time (the uber BSDF's `Material` and
// `bsdf_eval`, or models.wgsl's `ModelMaterial` and `model_eval`), and the sources those
// need (common/types.wgsl, common/bsdf.wgsl, common/models.wgsl) prepended.

struct Case {
    material: MATERIAL_T,
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
    let f = EVAL_FN(c.material, c.normal, c.wo, c.wi);
    results[i] = vec4<f32>(f * abs(dot(c.normal, c.wi)), 0.0);
}
