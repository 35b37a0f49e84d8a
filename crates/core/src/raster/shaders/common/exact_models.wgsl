// Mitsuba's exact material models (gpu/shaders/common/models.wgsl) in the deferred direct
// light (issue 42): the G-buffer holds each sample's material index + 1 in `emission.w`,
// and group 1 binds one `ModelMaterial` record per scene material (raster/exact_models.rs:
// flags 0 where the uber parameters the G-buffer holds are exact already, or where
// specular or roughness textures vary them per pixel; a diffuse texture's texel is the
// G-buffer's diffuse over the record's untextured stand-in's: `model_textured`). `exact_load` reads the sample's record once per shading
// point; the `exact_*` functions evaluate it in place of the uber BSDF where it is one of
// Mitsuba's models (a coating, a conductor of complex index, Beckmann's distribution), and
// fall back to the uber evaluation of the G-buffer's `Material` elsewhere. The
// diffuse/glossy split is the model's (`model_diffuse`, `model_glossy`): the coating's base
// and its dielectric reflection, as the ratio estimators of direct_shade.wgsl need it.

// `model_materials: array<ModelMaterial>`, the records, is declared by each pass at its own
// binding (exact_models_direct.wgsl for the direct passes; the estimators' shaders).

// The flags of a record the uber BSDF does not render exactly.
const EXACT_MODEL_FLAGS: u32 = MODEL_BECKMANN | MODEL_COATED | MODEL_CONDUCTOR;

// The shading point's record, where `exact_on`.
var<private> exact_on: bool;
var<private> exact_model: ModelMaterial;

// Reads the record of a sample's material: `index` its index + 1 (a G-buffer's `emission.w`; 0: none),
// `diffuse` its uber stand-in's (textured) diffuse albedo, which gives a diffuse map's
// texel back (models.wgsl `model_textured`).
fn exact_load(index: f32, diffuse: vec3<f32>) {
    exact_on = false;
    let i = u32(max(index, 0.0) + 0.5);
    if i == 0u || i > arrayLength(&model_materials) {
        return;
    }
    // The flags first: one word a sample where the material is the uber BSDF's.
    if (model_materials[i - 1u].flags & EXACT_MODEL_FLAGS) == 0u {
        return;
    }
    exact_model = model_textured(model_materials[i - 1u], diffuse);
    exact_on = true;
}

// f(wo, wi) of the shading point's material (`bsdf_eval` of `m` unless exact).
fn exact_eval(m: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if exact_on {
        return model_eval(exact_model, n, wo, wi);
    }
    return bsdf_eval(m, n, wo, wi);
}

// The glossy lobe alone: `bsdf_eval` of `glossy` (the uber material with its diffuse
// albedo zeroed) unless exact.
fn exact_glossy(glossy: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if exact_on {
        return model_glossy(exact_model, n, wo, wi);
    }
    return bsdf_eval(glossy, n, wo, wi);
}

// The scatter probability towards viewing cosine `cos_o`: `uber` unless exact.
fn exact_scatter(uber: vec3<f32>, cos_o: f32) -> vec3<f32> {
    if !exact_on {
        return uber;
    }
    return model_scatter_probability(exact_model, cos_o);
}

// A smooth material's mirror reflectance at viewing cosine `cos_o`: `uber` (the uber's
// Fresnel term) unless exact; a smooth coating's dielectric Fresnel term times its
// specular tint, a conductor's complex-index Fresnel term else.
fn exact_mirror(uber: vec3<f32>, cos_o: f32) -> vec3<f32> {
    if !exact_on {
        return uber;
    }
    if has_flag(exact_model, MODEL_COATED) {
        return exact_model.specular * fresnel_dielectric(cos_o, exact_model.coat_eta).x;
    }
    return model_fresnel(exact_model, cos_o);
}

// The glossy lobe widened for a light sample of angular radius² `spread2`: `bsdf_eval` of
// `wide` (the uber lobe widened by emitter_tree.wgsl `widened`) unless exact; the
// model's lobe widened the same way (α² + spread2/4, mirrors kept) else.
fn exact_widened_glossy(wide: Material, spread2: f32, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if !exact_on {
        return bsdf_eval(wide, n, wo, wi);
    }
    var r = exact_model;
    if r.roughness >= MIRROR_ROUGHNESS {
        let a = r.roughness * r.roughness;
        r.roughness = sqrt(sqrt(a * a + 0.25 * spread2));
    }
    return model_glossy(r, n, wo, wi);
}

// The diffuse lobe's ratio of exitant radiance to the irradiance of a constant environment
// at viewing cosine `n·wo`: `uber` (the uber BSDF's ρ/π·(1 − F(μo))) unless exact; a
// coating's ρ'·T(μo)·2∫T(μ)μ dμ/(π·η²), the uber form with the model's Fresnel terms else.
fn exact_env_diffuse(uber: vec3<f32>, n: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if !exact_on {
        return uber;
    }
    let m = exact_model;
    let co = abs(dot(n, wo));
    if has_flag(m, MODEL_COATED) {
        let eta = m.coat_eta;
        return coat_base(m) * (coat_t(m, co) * m.coat_external_mean / (PI * eta * eta));
    }
    let one_minus_avg = vec3<f32>(1.0) - model_fresnel_avg(m);
    let coupling = select(vec3<f32>(0.0), vec3<f32>(1.0) - model_fresnel(m, co), one_minus_avg > vec3<f32>(1e-6));
    return m.diffuse / PI * coupling;
}

// One tap of env_glossy.wgsl's quadrature of the glossy lobe: `uber` (its weight
// f·cos θi/pdf for the uber lobe) unless exact; the model's glossy lobe over the density of
// the GGX half vector the tap drew (D(h)·cos θh/(4·wo·h), roughness α) else.
fn exact_glossy_tap(uber: vec3<f32>, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, alpha: f32) -> vec3<f32> {
    if !exact_on {
        return uber;
    }
    let h = normalize(wo + wi);
    let ch = dot(n, h);
    let pdf = ggx_d(ch, alpha) * ch / (4.0 * dot(wo, h));
    if !(pdf > 0.0) {
        return vec3<f32>(0.0);
    }
    return model_glossy(exact_model, n, wo, wi) * (dot(n, wi) / pdf);
}
