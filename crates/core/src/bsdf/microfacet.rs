//! The GGX (Trowbridge-Reitz) microfacet distribution with height-correlated Smith masking,
//! in the local frame where the normal is +z.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// GGX normal distribution D(h) for roughness `alpha` (= perceptual roughness squared).
#[inline]
pub fn d(h: Vec3, alpha: f32) -> f32 {
    if h.z <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let c2 = h.z * h.z;
    // (1 − c²) + c²·α², not c²·(α² − 1) + 1: for α² below f32's epsilon, α² − 1 rounds to
    // −1 and t to 0 at h = n, making D infinite (and radiance NaN).
    let t = (1.0 - c2) + c2 * a2;
    a2 / (PI * t * t)
}

/// Smith's Λ for GGX.
#[inline]
fn lambda(w: Vec3, alpha: f32) -> f32 {
    let c2 = w.z * w.z;
    if c2 <= 0.0 {
        return f32::INFINITY;
    }
    let tan2 = (1.0 - c2).max(0.0) / c2;
    0.5 * ((1.0 + alpha * alpha * tan2).sqrt() - 1.0)
}

/// Height-correlated masking-shadowing G2(wo, wi).
#[inline]
pub fn g2(wo: Vec3, wi: Vec3, alpha: f32) -> f32 {
    1.0 / (1.0 + lambda(wo, alpha) + lambda(wi, alpha))
}

/// Samples a half vector with density D(h)·cos(θh).
#[inline]
pub fn sample_h(u: Vec2, alpha: f32) -> Vec3 {
    let a2 = alpha * alpha;
    let cos2 = (1.0 - u.x) / (1.0 + (a2 - 1.0) * u.x);
    let cos_t = cos2.max(0.0).sqrt();
    let sin_t = (1.0 - cos2).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

/// Density of the reflected direction when h is drawn by [`sample_h`].
#[inline]
pub fn pdf_reflected(wo: Vec3, h: Vec3, alpha: f32) -> f32 {
    let oh = wo.dot(h).abs();
    if oh <= 0.0 {
        return 0.0;
    }
    d(h, alpha) * h.z / (4.0 * oh)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ D(h) cos θh dω = 1: the projected microfacet area equals the macro-surface area.
    /// D is isotropic, so a 1-D midpoint rule over θ with 200k steps is exact to ~1e-6.
    #[test]
    fn ggx_is_normalized() {
        for alpha in [0.02f32, 0.3, 1.0] {
            let n = 200_000;
            let dt = std::f64::consts::FRAC_PI_2 / n as f64;
            let mut s = 0.0f64;
            for i in 0..n {
                let t = (i as f64 + 0.5) * dt;
                let h = Vec3::new(t.sin() as f32, 0.0, t.cos() as f32);
                s += d(h, alpha) as f64 * t.cos() * t.sin() * dt * 2.0 * std::f64::consts::PI;
            }
            assert!((s - 1.0).abs() < 1e-3, "alpha {alpha}: {s}");
        }
    }
}
