//! The sky's photons aimed at the openings its light enters a scene through (issue 44
//! item 3): a room lit by the sky through a window stores only the photons that pass the
//! window (~1.6% of them in `tests/scenes/openings/window_room.json`), so its indirect
//! light rests on a few hundred photons a frame and its mean moves with the seed.
//!
//! A pilot batch of sky photons, emitted as before (a direction drawn from the sky, a point
//! on the bounding disc facing it) and traced, marks the rays whose paths stored a photon.
//! The frame's sky photons are then two techniques combined by the balance heuristic
//! (Veach 1997, multi-sample MIS): the `n_p` plain photons, emitted exactly as without a
//! guide, and `n_a` aimed photons drawn from kernels around the K marked rays (a cone of
//! directions around the ray's, times a disc of positions around its crossing of the plane
//! through the bounds' centre facing the direction), density k = (1/K)·Σ_j k_j. Every
//! photon's power is L(ω)/(n_p·p + n_a·k) for the plain density p: unbiased, and a plain
//! photon whose ray no kernel covers (k = 0) carries exactly the power it has without a
//! guide. So the light of paths the pilot missed keeps today's photons and variance (an
//! open scene's sky light through few, rare paths: `test_environment.py`'s ground scene,
//! whose box shadow the former defensive mixture, with a quarter of the photons plain at
//! four times their power, made 0.56–0.85 where `path` has 0.30), and the paths it found
//! get n_a more photons. Where fewer than `MIN_KERNELS` pilot paths store anything, or
//! more than `MAX_MARKED_SHARE` of them (the sky's light is not behind an opening), there is
//! no guide and no aimed photon. The pilot: [`super::trace::sky_pilot`]; the aimed trace:
//! [`super::trace::emit_aimed_sky`].

use crate::sampling::{uniform_cone, Frame, Rng};
use crate::scene::environment::Environment;
use crate::scene::light::{Bounds, Emission};
use glam::Vec3;
use std::f32::consts::PI;

/// A kernel's cone half-angle (radians) and disc radius (a share of the bounding radius).
const KERNEL_ANGLE: f32 = 0.2;
const KERNEL_RADIUS: f32 = 0.1;
/// Fewest marked pilot rays to aim by, and most kept (the first, by index). The window
/// room's 200k-ray pilot marks ~1.1k: all of them kernels (with 512 the indirect light's
/// spread over seeds was 3.2-6.1% over three pilots, with all 1.9-2.7%; a ray's kernels
/// are looked up by direction, [`DirectionBins`], so more cost little).
const MIN_KERNELS: usize = 16;
const MAX_KERNELS: usize = 4096;
/// Largest share of the pilot's rays whose paths store photons for the guide to aim: above
/// it most of the sky's photons reach the scene's surfaces anyway (window room 0.55%, the
/// open ground scene 1.0–1.3%: both aim).
pub const MAX_MARKED_SHARE: f64 = 0.1;

/// One marked pilot ray: the unit direction towards the sky it came from, and where it
/// crossed the plane through the bounds' centre facing that direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkyRay {
    pub towards: Vec3,
    pub point: Vec3,
}

/// The sky photons' two techniques (see the module).
#[derive(Clone, Debug)]
pub struct SkyGuide {
    kernels: Vec<SkyRay>,
    /// The kernels each direction may meet (a ray's density tests only those).
    bins: DirectionBins,
    bounds: Bounds,
    cos_k: f32,
    r_k: f32,
    /// Photon counts of the plain and the aimed technique.
    plain: u64,
    aimed: u64,
}

impl SkyGuide {
    /// The guide of kernels around `rays` (the first `MAX_KERNELS`) marked by a pilot of
    /// `pilot` rays, for `plain` plain and `aimed` aimed photons; `None` for fewer than
    /// `MIN_KERNELS` rays, more than `MAX_MARKED_SHARE` of the pilot, or no aimed photon.
    pub fn new(
        rays: &[SkyRay],
        pilot: u64,
        bounds: Bounds,
        plain: u64,
        aimed: u64,
    ) -> Option<SkyGuide> {
        let share = rays.len() as f64 / pilot.max(1) as f64;
        if rays.len() < MIN_KERNELS || share > MAX_MARKED_SHARE || aimed == 0 {
            return None;
        }
        if bounds.radius.is_nan() || bounds.radius <= 0.0 {
            return None;
        }
        let kernels = rays[..rays.len().min(MAX_KERNELS)].to_vec();
        Some(SkyGuide {
            bins: DirectionBins::new(&kernels, KERNEL_ANGLE),
            kernels,
            bounds,
            cos_k: KERNEL_ANGLE.cos(),
            r_k: KERNEL_RADIUS * bounds.radius,
            plain,
            aimed,
        })
    }

    /// The number of aimed photons.
    pub fn aimed(&self) -> u64 {
        self.aimed
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
            .bins
            .of(towards)
            .iter()
            .map(|&j| &self.kernels[j as usize])
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

    /// The balance heuristic's weight of a plain photon `e` (emitted as without a guide):
    /// n_p·p / (n_p·p + n_a·k), exactly 1 where no kernel covers its ray.
    pub fn plain_weight(&self, env: &Environment, e: &Emission) -> f32 {
        let towards = -e.direction;
        let point = self.crossing(towards, e.origin);
        let k = self.kernel_density(towards, point);
        if k <= 0.0 {
            return 1.0;
        }
        let p = self.plain as f32 * self.plain_density(env, towards, point);
        p / (p + self.aimed as f32 * k)
    }

    /// One aimed photon: a ray drawn from a kernel chosen uniformly, with power
    /// L(ω)/(n_p·p + n_a·k) (over the photon counts already).
    pub fn emit_aimed(&self, env: &Environment, rng: &mut Rng) -> Option<Emission> {
        let n = self.kernels.len();
        let j = ((rng.next_f32() * n as f32) as usize).min(n - 1);
        let (u, v) = (rng.next_2d(), rng.next_2d());
        let k = self.kernels[j];
        let towards = Frame::new(k.towards).to_world(uniform_cone(u, self.cos_k));
        let f = Frame::new(towards);
        let r = self.r_k * v.x.sqrt();
        let phi = 2.0 * PI * v.y;
        let offset = f.t * (r * phi.cos()) + f.b * (r * phi.sin());
        let point = self.crossing(towards, k.point) + offset;
        let q = self.plain as f32 * self.plain_density(env, towards, point)
            + self.aimed as f32 * self.kernel_density(towards, point);
        if q.is_nan() || q <= 0.0 {
            return None;
        }
        Some(Emission {
            origin: point + towards * self.bounds.radius,
            direction: -towards,
            power: env.radiance(towards) / q,
        })
    }
}

/// Cells of directions by polar angle θ (from +y) and azimuth φ.
const THETA_BINS: usize = 16;
const PHI_BINS: usize = 32;
/// Margin (radians) added to every cone for the rounding of the cells' angles.
const BIN_MARGIN: f32 = 1e-3;

/// The kernels whose cones reach each cell of a θ × φ grid of directions, listed
/// conservatively (every kernel whose cone holds a direction of the cell is in its list):
/// a cone of half-angle α around θ₀ spans θ₀ ± α and, unless it holds a pole, azimuths
/// φ₀ ± asin(sin α / sin θ₀). A ray's kernel density then tests its cell's kernels only,
/// with the same result as testing all of them (window room: 200k plain and as many
/// aimed photons a frame, each testing 512 kernels before).
#[derive(Clone, Debug)]
struct DirectionBins {
    cells: Vec<Vec<u32>>,
}

impl DirectionBins {
    fn new(kernels: &[SkyRay], angle: f32) -> DirectionBins {
        let mut cells = vec![Vec::new(); THETA_BINS * PHI_BINS];
        let a = angle + BIN_MARGIN;
        for (j, k) in kernels.iter().enumerate() {
            let (t0, p0) = angles(k.towards);
            let (lo, hi) = (t0 - a, t0 + a);
            let t_bins = theta_bin(lo.max(0.0))..=theta_bin(hi.min(PI));
            let ratio = a.sin() / t0.sin();
            let all_phi = lo <= 0.0 || hi >= PI || ratio.is_nan() || ratio >= 1.0;
            let phi_bins: Vec<usize> = if all_phi {
                (0..PHI_BINS).collect()
            } else {
                let d = ratio.asin() + BIN_MARGIN;
                let first = phi_cell(p0 - d);
                let span =
                    ((2.0 * d / (2.0 * PI) * PHI_BINS as f32).ceil() as usize + 2).min(PHI_BINS);
                (0..span).map(|i| (first + i) % PHI_BINS).collect()
            };
            for t in t_bins {
                for &p in &phi_bins {
                    cells[t * PHI_BINS + p].push(j as u32);
                }
            }
        }
        DirectionBins { cells }
    }

    /// The kernels the direction `d` may lie in the cone of.
    fn of(&self, d: Vec3) -> &[u32] {
        let (t, p) = angles(d);
        &self.cells[theta_bin(t) * PHI_BINS + phi_cell(p)]
    }
}

/// Polar angle from +y in [0, π] and azimuth in (−π, π] of the unit direction `d`.
fn angles(d: Vec3) -> (f32, f32) {
    (d.y.clamp(-1.0, 1.0).acos(), d.z.atan2(d.x))
}

fn theta_bin(t: f32) -> usize {
    ((t / PI * THETA_BINS as f32) as usize).min(THETA_BINS - 1)
}

/// The cell of azimuth `p` (any real: wrapped).
fn phi_cell(p: f32) -> usize {
    let u = (p + PI).rem_euclid(2.0 * PI) / (2.0 * PI);
    ((u * PHI_BINS as f32) as usize).min(PHI_BINS - 1)
}

/// A guide whose kernels are the rays `towards` × `points` (tests), for `plain` and `aimed`
/// photons.
#[cfg(test)]
pub(crate) fn guide_of(
    rays: &[(Vec3, Vec3)],
    bounds: Bounds,
    plain: u64,
    aimed: u64,
) -> Option<SkyGuide> {
    let rays: Vec<SkyRay> = rays
        .iter()
        .map(|&(towards, point)| SkyRay { towards, point })
        .collect();
    SkyGuide::new(&rays, 100_000, bounds, plain, aimed)
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

    /// A few kernels in one corner of the sky and of the disc, for `n` plain and `n` aimed
    /// photons.
    fn guide(n: u64) -> SkyGuide {
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
        guide_of(&rays, b, n, n).unwrap()
    }

    /// The two techniques' photons (`n` each) that `keep` accepts: Σ power and Σ power²
    /// (channel x), and how many; the plain photons as `Environment::emit` gives them (over
    /// `n`) times their weight.
    fn mis_sums(g: &SkyGuide, n: u64, seed: u64, keep: &dyn Fn(&Emission) -> bool) -> [f64; 3] {
        let (env, b) = (constant_sky(), bounds());
        let mut rng = Rng::new(seed, 1, 0);
        let mut out = [0.0f64; 3];
        for i in 0..2 * n {
            let e = if i < n {
                env.emit(&mut rng, b).map(|mut e| {
                    e.power *= g.plain_weight(&env, &e) / n as f32;
                    e
                })
            } else {
                g.emit_aimed(&env, &mut rng)
            };
            if let Some(e) = e.filter(|e| keep(e)) {
                out[0] += e.power.x as f64;
                out[1] += (e.power.x as f64).powi(2);
                out[2] += 1.0;
            }
        }
        out
    }

    /// The power entering the bounding disc is the plain emission's: Σ over both techniques
    /// of L/(n_p·p + n_a·k) estimates ∫∫ L dω dA = 4π L · πr² for a constant sky (the
    /// weights sum to one on every ray the plain emission draws).
    #[test]
    fn both_techniques_carry_the_skys_power() {
        let n = 200_000;
        let (g, b) = (guide(n), bounds());
        let in_disc =
            |e: &Emission| (g.crossing(-e.direction, e.origin) - b.centre).length() <= b.radius;
        let [sum, _, _] = mis_sums(&g, n, 3, &in_disc);
        let expect = 2.0 * 4.0 * PI as f64 * (PI * b.radius * b.radius) as f64;
        assert!((sum / expect - 1.0).abs() < 0.02, "{sum} vs {expect}");
    }

    /// The power that the rays through a small target carry is the plain emission's (what
    /// enters an opening is unchanged), with many more photons.
    #[test]
    fn power_through_an_opening_is_unchanged() {
        let n = 1_000_000;
        let (g, env, b) = (guide(n), constant_sky(), bounds());
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
        // Plain: 2n photons, ~0.25% of them cross it (~5000). The estimates' standard
        // errors from the sample variance; each within 4 of them of the exact flux.
        let mut rng = Rng::new(5, 2, 0);
        let (mut sum, mut sq, mut plain_n) = (0.0f64, 0.0f64, 0u32);
        for _ in 0..2 * n {
            if let Some(e) = env.emit(&mut rng, b).filter(|e| hit(e)) {
                let p = e.power.x as f64 / (2 * n) as f64;
                (sum, sq, plain_n) = (sum + p, sq + p * p, plain_n + 1);
            }
        }
        let [aimed, aimed_sq, aimed_n] = mis_sums(&g, n, 6, &hit);
        // Exact: L · π·0.3² · ∫ over the hemisphere facing the disc of cos dω = L·π·0.09·π.
        let exact = 2.0 * (PI * 0.09) as f64 * PI as f64;
        for (name, mean, sq) in [("plain", sum, sq), ("aimed", aimed, aimed_sq)] {
            // Σ of 2n terms (most zero): its standard error √(Σx² − (Σx)²/2n).
            let se = (sq - mean * mean / (2 * n) as f64).max(0.0).sqrt();
            assert!(se < 0.03 * exact, "{name}: standard error {se}");
            assert!(
                (mean - exact).abs() < 4.0 * se,
                "{name}: {mean} ± {se} vs {exact}"
            );
        }
        assert!(aimed_n > 5.0 * plain_n as f64, "{aimed_n} vs {plain_n}");
    }

    /// A plain photon whose ray no kernel covers keeps its power exactly (bit for bit): the
    /// light of the paths the pilot did not find is today's.
    #[test]
    fn uncovered_plain_photons_are_unchanged() {
        let (g, env) = (guide(1000), constant_sky());
        let mut rng = Rng::new(9, 0, 0);
        let (mut uncovered, mut covered) = (0, 0);
        for _ in 0..20_000 {
            let e = env.emit(&mut rng, bounds()).unwrap();
            let w = g.plain_weight(&env, &e);
            let k = g.kernel_density(-e.direction, g.crossing(-e.direction, e.origin));
            if k == 0.0 {
                assert_eq!(w, 1.0);
                uncovered += 1;
            } else {
                assert!(w > 0.0 && w < 1.0, "{w}");
                covered += 1;
            }
        }
        assert!(uncovered > 1000 && covered > 10, "{uncovered} {covered}");
    }

    /// The direction cells list every kernel a direction can meet: the density over them is
    /// the density over all kernels, for rays everywhere on the sphere and near the kernels
    /// (kernels around the poles and the azimuth seam too).
    #[test]
    fn direction_cells_miss_no_kernel() {
        let b = bounds();
        let mut rng = Rng::new(11, 0, 0);
        let mut rays: Vec<(Vec3, Vec3)> = (0..300)
            .map(|_| {
                let t = crate::sampling::uniform_sphere(rng.next_2d());
                (t, b.centre + Frame::new(t).t * rng.next_f32())
            })
            .collect();
        for t in [Vec3::Y, -Vec3::Y, Vec3::new(-1.0, 0.05, 0.001).normalize()] {
            rays.push((t, b.centre));
        }
        let g = guide_of(&rays, b, 10, 10).unwrap();
        let all = |towards: Vec3, point: Vec3| {
            let c = b.centre;
            g.kernels
                .iter()
                .filter(|k| {
                    let centre = k.point - towards * (k.point - c).dot(towards);
                    k.towards.dot(towards) >= g.cos_k
                        && (point - centre).length_squared() <= g.r_k * g.r_k
                })
                .count()
        };
        let per = 1.0 / (2.0 * PI * (1.0 - g.cos_k) * PI * g.r_k * g.r_k);
        let len = g.kernels.len() as f32;
        let mut met = 0;
        for i in 0..200_000 {
            let (towards, point) = if i % 2 == 0 {
                let t = crate::sampling::uniform_sphere(rng.next_2d());
                (t, b.centre + Frame::new(t).t * (0.5 * rng.next_f32()))
            } else {
                let k = g.kernels[i / 2 % g.kernels.len()];
                let t = Frame::new(k.towards).to_world(uniform_cone(rng.next_2d(), g.cos_k));
                (t, g.crossing(t, k.point))
            };
            let n = all(towards, point);
            met += n;
            assert_eq!(
                g.kernel_density(towards, point),
                per * n as f32 / len,
                "{towards}"
            );
        }
        assert!(met > 100_000, "{met}");
    }

    #[test]
    fn no_guide_for_too_few_or_too_many_marked_rays() {
        let b = bounds();
        let rays = |n: usize| {
            vec![
                SkyRay {
                    towards: Vec3::Y,
                    point: Vec3::ZERO
                };
                n
            ]
        };
        assert!(guide_of(&[(Vec3::Y, Vec3::ZERO); MIN_KERNELS - 1], b, 10, 10).is_none());
        assert!(guide_of(&[(Vec3::Y, Vec3::ZERO); MIN_KERNELS], b, 10, 10).is_some());
        // More than a tenth of the pilot's paths stored photons: an open scene.
        assert!(SkyGuide::new(&rays(101), 1000, b, 10, 10).is_none());
        assert!(SkyGuide::new(&rays(100), 1000, b, 10, 10).is_some());
        assert!(SkyGuide::new(&rays(100), 1000, b, 10, 0).is_none());
    }
}
