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

    /// Footprint semi-axes Δ·s·∂p at the current hit, with the nonlinear compression
    /// ‖∂p‖^(−3/4) for photons that were diffusely reflected (§4.3), clamped to `r_max`.
    pub fn footprint_axes(
        &self,
        delta: f32,
        smoothing: f32,
        diffuse: bool,
        r_max: f32,
    ) -> [Vec3; 2] {
        self.dp.map(|a| {
            let len = a.length();
            let scaled = if diffuse && len > 0.0 {
                a * len.powf(-0.75)
            } else {
                a
            };
            let axis = scaled * delta * smoothing;
            let l = axis.length();
            if l > r_max {
                axis * (r_max / l)
            } else {
                axis
            }
        })
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

    #[test]
    fn spacing_of_a_point_light() {
        let n = 10_000;
        let delta = global_spacing(4.0 * std::f32::consts::PI, n);
        assert!((delta - 2.0 * (std::f32::consts::PI / n as f32).sqrt()).abs() < 1e-6);
    }
}
