//! Fresnel terms: Schlick's approximation for the specular lobe and the exact dielectric
//! reflectance for glass.

use glam::Vec3;

/// Schlick's approximation `F0 + (1 - F0)(1 - cos)^5`, per channel.
#[inline]
pub fn schlick(f0: Vec3, cos: f32) -> Vec3 {
    let m = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * m
}

/// Cosine-weighted hemispherical average of Schlick's term: `2 ∫ F(μ) μ dμ = F0 + (1 - F0)/21`.
#[inline]
pub fn schlick_average(f0: Vec3) -> Vec3 {
    f0 + (Vec3::ONE - f0) / 21.0
}

/// Unpolarized Fresnel reflectance of a smooth dielectric boundary.
///
/// `cos_i` is the cosine of the incident angle (> 0) and `eta` the ratio of the refractive
/// index on the far side to that on the incident side. Returns `(reflectance, cos_t)`, with
/// `cos_t = 0` and reflectance 1 under total internal reflection.
#[inline]
pub fn dielectric(cos_i: f32, eta: f32) -> (f32, f32) {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    (0.5 * (rs * rs + rp * rp), cos_t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_limits() {
        // Normal incidence: ((eta - 1) / (eta + 1))^2.
        let (f, ct) = dielectric(1.0, 1.5);
        assert!((f - 0.04).abs() < 1e-6 && (ct - 1.0).abs() < 1e-6);
        // Grazing incidence reflects everything.
        assert!(dielectric(1e-6, 1.5).0 > 0.999);
        // Total internal reflection from inside glass beyond the critical angle (41.8°).
        assert_eq!(dielectric(0.5, 1.0 / 1.5).0, 1.0);
        // Reciprocity of the boundary: F(θi, η) = F(θt, 1/η).
        let (f1, cos_t) = dielectric(0.7, 1.5);
        let (f2, _) = dielectric(cos_t, 1.0 / 1.5);
        assert!((f1 - f2).abs() < 1e-6);
    }

    #[test]
    fn schlick_average_matches_quadrature() {
        let f0 = Vec3::new(0.04, 0.5, 0.9);
        let n = 100_000;
        let mut sum = Vec3::ZERO;
        for i in 0..n {
            let mu = (i as f32 + 0.5) / n as f32;
            sum += schlick(f0, mu) * 2.0 * mu / n as f32;
        }
        assert!((sum - schlick_average(f0)).abs().max_element() < 1e-4);
    }
}
