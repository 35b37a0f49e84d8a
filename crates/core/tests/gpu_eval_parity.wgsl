// Test kernel: evaluates a WGSL BSDF times |cos θi| for a table of cases. A template:
// `MATERIAL_T` and `EVAL_FN` are replaced at load time (the uber BSDF's `Material` and
// `bsdf_eval`, or models.wgsl's `ModelMaterial` and `model_eval`), and the sources those
// need (common/types.wgsl, common/bsdf.wgsl, common/models.wgsl) prepended; run by
// common/kernel.wgsl.

struct Case {
    material: MATERIAL_T,
    normal: vec3<f32>,
    wo: vec3<f32>,
    wi: vec3<f32>,
}

alias Item = Case;

fn evaluate(c: Case) -> vec4<f32> {
    let f = EVAL_FN(c.material, c.normal, c.wo, c.wi);
    return vec4<f32>(f * abs(dot(c.normal, c.wi)), 0.0);
}
