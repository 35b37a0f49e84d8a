//! Mitsuba 3's `plastic` (smooth coating) and `roughplastic` (rough coating): a diffuse base
//! under a dielectric coating of relative index η.
//!
//! For `wo`, `wi` above the surface, with `T(μ)` the coating's transmittance from outside
//! (smooth: 1 − F(μ, η); rough: the table of [`Coating::new`]) and `R` its internal diffuse
//! reflectance (smooth: Mitsuba's `fresnel_diffuse_reflectance(1/η)`; rough: the mean of the
//! rough internal reflectance over cosines, as Mitsuba computes it):
//! - diffuse: `ρ'/π · T(μi)·T(μo)/η²` with `ρ' = ρ/(1 − R)`, or `ρ/(1 − ρR)` (`nonlinear`);
//! - specular: `s·F(μ, η)` as a delta mirror (smooth), or `s·F(wi·h, η)·D·G/(4 μi μo)` with
//!   Mitsuba's separable Smith G (rough);
//! - lobe choice: specular with probability `Fw/(Fw + (1 − F)(1 − w))`, F = 1 − T(μo) and
//!   `w = mean(s)/(mean(ρ) + mean(s))`: Mitsuba's `specular_sampling_weight`.

use super::microfacet::{self, Distribution};
use super::{fresnel, BsdfSample, Lobe, Material};
use crate::sampling::{cosine_hemisphere, Rng};
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// Entries of the rough external transmittance table, at μ = i/(N − 1).
pub const TABLE: usize = 32;

/// The dielectric coating of a plastic material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coating {
    /// Relative index of refraction, coating over outside (> 1).
    pub eta: f32,
    /// Mitsuba's `nonlinear`: the base's internal scattering darkens its colour.
    pub nonlinear: bool,
    /// Internal diffuse reflectance R of the coating.
    pub internal: f32,
    /// Cosine-weighted mean external transmittance 2∫T(μ)μ dμ (for the albedo AOV).
    pub external_mean: f32,
    /// External transmittance T(μ) at μ = i/(TABLE − 1); unused when smooth.
    pub transmittance: [f32; TABLE],
    /// Whether the coating is rough (roughplastic).
    pub rough: bool,
}

impl Coating {
    /// The coating of index `eta` over a material of GGX/Beckmann roughness `alpha`
    /// (smooth below [`super::MIRROR_ROUGHNESS`]²: Mitsuba's plastic).
    pub fn new(eta: f32, nonlinear: bool, alpha: f32, dist: Distribution) -> Coating {
        let rough = alpha.sqrt() >= super::MIRROR_ROUGHNESS;
        let mut c = Coating {
            eta,
            nonlinear,
            internal: fresnel::diffuse_reflectance(1.0 / eta),
            external_mean: 1.0 - fresnel::diffuse_reflectance(eta),
            transmittance: [0.0; TABLE],
            rough,
        };
        if rough {
            // Mitsuba clamps α to 1e-4.
            let alpha = alpha.max(1e-4);
            for (i, t) in c.transmittance.iter_mut().enumerate() {
                let mu = (i as f32 / (TABLE - 1) as f32).max(1e-6);
                *t = rough_scatter(mu, eta, alpha, dist, false);
            }
            // Mitsuba: 2·mean over 64 cosines in linspace(1e-6, 1) of R_int(μ)·μ.
            let n = 64;
            let mut r = 0.0;
            for i in 0..n {
                let mu = (i as f32 / (n - 1) as f32).max(1e-6);
                r += rough_scatter(mu, 1.0 / eta, alpha, dist, true) * mu;
            }
            c.internal = 2.0 * r / n as f32;
            let mut e = 0.0;
            for (x, w) in fresnel::gauss_legendre_01() {
                e += 2.0 * x * w * c.t(x);
            }
            c.external_mean = e;
        }
        c
    }

    /// Transmittance T(μ) from outside into the coating.
    pub fn t(&self, mu: f32) -> f32 {
        if !self.rough {
            return 1.0 - fresnel::dielectric(mu, self.eta).0;
        }
        // Mitsuba's lerp_gather.
        let x = mu.clamp(0.0, 1.0) * (TABLE - 1) as f32;
        let i = (x as usize).min(TABLE - 2);
        let f = x - i as f32;
        self.transmittance[i] * (1.0 - f) + self.transmittance[i + 1] * f
    }

    /// The base's diffuse reflectance under the coating, ρ' (before the 1/η² and T terms).
    fn base(&self, rho: Vec3) -> Vec3 {
        let r = if self.nonlinear {
            rho * self.internal
        } else {
            Vec3::splat(self.internal)
        };
        rho / (Vec3::ONE - r)
    }
}

/// For light arriving at cosine `mu` on a rough boundary of relative index `eta`: the
/// fraction reflected (`reflect`) or transmitted, single-scattering with Smith masking:
/// `∫ VNDF(m) G1(w', m) F or (1 − F) dm` (Mitsuba's `eval_reflectance`/`eval_transmittance`),
/// integrated over the half vectors drawn by [`microfacet::sample_h`] (density D·cos θm),
/// 64×64 Gauss-Legendre nodes.
fn rough_scatter(mu: f32, eta: f32, alpha: f32, dist: Distribution, reflect: bool) -> f32 {
    let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let g1 = |w: Vec3| 1.0 / (1.0 + microfacet::lambda(w, alpha, dist));
    let g1_wi = g1(wi);
    let nodes: Vec<(f32, f32)> = fresnel::gauss_legendre_01()
        .flat_map(|(x, w)| [(0.5 * x, 0.5 * w), (0.5 + 0.5 * x, 0.5 * w)])
        .collect();
    let mut sum = 0.0f64;
    for &(u1, w1) in &nodes {
        for &(u2, w2) in &nodes {
            let m = microfacet::sample_h(Vec2::new(u1, u2), alpha, dist);
            let im = wi.dot(m);
            if im <= 0.0 || m.z <= 0.0 {
                continue;
            }
            // VNDF(m)/(D(m) cos θm) = G1(wi)·(wi·m)/(μ cos θm).
            let weight = g1_wi * im / (mu * m.z);
            let (f, cos_t) = fresnel::dielectric(im, eta);
            let v = if reflect {
                let wo = 2.0 * im * m - wi;
                if wo.z <= 0.0 {
                    continue;
                }
                g1(wo) * f
            } else {
                if f >= 1.0 {
                    continue;
                }
                let wt = -wi / eta + (im / eta - cos_t) * m;
                if wt.z >= 0.0 {
                    continue;
                }
                g1(wt) * (1.0 - f)
            };
            sum += (weight * v * w1 * w2) as f64;
        }
    }
    sum as f32
}

fn mean(v: Vec3) -> f32 {
    (v.x + v.y + v.z) / 3.0
}

/// Probability of choosing the specular lobe for viewing cosine `co`.
fn specular_probability(m: &Material, c: &Coating, co: f32) -> f32 {
    let (s, d) = (mean(m.specular), mean(m.diffuse));
    if s + d <= 0.0 {
        return 0.0;
    }
    let w = s / (s + d);
    let f = 1.0 - c.t(co);
    let ps = f * w;
    let pd = (1.0 - f) * (1.0 - w);
    if ps + pd <= 0.0 {
        return 0.0;
    }
    ps / (ps + pd)
}

/// f(wo, wi) for `wo`, `wi` above the surface (the non-delta part).
pub(super) fn eval(m: &Material, c: &Coating, wo: Vec3, wi: Vec3) -> Vec3 {
    let diffuse = c.base(m.diffuse) * (FRAC_1_PI * c.t(wo.z) * c.t(wi.z) / (c.eta * c.eta));
    if !c.rough || m.specular.max_element() <= 0.0 {
        return diffuse;
    }
    let h = (wo + wi).normalize();
    let alpha = m.alpha();
    let g = microfacet::g_separable(wo, wi, alpha, m.distribution);
    let dg = microfacet::d(h, alpha, m.distribution) * g / (4.0 * wo.z * wi.z);
    diffuse + m.specular * (fresnel::dielectric(wi.dot(h), c.eta).0 * dg)
}

/// Density of [`sample`] producing the non-delta `wi` (both above the surface).
pub(super) fn pdf(m: &Material, c: &Coating, wo: Vec3, wi: Vec3) -> f32 {
    let ps = specular_probability(m, c, wo.z);
    let mut pdf = (1.0 - ps) * wi.z * FRAC_1_PI;
    if c.rough && ps > 0.0 {
        let h = (wo + wi).normalize();
        pdf += ps * microfacet::pdf_reflected(wo, h, m.alpha(), m.distribution);
    }
    pdf
}

/// Importance-samples a direction for `wo_up` above the surface; `sign` flips the result
/// to the side of the original `wo`.
pub(super) fn sample(
    m: &Material,
    c: &Coating,
    wo_up: Vec3,
    sign: f32,
    rng: &mut Rng,
) -> Option<BsdfSample> {
    let ps = specular_probability(m, c, wo_up.z);
    let u = rng.next_f32();
    let u2 = rng.next_2d();
    let (wi_up, lobe) = if u < ps {
        if !c.rough {
            let f = fresnel::dielectric(wo_up.z, c.eta).0;
            return Some(BsdfSample {
                wi: Vec3::new(-wo_up.x, -wo_up.y, wo_up.z) * sign,
                weight: m.specular * f / ps,
                pdf: ps,
                lobe: Lobe::Mirror,
            });
        }
        let h = microfacet::sample_h(u2, m.alpha(), m.distribution);
        (2.0 * wo_up.dot(h) * h - wo_up, Lobe::Glossy)
    } else {
        (cosine_hemisphere(u2), Lobe::Diffuse)
    };
    if wi_up.z <= 0.0 {
        return None;
    }
    let pdf = pdf(m, c, wo_up, wi_up);
    if pdf <= 0.0 {
        return None;
    }
    Some(BsdfSample {
        wi: wi_up * sign,
        weight: eval(m, c, wo_up, wi_up) * wi_up.z / pdf,
        pdf,
        lobe,
    })
}

/// The smooth coating's mirror lobe for `wo_up` above the surface (see
/// [`Material::delta_lobes`]), flipped by `sign`.
pub(super) fn delta_lobe(m: &Material, c: &Coating, wo_up: Vec3, sign: f32) -> Option<BsdfSample> {
    if c.rough {
        return None;
    }
    let ps = specular_probability(m, c, wo_up.z);
    let weight = m.specular * fresnel::dielectric(wo_up.z, c.eta).0;
    (ps > 0.0 && weight.max_element() > 0.0).then_some(BsdfSample {
        wi: Vec3::new(-wo_up.x, -wo_up.y, wo_up.z) * sign,
        weight,
        pdf: ps,
        lobe: Lobe::Mirror,
    })
}

/// The albedo for viewing cosine `co`: specular `s·(1 − T)` (exact when smooth; the rough
/// lobe's is bounded by it) plus the diffuse `ρ'·T(μo)·2∫T μ dμ/η²`.
pub(super) fn scatter_probability(m: &Material, c: &Coating, co: f32) -> Vec3 {
    let t = c.t(co);
    m.specular * (1.0 - t) + c.base(m.diffuse) * (t * c.external_mean / (c.eta * c.eta))
}

/// The uber material the GPU passes shade in its place (they carry the uber's parameters
/// only): Schlick's Fresnel of the coating's mean reflectance (times `specular`) in place
/// of the dielectric term, and the diffuse albedo scaled so that the uber's Fresnel-coupled Lambert
/// term has the coated base's cosine-weighted mean albedo; the same roughness, as GGX.
pub(super) fn uber_equivalent(m: &Material, c: &Coating) -> Material {
    // Schlick's F0 whose cosine-weighted mean F0 + (1 − F0)/21 is the coating's external
    // reflectance 1 − 2∫Tμ (not ((η−1)/(η+1))², whose Schlick mean is 8% low at η = 1.49).
    let f0 = ((21.0 * (1.0 - c.external_mean) - 1.0) / 20.0).clamp(0.0, 1.0);
    let spec = m.specular * f0;
    let one_minus_avg = Vec3::ONE - fresnel::schlick_average(spec);
    // Coated diffuse albedo averaged over cosines: ρ'·(2∫Tμ)²/η²; the uber's: ρ''·(1 − F_avg).
    let coated = c.base(m.diffuse) * (c.external_mean * c.external_mean / (c.eta * c.eta));
    Material {
        diffuse: (coated / one_minus_avg).min(Vec3::ONE),
        specular: spec,
        fresnel: true,
        coating: None,
        conductor: None,
        ..*m
    }
}
