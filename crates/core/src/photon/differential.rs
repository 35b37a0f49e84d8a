//! Photon differentials (Schjøth et al. 2007; Fabianowski & Dingliana 2009, §4), after
//! Igehy's ray differentials: each photon carries the derivatives of its position and
//! direction with respect to its two emission (or re-emission) parameters. At a hit they
//! span a footprint ellipse, scaled by one global spacing Δ = √(Ω/n) (2√(π/n) for an
//! isotropic point light emitting n photons into 4π).

use glam::Vec3;

/// Positional and directional differentials along the two sampling parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Differentials {
    pub dp: [Vec3; 2],
    pub dd: [Vec3; 2],
}

/// Two unit vectors orthogonal to `d` and to each other.
fn orthonormal_pair(d: Vec3) -> [Vec3; 2] {
    let f = crate::sampling::Frame::new(d);
    [f.t, f.b]
}

impl Differentials {
    /// A photon leaving a point (a light, or a diffuse re-emission at zero offset) in unit
    /// direction `d`: zero positional differentials, unit orthogonal directional ones
    /// (eq. 8, scaled so that one spacing Δ serves all photons).
    pub fn emitted(d: Vec3) -> Self {
        Differentials {
            dp: [Vec3::ZERO; 2],
            dd: orthonormal_pair(d),
        }
    }

    /// Scales all differentials (e.g. by Δ_light / Δ for a light whose photons are spaced
    /// differently from the global spacing).
    pub fn scaled(mut self, s: f32) -> Self {
        self.dp = self.dp.map(|v| v * s);
        self.dd = self.dd.map(|v| v * s);
        self
    }

    /// Transfer along `d` by distance `t` to a surface with normal `n` (Igehy 1999):
    /// ∂p' = ∂p + t∂d + ∂t·d with ∂t = −(∂p + t∂d)·n / (d·n), which keeps ∂p' in the
    /// surface's tangent plane.
    pub fn transfer(&mut self, d: Vec3, t: f32, n: Vec3) {
        let dn = d.dot(n);
        for i in 0..2 {
            let moved = self.dp[i] + t * self.dd[i];
            let dt = if dn.abs() > 1e-6 {
                -moved.dot(n) / dn
            } else {
                0.0
            };
            self.dp[i] = moved + dt * d;
        }
    }

    /// Perfect specular reflection of `d` about normal `n`, whose own derivative along the
    /// footprint is `dn` (from interpolated vertex normals; zero on flat surfaces):
    /// ∂d' = ∂d − 2[(d·n)∂n + ∂(d·n)·n].
    pub fn reflect(&mut self, d: Vec3, n: Vec3, dn: [Vec3; 2]) {
        let ddotn = d.dot(n);
        for (dd, dn) in self.dd.iter_mut().zip(dn) {
            let d_ddotn = dd.dot(n) + d.dot(dn);
            *dd -= 2.0 * (ddotn * dn + d_ddotn * n);
        }
    }

    /// Refraction from `d` to `d_t` with relative index `eta` = η_incident / η_transmitted at
    /// normal `n` (facing the incident side): d' = ηd − μn, μ = η(d·n) − d'·n, and
    /// ∂d' = η∂d − (μ∂n + ∂μ·n), ∂μ = (η − η²(d·n)/(d'·n))·∂(d·n).
    pub fn refract(&mut self, d: Vec3, d_t: Vec3, n: Vec3, eta: f32, dn: [Vec3; 2]) {
        let (ddotn, dtdotn) = (d.dot(n), d_t.dot(n));
        let mu = eta * ddotn - dtdotn;
        let k = if dtdotn.abs() > 1e-6 {
            eta - eta * eta * ddotn / dtdotn
        } else {
            0.0
        };
        for (dd, dn) in self.dd.iter_mut().zip(dn) {
            let d_ddotn = dd.dot(n) + d.dot(dn);
            *dd = eta * *dd - (mu * dn + k * d_ddotn * n);
        }
    }

    /// Diffuse (or glossy) re-emission in direction `d_out` (§4.3, eq. 13): new orthonormal
    /// directional differentials, and the origin virtually moved back by
    /// v = √|∂p₁ × ∂p₂| so that the footprint area is preserved.
    pub fn reemit(&mut self, d_out: Vec3) {
        let v = self.dp[0].cross(self.dp[1]).length().sqrt();
        let dd = orthonormal_pair(d_out);
        *self = Differentials {
            dp: [v * dd[0], v * dd[1]],
            dd,
        };
    }

    /// Russian roulette survival with probability `q` widens the footprint by 1/q in area.
    pub fn survive(&mut self, q: f32) {
        let s = 1.0 / q.max(1e-6).sqrt();
        for i in 0..2 {
            self.dp[i] *= s;
            self.dd[i] *= s;
        }
    }

    /// Footprint semi-axes Δ·s·∂p at the current hit, before the compression of diffusely
    /// reflected photons ([`compress`]) and the clamp to a largest radius ([`clamp_axis`]),
    /// which wait until all photons are traced.
    pub fn footprint_axes(&self, delta: f32, smoothing: f32) -> [Vec3; 2] {
        self.dp.map(|a| a * (delta * smoothing))
    }
}

/// The nonlinear compression of a diffusely reflected photon's semi-axis `a` (§4.3):
/// a·(‖a‖/L)^(−3/4), so its length becomes L^(3/4)·‖a‖^(1/4).
///
/// The paper writes the factor as ‖∂p‖^(−3/4) of the raw differential, which silently fixes
/// the reference length (L = Δ·s scene units for these axes a = Δ·s·∂p): the result then has
/// units of length^(1/4), and multiplying a scene's coordinates by 100 (metres to
/// centimetres) multiplies its diffuse footprints by only 100^(1/4) ≈ 3.2 — they would
/// shrink 32-fold relative to the scene (and in a metre-scale scene they end up smaller than
/// the caustic ones: tests/gather.rs). Measuring ‖a‖ against
/// a length of the scene itself keeps footprints scale-free; [`reference_length`] picks the
/// geometric mean of the lengths being compressed, so that the compression only narrows
/// the range of radii around their typical size (what §4.3 asks of it) and leaves the overall
/// size to the smoothing factor s.
pub fn compress(a: Vec3, reference: f32) -> Vec3 {
    let len = a.length();
    if len > 0.0 && reference > 0.0 {
        a * (len / reference).powf(-0.75)
    } else {
        a
    }
}

/// The reference length L of [`compress`]: the geometric mean of the (nonzero, finite)
/// semi-axis lengths `lengths`, accumulated in f64 and in order (deterministic). `None`
/// when there are none.
pub fn reference_length(lengths: impl IntoIterator<Item = f32>) -> Option<f32> {
    let (mut sum, mut n) = (0.0f64, 0u64);
    for l in lengths {
        if l > 0.0 && l.is_finite() {
            sum += (l as f64).ln();
            n += 1;
        }
    }
    (n > 0).then(|| (sum / n as f64).exp() as f32)
}

/// The principal semi-axes of the ellipse spanned by the conjugate semi-diameters `a`
/// (the footprint {a₁x + a₂y : x² + y² ≤ 1}): two orthogonal vectors, the longer first,
/// spanning the same ellipse (same area, same extent).
///
/// Differentials give conjugate semi-diameters: a photon arriving at a grazing angle θ has
/// both stretched by 1/cos θ along the same direction, so they end up nearly parallel.
/// Rescaling such skewed axes one by one ([`compress`], [`clamp_axis`]) keeps most of the
/// ellipse's elongation (both shrink by similar factors), and a footprint 20× longer than
/// wide is splatted as a thin bright streak; on the principal axes the compression shrinks
/// the long one most, taking the elongation to its fourth root.
pub fn principal_axes(a: [Vec3; 2]) -> [Vec3; 2] {
    // Eigenvectors of the Gram matrix [[p, q], [q, r]] of the two axes.
    let (p, q, r) = (a[0].dot(a[0]), a[0].dot(a[1]), a[1].dot(a[1]));
    let half_gap = (0.5 * (p - r)).hypot(q);
    let big = 0.5 * (p + r) + half_gap;
    let (x, y) = if q.abs() > 1e-12 * (p + r) {
        let v = glam::Vec2::new(big - r, q).normalize();
        (v.x, v.y)
    } else if p >= r {
        (1.0, 0.0)
    } else {
        (0.0, 1.0)
    };
    if !(x.is_finite() && y.is_finite()) {
        return a;
    }
    [a[0] * x + a[1] * y, a[1] * x - a[0] * y]
}

/// Length ratio of the longer to the shorter principal semi-axis of the ellipse spanned by
/// `a` (≥ 1; infinite for a degenerate one).
pub fn elongation(a: [Vec3; 2]) -> f32 {
    let [u, v] = principal_axes(a);
    u.length() / v.length()
}

/// Largest ratio of a footprint's long to its short semi-axis ([`cap_elongation`]): above
/// the 99.9th percentile of diffusely reflected photons' footprints (3.2 in
/// `cornell-glass`), so it reshapes caustic photons' only.
pub const MAX_ELONGATION: f32 = 4.0;

/// Principal semi-axes `a` (longer first, as [`principal_axes`] gives them) reshaped, at
/// the same area, so that the longer is at most `max` times the shorter.
///
/// Differentials of photons refracted near a sphere's rim or focused into a caustic line
/// give footprints hundreds of times longer than wide (a p99 elongation of 52 and a largest
/// of 2,600 among the caustic photons of `cornell-glass`); a few thousand such photons
/// splat as long light streaks rather than a caustic. Keeping the area keeps the kernel's
/// bandwidth (how many photons it averages) and only rounds its shape.
pub fn cap_elongation(a: [Vec3; 2], max: f32) -> [Vec3; 2] {
    let (long, short) = (a[0].length(), a[1].length());
    if short <= 0.0 || long <= max * short {
        return a;
    }
    let k = (long / (max * short)).sqrt();
    [a[0] / k, a[1] * k]
}

/// Clamps a semi-axis to the length `r_max`, keeping its direction.
pub fn clamp_axis(a: Vec3, r_max: f32) -> Vec3 {
    let l = a.length();
    if l > r_max {
        a * (r_max / l)
    } else {
        a
    }
}

/// Global spacing Δ = √(Ω/n) for `n` photons emitted into solid angle `omega`.
pub fn global_spacing(omega: f32, n: u64) -> f32 {
    (omega / n.max(1) as f32).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// From a point light at height h straight down onto a plane, the footprint area is
    /// π·Δ²·h² (the photon's solid angle share, spread over the distance squared).
    #[test]
    fn transfer_from_point_light_spreads_with_distance_squared() {
        let d = Vec3::new(0.0, -1.0, 0.0);
        for h in [0.5f32, 2.0] {
            let mut diff = Differentials::emitted(d);
            diff.transfer(d, h, Vec3::Y);
            let area = std::f32::consts::PI * diff.dp[0].cross(diff.dp[1]).length();
            assert!((area - std::f32::consts::PI * h * h).abs() < 1e-4);
            assert!(
                diff.dp[0].dot(Vec3::Y).abs() < 1e-6,
                "stays in the tangent plane"
            );
        }
        // Oblique incidence stretches the footprint by 1/cos.
        let d = Vec3::new(1.0, -1.0, 0.0).normalize();
        let mut diff = Differentials::emitted(d);
        diff.transfer(d, 2.0, Vec3::Y);
        let area = diff.dp[0].cross(diff.dp[1]).length();
        assert!(
            (area - 4.0 / std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-3,
            "{area}"
        );
    }

    /// A flat mirror keeps the beam's divergence: after reflection the footprint is the
    /// one the mirrored light would give at the total path length.
    #[test]
    fn flat_mirror_acts_like_an_image_light() {
        let d = Vec3::new(0.0, -1.0, 0.0);
        let mut diff = Differentials::emitted(d);
        diff.transfer(d, 1.0, Vec3::Y);
        diff.reflect(d, Vec3::Y, [Vec3::ZERO; 2]);
        let r = Vec3::Y;
        diff.transfer(r, 2.0, -Vec3::Y);
        let area = diff.dp[0].cross(diff.dp[1]).length();
        assert!((area - 9.0).abs() < 1e-3, "{area}");
    }

    /// A concave mirror (∂n pointing inwards) focuses: the footprint shrinks towards the
    /// focal point at half the radius of curvature.
    #[test]
    fn curved_mirror_focuses() {
        // Beam hitting a sphere of radius R = 2 from its centre: the reflected beam returns
        // to the centre, where the footprint vanishes.
        let d = Vec3::new(0.0, -1.0, 0.0);
        let mut diff = Differentials::emitted(d);
        diff.transfer(d, 2.0, Vec3::Y);
        // Inward normal of the sphere at the bottom: +y; moving along the surface by ∂p
        // rotates it by ∂p / R towards the centre.
        let n = Vec3::Y;
        let dn = diff.dp.map(|a| -a / 2.0);
        diff.reflect(d, n, dn);
        diff.transfer(Vec3::Y, 2.0, -Vec3::Y);
        assert!(
            diff.dp[0].length() < 1e-4 && diff.dp[1].length() < 1e-4,
            "{:?}",
            diff.dp
        );
    }

    #[test]
    fn reemission_preserves_area_and_roulette_widens() {
        let d = Vec3::new(0.3, -1.0, 0.2).normalize();
        let mut diff = Differentials::emitted(d);
        diff.transfer(d, 1.5, Vec3::Y);
        let before = diff.dp[0].cross(diff.dp[1]).length();
        diff.reemit(Vec3::new(0.0, 1.0, 0.0));
        let after = diff.dp[0].cross(diff.dp[1]).length();
        assert!((before - after).abs() / before < 1e-4);
        diff.survive(0.25);
        let widened = diff.dp[0].cross(diff.dp[1]).length();
        assert!((widened / after - 4.0).abs() < 1e-3);
    }

    /// Scaling a scene by k scales every raw semi-axis by k; with L measured in the scene
    /// (the geometric mean, which scales by k too) the compressed axes scale by exactly k,
    /// while the paper's literal ‖∂p‖^(−3/4) (L fixed at 1) scales them by k^(1/4).
    #[test]
    fn compression_is_scale_free() {
        let axes = [
            Vec3::new(0.02, 0.0, 0.01),
            Vec3::new(0.0, 0.3, 0.0),
            Vec3::new(1.5, 0.2, 0.0),
            Vec3::new(0.0, 0.0, 7.0),
        ];
        let k = 100.0f32;
        let l1 = reference_length(axes.iter().map(|a| a.length())).unwrap();
        let lk = reference_length(axes.iter().map(|a| (*a * k).length())).unwrap();
        assert!((lk / l1 / k - 1.0).abs() < 1e-5);
        for a in axes {
            let ratio = compress(a * k, lk).length() / compress(a, l1).length();
            assert!((ratio / k - 1.0).abs() < 1e-5, "{ratio}");
            let literal = compress(a * k, 1.0).length() / compress(a, 1.0).length();
            assert!((literal / k.powf(0.25) - 1.0).abs() < 1e-5, "{literal}");
        }
        // It narrows the range of lengths: the ratio of largest to smallest goes to its 4th root.
        let c: Vec<f32> = axes.iter().map(|a| compress(*a, l1).length()).collect();
        let before = 7.0 / axes[0].length();
        assert!((c[3] / c[0] - before.powf(0.25)).abs() < 1e-3);
    }

    /// Skewed semi-diameters of a grazing hit (both stretched along x): the principal axes
    /// span the same ellipse (same area, orthogonal, the right lengths), and compressing
    /// them rounds it where compressing the skewed ones keeps it 20× elongated.
    #[test]
    fn principal_axes_of_a_grazing_footprint() {
        // The circle of radius 1 seen at cos θ = 0.05: semi-axes 20 (x) and 1 (z), written
        // as the conjugate pair of the image of two orthonormal vectors at 30°.
        let (c, s) = (30f32.to_radians().cos(), 30f32.to_radians().sin());
        let a = [Vec3::new(20.0 * c, 0.0, s), Vec3::new(-20.0 * s, 0.0, c)];
        let [u, v] = principal_axes(a);
        assert!(u.dot(v).abs() < 1e-3 * u.length() * v.length(), "{u} {v}");
        assert!((u.length() - 20.0).abs() < 1e-3 && (v.length() - 1.0).abs() < 1e-3);
        let area = |a: [Vec3; 2]| a[0].cross(a[1]).length();
        assert!((area([u, v]) - area(a)).abs() < 1e-3);
        assert!((elongation(a) - 20.0).abs() < 1e-2);
        // Compressing against L = 1: principal axes → elongation 20^(1/4) ≈ 2.1; the skewed
        // ones (lengths 17.3 and 10.0, shrunk alike) stay 17.5× elongated.
        let squeezed = |a: [Vec3; 2]| elongation(a.map(|x| compress(x, 1.0)));
        assert!((squeezed([u, v]) - 20f32.powf(0.25)).abs() < 1e-2);
        assert!(squeezed(a) > 15.0, "{}", squeezed(a));
        // Already principal (or a circle) stays as it is.
        let b = [Vec3::X * 2.0, Vec3::Z];
        assert_eq!(principal_axes(b), b);
        let circle = principal_axes([Vec3::X, Vec3::Z]);
        assert!((circle[0].length() - 1.0).abs() < 1e-6 && circle[0].dot(circle[1]).abs() < 1e-6);
    }

    #[test]
    fn elongation_cap_keeps_the_area() {
        let a = [Vec3::X * 50.0, Vec3::Z * 0.5];
        let c = cap_elongation(a, 4.0);
        assert!((c[0].length() / c[1].length() - 4.0).abs() < 1e-4);
        let area = |a: [Vec3; 2]| a[0].cross(a[1]).length();
        assert!((area(c) - area(a)).abs() < 1e-4 * area(a));
        assert_eq!(c[0].normalize(), Vec3::X);
        let round = [Vec3::X * 3.0, Vec3::Z];
        assert_eq!(cap_elongation(round, 4.0), round);
    }

    #[test]
    fn spacing_of_a_point_light() {
        let n = 10_000;
        let delta = global_spacing(4.0 * std::f32::consts::PI, n);
        assert!((delta - 2.0 * (std::f32::consts::PI / n as f32).sqrt()).abs() < 1e-6);
    }
}
