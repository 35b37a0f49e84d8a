//! Mitsuba 3's `roughdielectric`: rough glass after Walter et al. 2007 ("Microfacet models
//! for refraction through rough surfaces"), single scattering, with Mitsuba's separable
//! Smith masking and its `specular_reflectance` (gi's `specular`) and
//! `specular_transmittance` (gi's `transmission`) multipliers.
//!
//! Directions are local (+z = the shading normal, the outside), both pointing away from the
//! surface: `wo` towards the viewer, `wi` towards the light. `η` is the material's `ior`
//! (inside over outside) and `η'` the index on `wi`'s side over `wo`'s. With the half
//! vector `m = ±normalize(wo + η'·wi)` (+z side), `F = F(wo·m)` and `G = G1(wo)·G1(wi)`:
//! - reflection: `s·F·D·G / (4 |cos o| |cos i|)`;
//! - transmission, radiance: `t·(1 − F)·D·G·|wo·m||wi·m| / (|cos o||cos i| (wo·m + η' wi·m)²)`.
//!
//! Transmission is not symmetric: radiance is compressed by `η'²` crossing into a denser
//! medium. [`eval`] and [`sample`] are the radiance BSDF (camera paths: `wo` towards the
//! camera); a particle carried from the light (photons) scatters with the adjoint,
//! `f*(wo, wi) = f(wi, wo) = η'²·f(wo, wi)`, which [`importance_factor`] gives.
//!
//! Sampling draws `m` with density `D(m)·cos θm` ([`microfacet::sample_h`]), then reflects
//! with probability `F(wo·m)` and refracts otherwise (Mitsuba's lobe choice). Mitsuba's
//! default `sample_visible` draws visible normals instead: the same expectation, other noise.

use super::microfacet::{self, Distribution};
use super::{fresnel, BsdfSample, Lobe, Material};
use crate::sampling::Rng;
use glam::Vec3;

/// Mitsuba's smallest roughness: α is clamped to it (the lobe never becomes a delta).
pub const MIN_ALPHA: f32 = 1e-4;

/// The microfacet roughness α of `m` (gi's `roughness` squared, clamped as Mitsuba does).
fn alpha(m: &Material) -> f32 {
    m.alpha().max(MIN_ALPHA)
}

/// The pair turned so that `wo` is on the outside (+z), and `η'` (index on `wi`'s side over
/// `wo`'s, for a crossing; 1 for a reflection). `None` at grazing `wo` or `wi`.
fn oriented(m: &Material, wo: Vec3, wi: Vec3) -> Option<(Vec3, Vec3, f32, bool)> {
    if wo.z == 0.0 || wi.z == 0.0 {
        return None;
    }
    let (wo, wi, eta) = if wo.z > 0.0 {
        (wo, wi, m.ior)
    } else {
        (-wo, -wi, 1.0 / m.ior)
    };
    let reflect = wi.z > 0.0;
    Some((wo, wi, eta, reflect))
}

/// The half vector of an oriented pair (+z side), or `None` where it is undefined (a
/// refraction towards the same side as `wo` of the microsurface).
fn half_vector(wo: Vec3, wi: Vec3, eta: f32, reflect: bool) -> Option<Vec3> {
    let h = if reflect { wo + wi } else { wo + eta * wi };
    let len = h.length();
    if len <= 1e-12 {
        return None;
    }
    let h = h / len * h.z.signum();
    // Each direction on the side of the microfacet its macro side says (Mitsuba's G1 test).
    (wo.dot(h) > 0.0 && wi.dot(h) * wi.z > 0.0).then_some(h)
}

/// Separable Smith masking `G1(wo)·G1(wi)`.
fn masking(wo: Vec3, wi: Vec3, alpha: f32, dist: Distribution) -> f32 {
    1.0 / ((1.0 + microfacet::lambda(wo, alpha, dist))
        * (1.0 + microfacet::lambda(wi, alpha, dist)))
}

/// The radiance BSDF f(wo, wi) (not multiplied by a cosine), both sides.
pub fn eval(m: &Material, wo: Vec3, wi: Vec3) -> Vec3 {
    let Some((wo, wi, eta, reflect)) = oriented(m, wo, wi) else {
        return Vec3::ZERO;
    };
    let Some(h) = half_vector(wo, wi, eta, reflect) else {
        return Vec3::ZERO;
    };
    let (a, dist) = (alpha(m), m.distribution);
    let dg = microfacet::d(h, a, dist) * masking(wo, wi, a, dist);
    let (oh, ih) = (wo.dot(h), wi.dot(h));
    let f = fresnel::dielectric(oh, eta).0;
    let cos = (wo.z * wi.z).abs();
    if reflect {
        m.specular * (f * dg / (4.0 * cos))
    } else {
        let denom = oh + eta * ih;
        m.transmission * ((1.0 - f) * dg * (oh * ih).abs() / (cos * denom * denom))
    }
}

/// Density over solid angle of [`sample`] producing `wi`.
pub fn pdf(m: &Material, wo: Vec3, wi: Vec3) -> f32 {
    let Some((wo, wi, eta, reflect)) = oriented(m, wo, wi) else {
        return 0.0;
    };
    let Some(h) = half_vector(wo, wi, eta, reflect) else {
        return 0.0;
    };
    let (oh, ih) = (wo.dot(h), wi.dot(h));
    let f = fresnel::dielectric(oh, eta).0;
    let p_h = microfacet::d(h, alpha(m), m.distribution) * h.z;
    if reflect {
        p_h * f / (4.0 * ih.abs())
    } else {
        let denom = oh + eta * ih;
        p_h * (1.0 - f) * eta * eta * ih.abs() / (denom * denom)
    }
}

/// Draws `wi` for `wo`: a reflection ([`Lobe::Glossy`]) or a refraction
/// ([`Lobe::RoughRefract`]), weighted `f·|cos θi|/pdf` (radiance).
pub fn sample(m: &Material, wo: Vec3, rng: &mut Rng) -> Option<BsdfSample> {
    let u = rng.next_f32();
    let u2 = rng.next_2d();
    if wo.z == 0.0 {
        return None;
    }
    let sign = wo.z.signum();
    let (wo_up, eta) = (wo * sign, if sign > 0.0 { m.ior } else { 1.0 / m.ior });
    let h = microfacet::sample_h(u2, alpha(m), m.distribution);
    let oh = wo_up.dot(h);
    if oh <= 0.0 {
        return None;
    }
    let (f, cos_t) = fresnel::dielectric(oh, eta);
    let (wi_up, lobe) = if u < f {
        (2.0 * oh * h - wo_up, Lobe::Glossy)
    } else {
        (-wo_up / eta + (oh / eta - cos_t) * h, Lobe::RoughRefract)
    };
    // A reflection below the horizon or a refraction above it is absorbed (its half
    // vector is not the drawn one; `pdf` counts it under the other lobe).
    if (lobe == Lobe::Glossy) != (wi_up.z > 0.0) || wi_up.z == 0.0 {
        return None;
    }
    let wi = (wi_up * sign).normalize();
    let pdf = pdf(m, wo, wi);
    if !(pdf.is_finite() && pdf > 0.0) {
        return None;
    }
    let weight = eval(m, wo, wi) * wi.z.abs() / pdf;
    Some(BsdfSample {
        wi,
        weight,
        pdf,
        lobe,
    })
}

/// The factor turning a radiance weight into the adjoint's (importance transport) for a
/// sample from `wo` to `wi`: `η'²` across the boundary, 1 for a reflection.
pub fn importance_factor(m: &Material, wo: Vec3, wi: Vec3) -> f32 {
    if wo.z * wi.z >= 0.0 {
        return 1.0;
    }
    let eta = if wo.z > 0.0 { m.ior } else { 1.0 / m.ior };
    eta * eta
}

/// The scatter probability ρs = ∫ f cos dωi for `wo`, bounded by the reflectance and
/// transmittance multipliers (the microfacet lobes' single-scattering loss is left out).
pub fn scatter_probability(m: &Material, wo: Vec3) -> Vec3 {
    let eta = if wo.z >= 0.0 { m.ior } else { 1.0 / m.ior };
    let f = fresnel::dielectric(wo.z.abs(), eta).0;
    m.specular * f + m.transmission * (1.0 - f)
}
