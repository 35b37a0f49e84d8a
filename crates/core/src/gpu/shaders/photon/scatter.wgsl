// A photon's scattering on the GPU: the uber BSDF's sampling (`Material::sample_general`
// in crates/core/src/bsdf/mod.rs: diffuse, GGX glossy and mirror reflection, smooth
// dielectric reflection and refraction) and the Russian roulette of
// `photon::trace::scatter_local`, on the same random numbers in the same order: u (the
// lobe), u2 (the direction or the Fresnel choice), then u_rr. Directions are in the
// shading frame (+z = the shading normal), both pointing away from the surface. After
// `types.wgsl`, `bsdf.wgsl` and `common/sample.wgsl`. Not here: Mitsuba's exact models, rough and thin glass,
// textures (the GPU trace refuses scenes with them, `gpu::photon::unsupported`).

// No lobe: the photon is absorbed.
const LOBE_NONE: u32 = 0xffffffffu;

// A sampled direction with `weight` = f·|cos θi|/pdf (the delta lobe's weight for those);
// lobe LOBE_NONE: absorbed.
struct BsdfSample {
    wi: vec3<f32>,
    lobe: u32,
    weight: vec3<f32>,
    pdf: f32,
}

fn bsdf_absorbed() -> BsdfSample {
    return BsdfSample(vec3<f32>(0.0), LOBE_NONE, vec3<f32>(0.0), 0.0);
}

// The smooth glass lobe, picked with probability `pg`: Fresnel reflection (u below the
// reflectance) or refraction; the geometric side (`wo.z < 0`: inside) decides the index.
fn sample_glass(m: Material, wo: vec3<f32>, pg: f32, u: f32) -> BsdfSample {
    let flip = wo.z < 0.0;
    let s = select(1.0, -1.0, flip);
    let wo_up = wo * s;
    let tint = m.transmission * (vec3<f32>(1.0) - fresnel_spec(m, wo_up.z)) / pg;
    let eta = select(m.ior, 1.0 / m.ior, flip);
    let fr = fresnel_dielectric(wo_up.z, eta);
    if u < fr.x {
        return BsdfSample(vec3<f32>(-wo.x, -wo.y, wo.z), LOBE_GLASS_REFLECT, tint, pg * fr.x);
    }
    let wt_up = -wo_up / eta + vec3<f32>(0.0, 0.0, wo_up.z / eta - fr.y);
    return BsdfSample(normalize(wt_up * s), LOBE_GLASS_REFRACT, tint, pg * (1.0 - fr.x));
}

// `Material::sample` of the uber BSDF for local `wo` on random numbers `u`, `u2`.
fn bsdf_sample_local(m: Material, wo: vec3<f32>, u: f32, u2: vec2<f32>) -> BsdfSample {
    let s = select(1.0, -1.0, wo.z < 0.0);
    let wo_up = wo * s;
    let p = lobe_probabilities(m, wo_up.z);
    let mirror = m.roughness < MIRROR_ROUGHNESS;
    if u < p.x + p.y {
        if u < p.x && mirror {
            let w = fresnel_spec(m, wo_up.z) / p.x;
            return BsdfSample(vec3<f32>(-wo.x, -wo.y, wo.z), LOBE_MIRROR, w, p.x);
        }
        var wi_up: vec3<f32>;
        var lobe = LOBE_DIFFUSE;
        if u < p.x {
            let h = ggx_sample_h(u2, m.roughness * m.roughness);
            wi_up = 2.0 * dot(wo_up, h) * h - wo_up;
            lobe = LOBE_GLOSSY;
        } else {
            wi_up = cosine_hemisphere(u2);
        }
        if wi_up.z <= 0.0 {
            return bsdf_absorbed();
        }
        let wi = wi_up * s;
        let pdf = bsdf_pdf_local(m, wo, wi);
        if pdf <= 0.0 {
            return bsdf_absorbed();
        }
        let f = bsdf_eval(m, vec3<f32>(0.0, 0.0, 1.0), wo, wi);
        return BsdfSample(wi, lobe, f * wi_up.z / pdf, pdf);
    }
    if p.z <= 0.0 {
        return bsdf_absorbed();
    }
    return sample_glass(m, wo, p.z, u2.x);
}

// A photon's scattering that survived the roulette: direction (local), power Φ·w/q, q.
struct Scattered {
    wi: vec3<f32>,
    lobe: u32,
    power: vec3<f32>,
    q: f32,
}

// `photon::trace::scatter_local`: samples the BSDF at local `wo` (reflections stay on the
// side of the local geometric normal `ng`, refractions cross it), then Russian roulette
// with q = min(1, max(Φ·w)/max(Φ)) on `u.w`. lobe LOBE_NONE: absorbed.
fn photon_scatter(m: Material, wo: vec3<f32>, ng: vec3<f32>, power: vec3<f32>, u: vec4<f32>) -> Scattered {
    let none = Scattered(vec3<f32>(0.0), LOBE_NONE, vec3<f32>(0.0), 0.0);
    let bs = bsdf_sample_local(m, wo, u.x, u.yz);
    if bs.lobe == LOBE_NONE {
        return none;
    }
    let same_side = dot(bs.wi, ng) * dot(wo, ng) > 0.0;
    let crosses = bs.lobe == LOBE_GLASS_REFRACT;
    if same_side == crosses {
        return none;
    }
    let scattered = power * bs.weight;
    let q = min(max3(scattered) / max3(power), 1.0);
    // `!(q > 0)` also catches NaN.
    if !(q > 0.0) || u.w >= q {
        return none;
    }
    return Scattered(bs.wi, bs.lobe, scattered / q, q);
}

// `Material::stores_photons` for the uber BSDF: a non-delta lobe.
fn stores_photons(m: Material) -> bool {
    let glossy = max3(m.specular) > 0.0 && m.roughness >= MIRROR_ROUGHNESS;
    return max3(m.diffuse) > 0.0 || glossy;
}
