//! Microfacet distributions (GGX/Trowbridge-Reitz and Beckmann) with Smith masking, in the
//! local frame where the normal is +z. α is the distribution's roughness (gi's
//! `roughness` squared, Mitsuba's `alpha`).
//!
//! Masking: Λ of GGX is exact; Beckmann's G1 is the rational approximation Mitsuba 3 (and
//! Walter et al. 2007) use, Λ = 1/G1 − 1. The uber BSDF combines the two directions
//! height-correlated, G2 = 1/(1 + Λo + Λi); Mitsuba's models are separable, G1(o)·G1(i).

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Which normal distribution a rough lobe uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Distribution {
    #[default]
    Ggx,
    Beckmann,
}

/// Normal distribution D(h) for roughness `alpha`.
#[inline]
pub fn d(h: Vec3, alpha: f32, dist: Distribution) -> f32 {
    if h.z <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let c2 = h.z * h.z;
    match dist {
        Distribution::Ggx => {
            // (1 − c²) + c²·α², not c²·(α² − 1) + 1: for α² below f32's epsilon, α² − 1
            // rounds to −1 and t to 0 at h = n, making D infinite (and radiance NaN).
            let t = (1.0 - c2) + c2 * a2;
            a2 / (PI * t * t)
        }
        Distribution::Beckmann => {
            let tan2 = (1.0 - c2).max(0.0) / c2;
            let v = (-tan2 / a2).exp() / (PI * a2 * c2 * c2);
            if v * h.z > 1e-20 {
                v
            } else {
                0.0
            }
        }
    }
}

/// Smith's Λ of direction `w`.
#[inline]
pub fn lambda(w: Vec3, alpha: f32, dist: Distribution) -> f32 {
    let c2 = w.z * w.z;
    if c2 <= 0.0 {
        return f32::INFINITY;
    }
    let tan2 = (1.0 - c2).max(0.0) / c2;
    match dist {
        Distribution::Ggx => 0.5 * ((1.0 + alpha * alpha * tan2).sqrt() - 1.0),
        Distribution::Beckmann => {
            let t2 = alpha * alpha * tan2;
            if t2 <= 0.0 {
                return 0.0;
            }
            let a = 1.0 / t2.sqrt();
            if a >= 1.6 {
                return 0.0;
            }
            let g1 = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
            1.0 / g1 - 1.0
        }
    }
}

/// Height-correlated masking-shadowing G2(wo, wi) (the uber BSDF's).
#[inline]
pub fn g2(wo: Vec3, wi: Vec3, alpha: f32, dist: Distribution) -> f32 {
    1.0 / (1.0 + lambda(wo, alpha, dist) + lambda(wi, alpha, dist))
}

/// Separable masking-shadowing G1(wo)·G1(wi) (Mitsuba's). Both directions above the
/// surface and on the front of `h` (the callers reflect about `h`, so this holds).
#[inline]
pub fn g_separable(wo: Vec3, wi: Vec3, alpha: f32, dist: Distribution) -> f32 {
    1.0 / ((1.0 + lambda(wo, alpha, dist)) * (1.0 + lambda(wi, alpha, dist)))
}

/// Samples a half vector with density D(h)·cos(θh).
#[inline]
pub fn sample_h(u: Vec2, alpha: f32, dist: Distribution) -> Vec3 {
    let a2 = alpha * alpha;
    let cos2 = match dist {
        Distribution::Ggx => (1.0 - u.x) / (1.0 + (a2 - 1.0) * u.x),
        // tan²θ = −α²·ln(1 − u): the inverse of Beckmann's radial CDF.
        Distribution::Beckmann => 1.0 / (1.0 - a2 * (1.0 - u.x).max(1e-30).ln()),
    };
    let cos_t = cos2.max(0.0).sqrt();
    let sin_t = (1.0 - cos2).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

/// Density of the reflected direction when h is drawn by [`sample_h`].
#[inline]
pub fn pdf_reflected(wo: Vec3, h: Vec3, alpha: f32, dist: Distribution) -> f32 {
    let oh = wo.dot(h).abs();
    if oh <= 0.0 {
        return 0.0;
    }
    d(h, alpha, dist) * h.z / (4.0 * oh)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ D(h) cos θh dω = 1: the projected microfacet area equals the macro-surface area.
    /// D is isotropic, so a 1-D midpoint rule over θ with 200k steps is exact to ~1e-6.
    #[test]
    fn distributions_are_normalized() {
        for dist in [Distribution::Ggx, Distribution::Beckmann] {
            for alpha in [0.02f32, 0.3, 1.0] {
                let n = 200_000;
                let dt = std::f64::consts::FRAC_PI_2 / n as f64;
                let mut s = 0.0f64;
                for i in 0..n {
                    let t = (i as f64 + 0.5) * dt;
                    let h = Vec3::new(t.sin() as f32, 0.0, t.cos() as f32);
                    s += d(h, alpha, dist) as f64
                        * t.cos()
                        * t.sin()
                        * dt
                        * 2.0
                        * std::f64::consts::PI;
                }
                assert!((s - 1.0).abs() < 1e-3, "{dist:?} alpha {alpha}: {s}");
            }
        }
    }

    /// Smith's G1 = 1/(1 + Λ) is the projected area of the visible microfacets:
    /// ∫ G1(w) max(0, w·h) D(h) dω_h = cos θw (within the rational fit's 0.5% for Beckmann).
    #[test]
    fn masking_is_consistent_with_the_distribution() {
        for dist in [Distribution::Ggx, Distribution::Beckmann] {
            for alpha in [0.1f32, 0.5] {
                for cos_w in [0.9f32, 0.5, 0.2] {
                    let w = Vec3::new((1.0 - cos_w * cos_w).sqrt(), 0.0, cos_w);
                    let (nt, np) = (2000, 400);
                    let mut s = 0.0f64;
                    for i in 0..nt {
                        let t = (i as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
                        for j in 0..np {
                            let p = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
                            let h = Vec3::new(
                                (t.sin() * p.cos()) as f32,
                                (t.sin() * p.sin()) as f32,
                                t.cos() as f32,
                            );
                            let dw = t.sin() * std::f64::consts::FRAC_PI_2 / nt as f64
                                * std::f64::consts::TAU
                                / np as f64;
                            s += (w.dot(h).max(0.0) * d(h, alpha, dist)) as f64 * dw;
                        }
                    }
                    let g1 = 1.0 / (1.0 + lambda(w, alpha, dist)) as f64;
                    let rel = (s * g1 / cos_w as f64 - 1.0).abs();
                    assert!(rel < 6e-3, "{dist:?} α {alpha} cos {cos_w}: {rel}");
                }
            }
        }
    }
}
