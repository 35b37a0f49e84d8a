// Mitsuba 3's material models as the CPU evaluates them (crates/core/src/bsdf/): the coated
// plastics (`bsdf/coated.rs`), conductors of complex index (`fresnel::conductor`), Beckmann
// and GGX with Mitsuba's separable Smith masking (`bsdf/microfacet.rs`), and the uber BSDF
// with any distribution (`Material::eval_general`). Joined after bsdf.wgsl (PI, max3,
// schlick, MIRROR_ROUGHNESS). The record is `ModelMaterial` (raw.rs `ModelMaterialRaw`,
// one per scene material, beside the uber stand-in `Material`).

// `ModelMaterial.flags` (raw.rs `model_flags`).
const MODEL_FRESNEL: u32 = 1u;
const MODEL_BECKMANN: u32 = 2u;
const MODEL_COATED: u32 = 4u;
const MODEL_CONDUCTOR: u32 = 8u;
const MODEL_NONLINEAR: u32 = 16u;
const MODEL_ROUGH_COAT: u32 = 32u;
const MODEL_TEX_DIFFUSE: u32 = 64u;
// `coated::TABLE`: entries of the rough coating's transmittance table.
const COAT_TABLE: u32 = 32u;

// A material as the CPU's `bsdf::Material` holds it. `diffuse`, `specular`, `roughness`,
// `transmission`, `ior`: as the uber BSDF's (for a coating: ρ under it and the specular
// tint s; for a conductor: the tint of its Fresnel term). `conductor_*`: the complex index
// η + ik and 2∫F(μ)μ dμ. `coat_*`: relative index η, internal diffuse reflectance R,
// 2∫T(μ)μ dμ and the transmittance T(μ) at μ = i/31 (rough coatings; 4 entries a vec4).
// `stand_in_diffuse`: where a texture varies `diffuse` (MODEL_TEX_DIFFUSE), the untextured
// uber stand-in's diffuse albedo (`model_textured`).
struct ModelMaterial {
    diffuse: vec3<f32>,
    flags: u32,
    specular: vec3<f32>,
    roughness: f32,
    transmission: vec3<f32>,
    ior: f32,
    conductor_eta: vec3<f32>,
    coat_eta: f32,
    conductor_k: vec3<f32>,
    coat_internal: f32,
    conductor_average: vec3<f32>,
    coat_external_mean: f32,
    coat_t: array<vec4<f32>, 8>,
    stand_in_diffuse: vec3<f32>,
    _pad: u32,
}

// Record `r` at a sample whose uber stand-in has diffuse albedo `sample_diffuse` (the
// G-buffer's, an RSM's, a VPL record's: the untextured stand-in's times the texel, as
// `textured_material` applies a map): where a texture varies the diffuse reflectance, the
// texel is that over `r.stand_in_diffuse` (per channel; 0 where the stand-in's is) and the
// model's ρ is its own times the texel (`Scene::material_at` on the CPU).
// `raster::exact_models::textured_model` is the same on the CPU.
fn model_textured(r: ModelMaterial, sample_diffuse: vec3<f32>) -> ModelMaterial {
    if !has_flag(r, MODEL_TEX_DIFFUSE) {
        return r;
    }
    var out = r;
    let s = r.stand_in_diffuse;
    let texel = select(vec3<f32>(0.0), sample_diffuse / max(s, vec3<f32>(1e-30)), s > vec3<f32>(0.0));
    out.diffuse = r.diffuse * texel;
    return out;
}

fn has_flag(m: ModelMaterial, flag: u32) -> bool {
    return (m.flags & flag) != 0u;
}

// `fresnel::conductor`: the exact reflectance of a conductor of index eta + i·k.
fn fresnel_conductor(cos_i: f32, eta: vec3<f32>, k: vec3<f32>) -> vec3<f32> {
    let c = clamp(cos_i, 0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let t1 = eta * eta - k * k - vec3<f32>(s2);
    let a2b2 = sqrt(max(t1 * t1 + 4.0 * k * k * eta * eta, vec3<f32>(0.0)));
    let a = sqrt(max(0.5 * (a2b2 + t1), vec3<f32>(0.0)));
    let term1 = a2b2 + vec3<f32>(c2);
    let term2 = 2.0 * c * a;
    let rs = (term1 - term2) / (term1 + term2);
    let term3 = a2b2 * c2 + vec3<f32>(s4);
    let term4 = term2 * s2;
    let rp = rs * (term3 - term4) / (term3 + term4);
    return 0.5 * (rs + rp);
}

// `microfacet::d` for a half vector of cosine `c` to the normal.
fn mf_d(c: f32, alpha: f32, beckmann: bool) -> f32 {
    if c <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let c2 = c * c;
    if beckmann {
        let tan2 = max(1.0 - c2, 0.0) / c2;
        let v = exp(-tan2 / a2) / (PI * a2 * c2 * c2);
        return select(0.0, v, v * c > 1e-20);
    }
    let t = (1.0 - c2) + c2 * a2;
    return a2 / (PI * t * t);
}

// Smith's Λ (`microfacet::lambda`) of a direction of cosine `c` (> 0; a huge Λ at 0).
fn mf_lambda(c: f32, alpha: f32, beckmann: bool) -> f32 {
    let c2 = c * c;
    if c2 <= 0.0 {
        return 3.0e38;
    }
    let tan2 = max(1.0 - c2, 0.0) / c2;
    if beckmann {
        let t2 = alpha * alpha * tan2;
        if t2 <= 0.0 {
            return 0.0;
        }
        let a = 1.0 / sqrt(t2);
        if a >= 1.6 {
            return 0.0;
        }
        let g1 = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
        return 1.0 / g1 - 1.0;
    }
    return 0.5 * (sqrt(1.0 + alpha * alpha * tan2) - 1.0);
}

// The coating's transmittance T(μ) from outside (`Coating::t`).
fn coat_t(m: ModelMaterial, mu: f32) -> f32 {
    if !has_flag(m, MODEL_ROUGH_COAT) {
        return 1.0 - fresnel_dielectric(mu, m.coat_eta).x;
    }
    // Mitsuba's lerp_gather.
    let x = clamp(mu, 0.0, 1.0) * f32(COAT_TABLE - 1u);
    let i = min(u32(x), COAT_TABLE - 2u);
    let f = x - f32(i);
    let t = m.coat_t;
    let j = i + 1u;
    return t[i / 4u][i % 4u] * (1.0 - f) + t[j / 4u][j % 4u] * f;
}

// ρ' of the base under the coating (`Coating::base`).
fn coat_base(m: ModelMaterial) -> vec3<f32> {
    var r = vec3<f32>(m.coat_internal);
    if has_flag(m, MODEL_NONLINEAR) {
        r = m.diffuse * m.coat_internal;
    }
    return m.diffuse / (vec3<f32>(1.0) - r);
}

// `Material::fresnel_spec`: the specular lobe's Fresnel term.
fn model_fresnel(m: ModelMaterial, cos_t: f32) -> vec3<f32> {
    if has_flag(m, MODEL_CONDUCTOR) {
        return m.specular * fresnel_conductor(cos_t, m.conductor_eta, m.conductor_k);
    }
    if has_flag(m, MODEL_FRESNEL) {
        return schlick(m.specular, cos_t);
    }
    return m.specular;
}

// `Material::fresnel_avg`.
fn model_fresnel_avg(m: ModelMaterial) -> vec3<f32> {
    if has_flag(m, MODEL_CONDUCTOR) {
        return m.specular * m.conductor_average;
    }
    if has_flag(m, MODEL_FRESNEL) {
        return m.specular + (vec3<f32>(1.0) - m.specular) / 21.0;
    }
    return m.specular;
}

// f(wo, wi) of `Material::eval`, two-sided (in the hemisphere of `wo`); delta lobes are 0:
// the diffuse lobe plus the glossy one.
fn model_eval(m: ModelMaterial, n: vec3<f32>, wo_in: vec3<f32>, wi_in: vec3<f32>) -> vec3<f32> {
    return model_diffuse(m, n, wo_in, wi_in) + model_glossy(m, n, wo_in, wi_in);
}

// The diffuse lobe of `model_eval`: a coating's base (`coated::eval`'s first term), or
// Lambert with the Fresnel coupling of the uber BSDF (`Material::eval`).
fn model_diffuse(m: ModelMaterial, n: vec3<f32>, wo_in: vec3<f32>, wi_in: vec3<f32>) -> vec3<f32> {
    let co_raw = dot(n, wo_in);
    let ci_raw = dot(n, wi_in);
    if co_raw * ci_raw <= 0.0 {
        return vec3<f32>(0.0);
    }
    let co = abs(co_raw);
    let ci = abs(ci_raw);
    if has_flag(m, MODEL_COATED) {
        let eta = m.coat_eta;
        return coat_base(m) * (coat_t(m, co) * coat_t(m, ci) / (PI * eta * eta));
    }
    if max3(m.diffuse) <= 0.0 {
        return vec3<f32>(0.0);
    }
    let one_minus_avg = vec3<f32>(1.0) - model_fresnel_avg(m);
    let num = (vec3<f32>(1.0) - model_fresnel(m, co)) * (vec3<f32>(1.0) - model_fresnel(m, ci));
    let coupling = select(vec3<f32>(0.0), num / one_minus_avg, one_minus_avg > vec3<f32>(1e-6));
    return m.diffuse / PI * coupling;
}

// The glossy (microfacet) lobe of `model_eval`: a rough coating's dielectric reflection
// (`coated::eval`'s second term), or the specular lobe of a conductor (separable masking)
// or of the uber BSDF (height-correlated); 0 for a smooth one.
fn model_glossy(m: ModelMaterial, n: vec3<f32>, wo_in: vec3<f32>, wi_in: vec3<f32>) -> vec3<f32> {
    let co_raw = dot(n, wo_in);
    let ci_raw = dot(n, wi_in);
    if co_raw * ci_raw <= 0.0 || max3(m.specular) <= 0.0 {
        return vec3<f32>(0.0);
    }
    let coated = has_flag(m, MODEL_COATED);
    if (coated && !has_flag(m, MODEL_ROUGH_COAT)) || (!coated && m.roughness < MIRROR_ROUGHNESS) {
        return vec3<f32>(0.0);
    }
    let s = sign(co_raw);
    let co = co_raw * s;
    let ci = ci_raw * s;
    let h = normalize(wo_in * s + wi_in * s);
    let ih = dot(wi_in * s, h);
    let nh = dot(n, h);
    let alpha = m.roughness * m.roughness;
    let beckmann = has_flag(m, MODEL_BECKMANN);
    let lo = mf_lambda(co, alpha, beckmann);
    let li = mf_lambda(ci, alpha, beckmann);
    // Mitsuba's separable masking for coatings and conductors, the uber BSDF's
    // height-correlated G2.
    let separable = coated || has_flag(m, MODEL_CONDUCTOR);
    let g = select(1.0 / (1.0 + lo + li), 1.0 / ((1.0 + lo) * (1.0 + li)), separable);
    let dg = mf_d(nh, alpha, beckmann) * g / (4.0 * co * ci);
    if coated {
        return m.specular * (fresnel_dielectric(ih, m.coat_eta).x * dg);
    }
    return model_fresnel(m, ih) * dg;
}

// `Material::scatter_probability` for a viewing cosine `cos_o` (the albedo AOV).
fn model_scatter_probability(m: ModelMaterial, cos_o: f32) -> vec3<f32> {
    let c = abs(cos_o);
    if has_flag(m, MODEL_COATED) {
        let t = coat_t(m, c);
        let eta = m.coat_eta;
        return m.specular * (1.0 - t) + coat_base(m) * (t * m.coat_external_mean / (eta * eta));
    }
    let f = model_fresnel(m, c);
    return f + (vec3<f32>(1.0) - f) * (m.diffuse + m.transmission);
}
