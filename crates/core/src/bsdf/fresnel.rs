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

/// Unpolarized Fresnel reflectance of a conductor of complex relative index `eta + i·k`
/// (per channel) at incident cosine `cos_i` (the exact formula, as Mitsuba's
/// `fresnel_conductor`, after Moeller's "Optics").
pub fn conductor(cos_i: f32, eta: Vec3, k: Vec3) -> Vec3 {
    let c = cos_i.clamp(0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let t1 = eta * eta - k * k - Vec3::splat(s2);
    let a2b2 = (t1 * t1 + 4.0 * k * k * eta * eta).max(Vec3::ZERO);
    let a2b2 = Vec3::new(a2b2.x.sqrt(), a2b2.y.sqrt(), a2b2.z.sqrt());
    let a = (0.5 * (a2b2 + t1)).max(Vec3::ZERO);
    let a = Vec3::new(a.x.sqrt(), a.y.sqrt(), a.z.sqrt());
    let term1 = a2b2 + Vec3::splat(c2);
    let term2 = 2.0 * c * a;
    let rs = (term1 - term2) / (term1 + term2);
    let term3 = a2b2 * c2 + Vec3::splat(s4);
    let term4 = term2 * s2;
    let rp = rs * (term3 - term4) / (term3 + term4);
    0.5 * (rs + rp)
}

/// Cosine-weighted hemispherical average `2 ∫ F(μ) μ dμ` of the conductor Fresnel term
/// (Gauss-Legendre, 32 nodes: F is smooth in μ).
pub fn conductor_average(eta: Vec3, k: Vec3) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for (x, w) in gauss_legendre_01() {
        sum += conductor(x, eta, k) * (2.0 * x * w);
    }
    sum
}

/// 32-node Gauss-Legendre nodes and weights on [0, 1].
pub fn gauss_legendre_01() -> impl Iterator<Item = (f32, f32)> {
    const N: usize = 32;
    (0..N).map(|i| {
        // Newton iteration on P_N from Chebyshev's initial guess (f64).
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (N as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0f64, x);
            for n in 2..=N {
                let p2 = ((2 * n - 1) as f64 * x * p1 - (n - 1) as f64 * p0) / n as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = N as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        ((0.5 * (x + 1.0)) as f32, (0.5 * w) as f32)
    })
}

/// Hemispherical-average reflectance of a smooth dielectric boundary of relative index
/// `eta` lit by diffuse light (Mitsuba's `fresnel_diffuse_reflectance`: the fit of
/// d'Eon & Irving 2011 for eta < 1 and Egan & Hilgeman 1973's for eta ≥ 1).
pub fn diffuse_reflectance(eta: f32) -> f32 {
    let inv = 1.0 / eta;
    if eta < 1.0 {
        0.0636 * inv + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        let c = [0.919317f32, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881];
        c.iter().rev().fold(0.0, |acc, &ci| acc * inv + ci)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conductor_limits() {
        // k = 0 is a dielectric of index eta.
        let f = conductor(0.6, Vec3::splat(1.5), Vec3::ZERO);
        assert!((f.x - dielectric(0.6, 1.5).0).abs() < 1e-5, "{f}");
        // Normal incidence: ((η−1)² + k²)/((η+1)² + k²).
        let (eta, k) = (Vec3::new(0.2, 0.9, 1.5), Vec3::new(3.0, 2.4, 1.9));
        let f = conductor(1.0, eta, k);
        let f0 = ((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k);
        assert!((f - f0).abs().max_element() < 1e-5, "{f} {f0}");
        // Mitsuba's "none": a perfect reflector at every angle.
        for c in [1.0, 0.5, 0.01] {
            let f = conductor(c, Vec3::ZERO, Vec3::ONE);
            assert!((f - Vec3::ONE).abs().max_element() < 1e-5, "{f}");
        }
    }

    #[test]
    fn diffuse_reflectance_matches_quadrature() {
        // 2 ∫ F(μ, η) μ dμ by the midpoint rule against the fit (0.1% for 1 < η < 2; the
        // internal side has total internal reflection, its fit 0.5%).
        for eta in [1.2f32, 1.49, 1.0 / 1.49, 1.0 / 1.2] {
            let n = 100_000;
            let mut s = 0.0f64;
            for i in 0..n {
                let mu = (i as f32 + 0.5) / n as f32;
                s += (dielectric(mu, eta).0 * 2.0 * mu) as f64 / n as f64;
            }
            let fit = diffuse_reflectance(eta) as f64;
            assert!(
                (fit - s).abs() < 5e-3 * s.max(0.05),
                "η {eta}: fit {fit}, {s}"
            );
        }
    }

    #[test]
    fn gauss_legendre_integrates_polynomials() {
        let s: f32 = gauss_legendre_01().map(|(x, w)| w * x.powi(7)).sum();
        assert!((s - 0.125).abs() < 1e-6, "{s}");
        let total: f32 = gauss_legendre_01().map(|(_, w)| w).sum();
        assert!((total - 1.0).abs() < 1e-6);
    }

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
