// The uber BSDF (see crates/core/src/bsdf/mod.rs, `Material::eval`): Lambert with Schlick
// coupling + GGX with height-correlated Smith masking. Delta lobes (mirror, glass) evaluate
// to zero. Directions point away from the surface; `n` is the unit shading normal.

const PI: f32 = 3.14159265358979;
const MIRROR_ROUGHNESS: f32 = 1e-3;

fn schlick(f0: vec3<f32>, cos_t: f32) -> vec3<f32> {
    let x = 1.0 - clamp(cos_t, 0.0, 1.0);
    let x2 = x * x;
    let m = x2 * x2 * x;
    return f0 + (vec3<f32>(1.0) - f0) * m;
}

fn fresnel_spec(m: Material, cos_t: f32) -> vec3<f32> {
    if m.fresnel != 0u {
        return schlick(m.specular, cos_t);
    }
    return m.specular;
}

fn fresnel_avg(m: Material) -> vec3<f32> {
    if m.fresnel != 0u {
        return m.specular + (vec3<f32>(1.0) - m.specular) / 21.0;
    }
    return m.specular;
}

fn ggx_d(cos_h: f32, alpha: f32) -> f32 {
    if cos_h <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    // (1 - c²) + c²·α²: stays positive when α² is below f32's epsilon (see microfacet.rs).
    let t = (1.0 - cos_h * cos_h) + cos_h * cos_h * a2;
    return a2 / (PI * t * t);
}

fn smith_lambda(cos_t: f32, alpha: f32) -> f32 {
    let c2 = cos_t * cos_t;
    let tan2 = max(1.0 - c2, 0.0) / c2;
    return 0.5 * (sqrt(1.0 + alpha * alpha * tan2) - 1.0);
}

fn max3(v: vec3<f32>) -> f32 {
    return max(v.x, max(v.y, v.z));
}

// f(wo, wi), two-sided: evaluated in the hemisphere of `wo`.
fn bsdf_eval(m: Material, n: vec3<f32>, wo_in: vec3<f32>, wi_in: vec3<f32>) -> vec3<f32> {
    let co_raw = dot(n, wo_in);
    let ci_raw = dot(n, wi_in);
    if co_raw * ci_raw <= 0.0 {
        return vec3<f32>(0.0);
    }
    let s = sign(co_raw);
    let wo = wo_in * s;
    let wi = wi_in * s;
    let co = co_raw * s;
    let ci = ci_raw * s;
    var f = vec3<f32>(0.0);
    if max3(m.diffuse) > 0.0 {
        let one_minus_avg = vec3<f32>(1.0) - fresnel_avg(m);
        let num = (vec3<f32>(1.0) - fresnel_spec(m, co)) * (vec3<f32>(1.0) - fresnel_spec(m, ci));
        let coupling = select(vec3<f32>(0.0), num / one_minus_avg, one_minus_avg > vec3<f32>(1e-6));
        f += m.diffuse / PI * coupling;
    }
    if max3(m.specular) > 0.0 && m.roughness >= MIRROR_ROUGHNESS {
        let h = normalize(wo + wi);
        let alpha = m.roughness * m.roughness;
        let g2 = 1.0 / (1.0 + smith_lambda(co, alpha) + smith_lambda(ci, alpha));
        let dg = ggx_d(dot(n, h), alpha) * g2 / (4.0 * co * ci);
        f += fresnel_spec(m, dot(wi, h)) * dg;
    }
    return f;
}

// The scatter probability (the albedo AOV), as `Material::scatter_probability`.
fn scatter_probability(m: Material, cos_o: f32) -> vec3<f32> {
    let f = fresnel_spec(m, abs(cos_o));
    return f + (vec3<f32>(1.0) - f) * (m.diffuse + m.transmission);
}

// `fresnel::dielectric`: (reflectance, cos θt) of a smooth boundary of relative index `eta`.
fn fresnel_dielectric(cos_in: f32, eta: f32) -> vec2<f32> {
    let cos_i = clamp(cos_in, 0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return vec2<f32>(1.0, 0.0);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return vec2<f32>(0.5 * (rs * rs + rp * rp), cos_t);
}
