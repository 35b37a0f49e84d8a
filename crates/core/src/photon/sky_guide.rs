//! The sky's photons aimed at the openings its light enters a scene through (issue 44
//! item 3): a room lit by the sky through a window stores only the photons that pass the
//! window (~1.6% of them in `tests/scenes/openings/window_room.json`), so its indirect
//! light rests on a few hundred photons a frame and its mean moves with the seed.
//!
//! A pilot batch of sky photons, emitted as before (a direction drawn from the sky, a point
//! on the bounding disc facing it) and traced, marks the rays whose paths stored a photon;
//! the frame's sky photons are then drawn from the defensive mixture
//! q = a·p + (1 − a)·(1/K)·Σ_j k_j of the plain density p and kernels k_j around the K
//! marked rays (a cone of directions around the ray's, times a disc of positions around its
//! crossing of the plane through the bounds' centre facing the direction), each with power
//! L(ω)/q: every ray the plain emission can draw keeps a density (a·p), so the estimate is
//! unbiased (Owen & Zhou 2000's defensive importance sampling; the pilot only shapes q, and
//! its photons are not stored). Where fewer than `MIN_KERNELS` pilot paths store anything
//! (an open scene whose sky photons all escape, or none enter) the plain emission stays.
//! The pilot: [`super::trace::sky_pilot`].

use crate::sampling::{uniform_cone, Frame, Rng};
use crate::scene::environment::Environment;
use crate::scene::light::{Bounds, Emission};
use glam::Vec3;
use std::f32::consts::PI;

/// The plain emission's share of the mixture (the defensive part).
const PLAIN_SHARE: f32 = 0.25;
/// A kernel's cone half-angle (radians) and disc radius (a share of the bounding radius).
const KERNEL_ANGLE: f32 = 0.2;
const KERNEL_RADIUS: f32 = 0.1;
/// Fewest marked pilot rays to aim by, and most kept (the first, by index).
const MIN_KERNELS: usize = 16;
const MAX_KERNELS: usize = 512;

/// One marked pilot ray: the unit direction towards the sky it came from, and where it
/// crossed the plane through the bounds' centre facing that direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkyRay {
    pub towards: Vec3,
    pub point: Vec3,
}

/// The mixture the sky's photons are drawn from (see the module).
#[derive(Clone, Debug)]
pub struct SkyGuide {
    kernels: Vec<SkyRay>,
    bounds: Bounds,
    cos_k: f32,
    r_k: f32,
}

impl SkyGuide {
    /// The guide of kernels around `rays` (the first `MAX_KERNELS`), `None` for fewer than
    /// `MIN_KERNELS`.
    pub fn new(mut rays: Vec<SkyRay>, bounds: Bounds) -> Option<SkyGuide> {
        if rays.len() < MIN_KERNELS || bounds.radius.is_nan() || bounds.radius <= 0.0 {
            return None;
        }
        rays.truncate(MAX_KERNELS);
        Some(SkyGuide {
            kernels: rays,
            bounds,
            cos_k: KERNEL_ANGLE.cos(),
            r_k: KERNEL_RADIUS * bounds.radius,
        })
    }

    /// Where the ray from `towards` through `origin` crosses the plane through the bounds'
    /// centre facing `towards`.
    pub fn crossing(&self, towards: Vec3, origin: Vec3) -> Vec3 {
        let c = self.bounds.centre;
        origin - towards * (origin - c).dot(towards)
    }

    /// The plain emission's density of the ray from `towards` crossing the centre's plane at
    /// `point` (per steradian and m² across the ray).
    fn plain_density(&self, env: &Environment, towards: Vec3, point: Vec3) -> f32 {
        let r = self.bounds.radius;
        if (point - self.bounds.centre).length_squared() > r * r {
            return 0.0;
        }
        env.pdf(towards) / (PI * r * r)
    }

    /// The kernels' mean density of that ray (same measure).
    fn kernel_density(&self, towards: Vec3, point: Vec3) -> f32 {
        let per = 1.0 / (2.0 * PI * (1.0 - self.cos_k) * PI * self.r_k * self.r_k);
        let r2 = self.r_k * self.r_k;
        let c = self.bounds.centre;
        let hits = self
            .kernels
            .iter()
            .filter(|k| {
                if k.towards.dot(towards) < self.cos_k {
                    return false;
                }
                // The kernel's point moved to the plane facing `towards`.
                let centre = k.point - towards * (k.point - c).dot(towards);
                (point - centre).length_squared() <= r2
            })
            .count();
        per * hits as f32 / self.kernels.len() as f32
    }

    /// The mixture's density of the ray (same measure).
    pub fn density(&self, env: &Environment, towards: Vec3, point: Vec3) -> f32 {
        PLAIN_SHARE * self.plain_density(env, towards, point)
            + (1.0 - PLAIN_SHARE) * self.kernel_density(towards, point)
    }

    /// One sky photon drawn from the mixture with power L(ω)/q (divide by the photon count),
    /// and the area across the ray that a photon of the plain emission stands for (the
    /// bounding disc's, for photon differentials: the aimed photons keep the plain ones'
    /// footprints, so that a surface's light is smoothed as before over more photons; with
    /// their own, denser spacing their footprints shrink and each pixel sees as few).
    pub fn emit(&self, env: &Environment, rng: &mut Rng) -> Option<(Emission, f32)> {
        let pick = rng.next_f32();
        let (u, v) = (rng.next_2d(), rng.next_2d());
        let (towards, point) = if pick < PLAIN_SHARE {
            let s = env.sample(u)?;
            let (origin, _) = self.bounds.disc_point(s.wi, v);
            (s.wi, self.crossing(s.wi, origin))
        } else {
            let n = self.kernels.len();
            let j = (((pick - PLAIN_SHARE) / (1.0 - PLAIN_SHARE)) * n as f32) as usize;
            let k = self.kernels[j.min(n - 1)];
            let towards = Frame::new(k.towards).to_world(uniform_cone(u, self.cos_k));
            let f = Frame::new(towards);
            let r = self.r_k * v.x.sqrt();
            let phi = 2.0 * PI * v.y;
            let offset = f.t * (r * phi.cos()) + f.b * (r * phi.sin());
            (towards, self.crossing(towards, k.point) + offset)
        };
        let q = self.density(env, towards, point);
        if q.is_nan() || q <= 0.0 {
            return None;
        }
        let e = Emission {
            origin: point + towards * self.bounds.radius,
            direction: -towards,
            power: env.radiance(towards) / q,
        };
        let r = self.bounds.radius;
        Some((e, PI * r * r))
    }
}

/// A guide whose kernels are the rays `towards` × `points` (tests).
#[cfg(test)]
pub(crate) fn guide_of(rays: &[(Vec3, Vec3)], bounds: Bounds) -> Option<SkyGuide> {
    let rays = rays
        .iter()
        .map(|&(towards, point)| SkyRay { towards, point })
        .collect();
    SkyGuide::new(rays, bounds)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::environment::Environment;

    fn constant_sky() -> Environment {
        Environment::constant(Vec3::splat(2.0))
    }

    fn bounds() -> Bounds {
        Bounds {
            centre: Vec3::new(0.5, 1.0, -0.5),
            radius: 3.0,
        }
    }

    /// A few kernels in one corner of the sky and of the disc.
    fn guide() -> SkyGuide {
        let b = bounds();
        let mut rng = Rng::new(7, 0, 0);
        let rays: Vec<(Vec3, Vec3)> = (0..40)
            .map(|_| {
                let t = Frame::new(Vec3::new(0.3, 0.8, 0.5).normalize())
                    .to_world(uniform_cone(rng.next_2d(), 0.9));
                let f = Frame::new(t);
                let p = b.centre + f.t * 1.2 + f.b * (rng.next_2d().x - 0.5);
                (t, p)
            })
            .collect();
        guide_of(&rays, b).unwrap()
    }

    /// The photons' mean power over the scene's bounding disc, as the plain emission's:
    /// E[L/q] over the mixture is ∫∫ L dω dA = 4π L · πr² for a constant sky (what crosses
    /// the sphere), and the mixture's density integrates to one (its weights are right).
    #[test]
    fn aimed_photons_carry_the_skys_power() {
        let (g, env, b) = (guide(), constant_sky(), bounds());
        let n = 400_000;
        let mut rng = Rng::new(3, 1, 0);
        let mut sum = 0.0f64;
        let mut aimed = 0u32;
        for _ in 0..n {
            let Some((e, _)) = g.emit(&env, &mut rng) else {
                continue;
            };
            let point = g.crossing(-e.direction, e.origin);
            if (point - b.centre).length() <= b.radius {
                sum += e.power.x as f64;
            }
            aimed += u32::from(g.kernel_density(-e.direction, point) > 0.0);
        }
        let expect = 2.0 * 4.0 * PI as f64 * (PI * b.radius * b.radius) as f64;
        let mean = sum / n as f64;
        assert!((mean / expect - 1.0).abs() < 0.02, "{mean} vs {expect}");
        // Most photons are aimed (the kernels' share and the plain draws that fall in them).
        assert!(aimed as f64 > 0.7 * n as f64, "{aimed}");
    }

    /// The power that the rays through a small target carry is the plain emission's (the
    /// estimate of what enters an opening is unchanged, and the aimed photons reach it more
    /// often).
    #[test]
    fn power_through_an_opening_is_unchanged() {
        let (g, env, b) = (guide(), constant_sky(), bounds());
        let k = g.kernels[0];
        // A small window: a disc of radius 0.3 at the kernel's crossing, facing its direction.
        let hit = |e: &Emission| {
            let t = k.towards;
            let d = e.direction;
            let denom = d.dot(-t);
            if denom <= 1e-6 {
                return false;
            }
            let s = (e.origin - k.point).dot(t) / denom;
            s > 0.0 && (e.origin + d * s - k.point).length() < 0.3
        };
        // Plain: ~0.25% of the photons cross it (~5000). The estimates' standard errors from
        // the sample variance; each within 4 of them of the exact flux.
        let n = 2_000_000;
        let estimate = |aimed: bool, seed: u64| {
            let mut rng = Rng::new(seed, 2, 0);
            let (mut sum, mut sq, mut count) = (0.0f64, 0.0f64, 0u32);
            for _ in 0..n {
                let e = if aimed {
                    g.emit(&env, &mut rng).map(|(e, _)| e)
                } else {
                    env.emit(&mut rng, b)
                };
                if let Some(e) = e.filter(|e| hit(e)) {
                    sum += e.power.x as f64;
                    sq += (e.power.x as f64).powi(2);
                    count += 1;
                }
            }
            let mean = sum / n as f64;
            let stderr = ((sq / n as f64 - mean * mean) / n as f64).sqrt();
            (mean, stderr, count)
        };
        // Exact: L · π·0.3² · ∫ over the hemisphere facing the disc of cos dω = L·π·0.09·π.
        let exact = 2.0 * (PI * 0.09) as f64 * PI as f64;
        let (plain, plain_se, plain_n) = estimate(false, 5);
        let (aimed, aimed_se, aimed_n) = estimate(true, 6);
        for (name, mean, se) in [("plain", plain, plain_se), ("aimed", aimed, aimed_se)] {
            assert!(se < 0.03 * exact, "{name}: standard error {se}");
            assert!(
                (mean - exact).abs() < 4.0 * se,
                "{name}: {mean} ± {se} vs {exact}"
            );
        }
        assert!(aimed_n > 5 * plain_n, "{aimed_n} vs {plain_n}");
    }

    #[test]
    fn too_few_rays_keep_the_plain_emission() {
        let rays = vec![(Vec3::Y, Vec3::ZERO); MIN_KERNELS - 1];
        assert!(guide_of(&rays, bounds()).is_none());
    }
}
