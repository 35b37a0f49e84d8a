//! Boundary compensation of splatted photon kernels. A photon near the edge of a surface
//! (a wall meeting the floor, the top edge of a box) has part of its kernel disc off the
//! surface, and the energy that falls there is lost: ISPM's photon volumes measured 1–4% too
//! little indirect light in the Cornell box, growing with the kernel radius. Each photon's
//! kernel coverage f = ∫ κ·[surface there] / ∫ κ is estimated with a few probe rays, and its
//! power divided by f, so that what lands on the surface adds up to the photon's power.
//!
//! A probe takes a point of the disc distributed like the (Epanechnikov) kernel and casts a
//! ray from above it (`z_ratio`·r along the photon's normal, the volume's half-thickness)
//! down through the volume: the point counts if the ray meets a surface within the volume
//! whose normal agrees with the photon's, which is the test the splat applies per pixel.

use super::knn::Kernel;
use super::knn::NORMAL_AGREEMENT;
use super::{Photon, PhotonSet};
use crate::sampling::{Frame, Rng};
use crate::scene::Scene;
use crate::trace::{Interaction, SceneBvh};
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// Probe rays per photon that may be off a surface (stratified in angle and radius).
pub const PROBES: u32 = 8;
/// Quick tests first: whether the disc lies inside one triangle; then probes on a ring at this fraction of the radius, one per quadrant. When
/// all four find the surface the photon counts as fully covered, which saves two thirds of
/// the rays in the interior of surfaces (most photons); an edge that cuts off less than
/// about 4% of the kernel can slip through.
const RING_PROBES: u32 = 4;
const RING_RADIUS: f32 = 0.8;
/// Smallest coverage divided out: a photon is at most 4× brightened (a photon in a corner
/// of three walls keeps f ≈ 1/4; lower estimates are mostly probe noise on small objects).
pub const MIN_COVERAGE: f32 = 0.25;

/// Whether the surface the splat would shade is under the point at offset (`d`, angle `a`)
/// in the photon's tangent plane.
fn probe(scene: &Scene, bvh: &SceneBvh, p: &Photon, frame: &Frame, d: f32, a: f32, h: f32) -> bool {
    let q = p.position() + d * (a.cos() * frame.t + a.sin() * frame.b);
    probe_at(scene, bvh, q, frame.n, h)
}

/// Whether a surface facing `n` lies within `h` of the point `q` along `n`.
fn probe_at(scene: &Scene, bvh: &SceneBvh, q: Vec3, n: Vec3, h: f32) -> bool {
    let Some(hit) = bvh.intersect(q + h * n, -n, 2.0 * h) else {
        return false;
    };
    let (ng, ns, _) = Interaction::normals(scene, &hit, -n);
    let ns = ns * ng.dot(n).signum();
    ns.dot(n) > NORMAL_AGREEMENT
}

/// Whether the kernel disc of radius `r` lies inside the triangle under the photon, which
/// settles full coverage with one ray for photons on large triangles (walls, floors).
fn disc_inside_triangle(scene: &Scene, bvh: &SceneBvh, p: &Photon, r: f32, h: f32) -> bool {
    let n = p.normal();
    let Some(hit) = bvh.intersect(p.position() + h * n, -n, 2.0 * h) else {
        return false;
    };
    let [a, b, c] = scene.triangle(hit.triangle as usize);
    let ng = (b - a).cross(c - a).normalize_or_zero();
    if ng.dot(n).abs() <= NORMAL_AGREEMENT {
        return false;
    }
    // In-plane distance from the hit point to each edge, on the inner side of all three.
    let x = p.position() + (h - hit.t) * n;
    [(a, b), (b, c), (c, a)].iter().all(|&(u, v)| {
        let inward = ng.cross(v - u).normalize_or_zero();
        (x - u).dot(inward) >= r
    })
}

/// Fraction of the kernel of radius `r` around photon `p` that lies on surfaces the splat
/// would shade.
pub fn coverage(
    scene: &Scene,
    bvh: &SceneBvh,
    p: &Photon,
    r: f32,
    z_ratio: f32,
    rng: &mut Rng,
) -> f32 {
    let frame = Frame::new(p.normal());
    let h = z_ratio * r;
    if disc_inside_triangle(scene, bvh, p, r, h) {
        return 1.0;
    }
    let turn = rng.next_f32();
    if (0..RING_PROBES).all(|i| {
        let a = (i as f32 + turn) / RING_PROBES as f32 * std::f32::consts::TAU;
        probe(scene, bvh, p, &frame, RING_RADIUS * r, a, h)
    }) {
        return 1.0;
    }
    // Latin-hypercube strata: angle i, radius (i·3 mod 8).
    let hits = (0..PROBES)
        .filter(|&i| {
            let a = (i as f32 + rng.next_f32()) / PROBES as f32 * std::f32::consts::TAU;
            let xi = (((i * 3) % PROBES) as f32 + rng.next_f32()) / PROBES as f32;
            // Epanechnikov radial density ∝ (1 − d²/r²)·d: u = d²/r² has CDF 2u − u².
            let d = r * (1.0 - (1.0 - xi).sqrt()).sqrt();
            probe(scene, bvh, p, &frame, d, a, h)
        })
        .count();
    hits as f32 / PROBES as f32
}

/// Moments of the Epanechnikov kernel (normalised: ∫κ = 1 over the whole disc) over the
/// part of its disc that lies on surfaces the splat shades, with u the offset from the
/// centre in units of the radius, in the (t, b) axes of `Frame::new(normal)`:
/// m0 = ∫κ (the coverage), m1 = ∫κ u, m2 = ∫κ u uᵀ (xx, xy, yy).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoveredMoments {
    pub m0: f32,
    pub m1: Vec2,
    pub m2: [f32; 3],
}

impl CoveredMoments {
    /// The whole disc: E\[u²\] = E\[s²\]/2 = 1/6 per axis (radial density ∝ (1 − s²)s).
    pub const FULL: CoveredMoments = CoveredMoments {
        m0: 1.0,
        m1: Vec2::ZERO,
        m2: [1.0 / 6.0, 0.0, 1.0 / 6.0],
    };
}

/// Directions of [`coverage_moments`], the bisection steps along each (and along the rim
/// where the cover starts or stops reaching it), and the sub-angles each gap between two
/// boundary points is integrated with.
pub const MOMENT_DIRECTIONS: u32 = 8;
pub const MOMENT_BISECTIONS: u32 = 4;
const MOMENT_SUBANGLES: u32 = 8;

/// [`coverage`] with the first and second moments of the covered part of the kernel
/// ([`CoveredMoments`]), traced instead of counted: full when the disc lies inside one
/// triangle, else the boundary of the cover, and the kernel's moments over it
/// integrated in closed form along the radius. The boundary: along [`MOMENT_DIRECTIONS`]
/// evenly spaced directions (rotated at random), a probe at the rim and, where it misses,
/// [`MOMENT_BISECTIONS`] bisection steps for the distance where the surface ends; between a
/// direction that reaches the rim and one that does not, bisection along the rim for where
/// the cover leaves it. Between two boundary points the boundary is the rim where both lie
/// on it, else the straight segment between them: exact for a disc cut by straight creases
/// and edges (up to the bisections' 1/32, and a corner between two samples). Counted probes
/// are noisy (and 1/coverage of a noisy count is biased, see
/// `frame::progressive::query_coverage`); evenly spaced directions without the rim crossings
/// miss where the cut starts by up to a sector (m0 0.530 against 0.542 at a wall).
pub fn coverage_moments(
    scene: &Scene,
    bvh: &SceneBvh,
    p: &Photon,
    r: f32,
    z_ratio: f32,
    rng: &mut Rng,
) -> CoveredMoments {
    let frame = Frame::new(p.normal());
    let h = z_ratio * r;
    if disc_inside_triangle(scene, bvh, p, r, h) {
        return CoveredMoments::FULL;
    }
    let on = |s: f32, a: f32| probe(scene, bvh, p, &frame, s * r, a, h);
    // Boundary points (angle, distance in units of r); 1 = on the rim.
    let da = std::f32::consts::TAU / MOMENT_DIRECTIONS as f32;
    let turn = rng.next_f32();
    let rim: Vec<(f32, bool)> = (0..MOMENT_DIRECTIONS)
        .map(|i| {
            let a = (i as f32 + turn) * da;
            (a, on(1.0, a))
        })
        .collect();
    // All directions reach the rim: whole (a cut missed between two of them leaves out less
    // than 0.2% of the kernel). The 4 probes at 0.8 r of [`coverage`] are no test here:
    // they miss a cut 0.6 r away one time in ten (−0.7% at such a pixel, measured).
    if rim.iter().all(|&(_, full)| full) {
        return CoveredMoments::FULL;
    }
    let mut points: Vec<(f32, f32)> = Vec::with_capacity(2 * rim.len());
    for (i, &(a, full)) in rim.iter().enumerate() {
        let end = if full {
            1.0
        } else {
            let (mut lo, mut hi) = (0.0f32, 1.0f32);
            for _ in 0..MOMENT_BISECTIONS {
                let mid = 0.5 * (lo + hi);
                if on(mid, a) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            0.5 * (lo + hi)
        };
        points.push((a, end));
        let next = rim[(i + 1) % rim.len()].1;
        if full != next {
            // The rim crossing between this direction and the next.
            let (mut lo, mut hi) = (a, a + da);
            for _ in 0..MOMENT_BISECTIONS {
                let mid = 0.5 * (lo + hi);
                if on(1.0, mid) == full {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            points.push((0.5 * (lo + hi), 1.0));
        }
    }
    let mut m = CoveredMoments {
        m0: 0.0,
        m1: Vec2::ZERO,
        m2: [0.0; 3],
    };
    let dir = |a: f32| Vec2::new(a.cos(), a.sin());
    for (i, &(a0, e0)) in points.iter().enumerate() {
        let (mut a1, e1) = points[(i + 1) % points.len()];
        if a1 <= a0 {
            a1 += std::f32::consts::TAU;
        }
        let (p0, p1) = (e0 * dir(a0), e1 * dir(a1));
        let rim_arc = e0 >= 1.0 && e1 >= 1.0;
        let step = (a1 - a0) / MOMENT_SUBANGLES as f32;
        for k in 0..MOMENT_SUBANGLES {
            let a = a0 + (k as f32 + 0.5) * step;
            let d = dir(a);
            // Where the ray at angle a meets the segment p0 p1 (t d = p0 + λ (p1 − p0)).
            let cross = |u: Vec2, v: Vec2| u.x * v.y - u.y * v.x;
            let end = if rim_arc {
                1.0
            } else {
                let t = cross(p0, p1 - p0) / cross(d, p1 - p0);
                if t.is_finite() && t > 0.0 {
                    t.min(1.0)
                } else {
                    e0.min(e1)
                }
            };
            // κ = 2/π (1 − s²) over [0, end] × step: ∫(1 − s²) s^(k+1) ds.
            let s2 = end * end;
            let w0 = s2 / 2.0 - s2 * s2 / 4.0;
            let w1 = end * s2 / 3.0 - end * s2 * s2 / 5.0;
            let w2 = s2 * s2 / 4.0 - s2 * s2 * s2 / 6.0;
            let c = 2.0 / std::f32::consts::PI * step;
            m.m0 += c * w0;
            m.m1 += c * w1 * d;
            m.m2[0] += c * w2 * d.x * d.x;
            m.m2[1] += c * w2 * d.x * d.y;
            m.m2[2] += c * w2 * d.y * d.y;
        }
    }
    m
}

/// Divides every photon's power by its kernel coverage (`radius(p)` is the kernel radius the
/// splat will use).
pub fn compensate(
    scene: &Scene,
    bvh: &SceneBvh,
    photons: &mut [Photon],
    radius: impl Fn(&Photon) -> f32 + Sync,
    z_ratio: f32,
    seed: u64,
) {
    compensate_until(scene, bvh, photons, radius, z_ratio, seed, &|| false);
}

/// [`compensate`] that leaves the remaining photons alone once `stop()` holds (asked per
/// photon); the caller then discards them.
pub fn compensate_until(
    scene: &Scene,
    bvh: &SceneBvh,
    photons: &mut [Photon],
    radius: impl Fn(&Photon) -> f32 + Sync,
    z_ratio: f32,
    seed: u64,
    stop: &(dyn Fn() -> bool + Sync),
) {
    photons.par_iter_mut().enumerate().for_each(|(i, p)| {
        if stop() {
            return;
        }
        let mut rng = Rng::new(seed, 0xb0da, i as u64);
        let f = coverage(scene, bvh, p, radius(p), z_ratio, &mut rng).max(MIN_COVERAGE);
        p.power = (p.power() / f).into();
    });
}

/// Radius fraction u = d/r of a point distributed like `kernel` over the unit disc (radial
/// density ∝ kernel(u)·u), from ξ in [0, 1).
fn kernel_radius(kernel: Kernel, xi: f32) -> f32 {
    match kernel {
        Kernel::Box => xi.sqrt(),
        // Density 6u(1 − u), CDF 3u² − 2u³ (a Beta(2, 2)): its closed-form inverse.
        Kernel::Cone => 0.5 - (((1.0 - 2.0 * xi).clamp(-1.0, 1.0)).asin() / 3.0).sin(),
        Kernel::Epanechnikov => (1.0 - (1.0 - xi).sqrt()).sqrt(),
    }
}

/// Fraction of the elliptical footprint of a gather photon (semi-axes `axes` in its surface
/// plane, half-thickness `h`, weighted by `kernel`) that lies on surfaces the gather would
/// shade: the probes of [`coverage`], placed on the ellipse.
pub fn footprint_coverage(
    scene: &Scene,
    bvh: &SceneBvh,
    p: &Photon,
    axes: [Vec3; 2],
    h: f32,
    kernel: Kernel,
    rng: &mut Rng,
) -> f32 {
    let r = axes[0].length().max(axes[1].length());
    if !(r.is_finite() && r > 0.0) || disc_inside_triangle(scene, bvh, p, r, h) {
        return 1.0;
    }
    let n = p.normal();
    let at = |u: f32, a: f32| p.position() + u * (a.cos() * axes[0] + a.sin() * axes[1]);
    let turn = rng.next_f32();
    if (0..RING_PROBES).all(|i| {
        let a = (i as f32 + turn) / RING_PROBES as f32 * std::f32::consts::TAU;
        probe_at(scene, bvh, at(RING_RADIUS, a), n, h)
    }) {
        return 1.0;
    }
    let hits = (0..PROBES)
        .filter(|&i| {
            let a = (i as f32 + rng.next_f32()) / PROBES as f32 * std::f32::consts::TAU;
            let xi = (((i * 3) % PROBES) as f32 + rng.next_f32()) / PROBES as f32;
            probe_at(scene, bvh, at(kernel_radius(kernel, xi), a), n, h)
        })
        .count();
    hits as f32 / PROBES as f32
}

/// Divides the power of every gather photon of `set` (with footprints) by its footprint
/// coverage; `thickness` is the footprints' half-thickness over their smaller semi-axis.
pub fn compensate_footprints(
    scene: &Scene,
    bvh: &SceneBvh,
    set: &mut PhotonSet,
    thickness: f32,
    kernel: Kernel,
    seed: u64,
) {
    if set.footprints.len() != set.photons.len() {
        return;
    }
    set.photons
        .par_iter_mut()
        .zip(&set.footprints)
        .enumerate()
        .for_each(|(i, (p, f))| {
            let mut rng = Rng::new(seed, 0xb0db, i as u64);
            let h = thickness * f.axes[0].length().min(f.axes[1].length());
            let c = footprint_coverage(scene, bvh, p, f.axes, h, kernel, &mut rng);
            p.power = (p.power() / c.max(MIN_COVERAGE)).into();
        });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    fn photon_at(position: [f32; 3], normal: [f32; 3]) -> Photon {
        Photon {
            position,
            normal,
            power: [1.0; 3],
            ..Default::default()
        }
    }

    /// Cornell floor (y = 0, |x|, |z| ≤ 1): full coverage in the middle, about half at a
    /// wall, about a quarter in a corner (estimates of 8 probes: averaged over 200 seeds).
    #[test]
    fn coverage_follows_the_edges_of_the_floor() {
        let scene = builtin::load("cornell").unwrap();
        let bvh = SceneBvh::build(&scene);
        let mean = |pos: [f32; 3]| {
            let p = photon_at(pos, [0.0, 1.0, 0.0]);
            (0..200)
                .map(|s| coverage(&scene, &bvh, &p, 0.1, 0.5, &mut Rng::new(s, 0, 0)))
                .sum::<f32>()
                / 200.0
        };
        let (middle, wall, corner) = (
            mean([-0.5, 0.0, 0.6]),
            mean([-0.999, 0.0, 0.3]),
            mean([-0.999, 0.0, -0.999]),
        );
        assert_eq!(middle, 1.0);
        assert!((wall - 0.5).abs() < 0.05, "{wall}");
        assert!((corner - 0.25).abs() < 0.05, "{corner}");
    }

    /// A gather footprint 0.1 from the left wall of the Cornell floor: with its long semi-axis
    /// (0.2) along the wall it is whole; across the wall the cone kernel beyond half that
    /// axis is cut off, 11.0% of its weight (numerical integral: 0.890 stays). Mean of 400
    /// estimates of 8 probes, standard error ≈ 0.006: 0.03 is five of them.
    #[test]
    fn footprint_coverage_follows_the_ellipse() {
        let scene = builtin::load("cornell").unwrap();
        let bvh = SceneBvh::build(&scene);
        let p = photon_at([-0.9, 0.0, 0.3], [0.0, 1.0, 0.0]);
        let (x, z) = (Vec3::X, Vec3::Z);
        let mean = |axes: [Vec3; 2]| {
            (0..400)
                .map(|s| {
                    let mut rng = Rng::new(s, 1, 0);
                    footprint_coverage(&scene, &bvh, &p, axes, 0.015, Kernel::Cone, &mut rng)
                })
                .sum::<f32>()
                / 400.0
        };
        assert_eq!(mean([0.05 * x, 0.2 * z]), 1.0);
        let across = mean([0.2 * x, 0.05 * z]);
        assert!((across - 0.890).abs() < 0.03, "{across}");
        // The radial samples follow each kernel: mean radius fraction 2/3 (box), 1/2 (cone),
        // 8/15 (Epanechnikov).
        for (k, want) in [
            (Kernel::Box, 2.0 / 3.0),
            (Kernel::Cone, 0.5),
            (Kernel::Epanechnikov, 8.0 / 15.0),
        ] {
            let m = (0..10_000)
                .map(|i| kernel_radius(k, (i as f32 + 0.5) / 10_000.0))
                .sum::<f32>()
                / 10_000.0;
            assert!((m - want).abs() < 1e-3, "{k:?} {m}");
        }
    }

    /// The one-ray shortcut: a disc well inside one floor triangle is recognised, one that
    /// reaches over the wall or across the quad's diagonal is not.
    #[test]
    fn disc_inside_triangle_checks_all_edges() {
        let scene = builtin::load("cornell").unwrap();
        let bvh = SceneBvh::build(&scene);
        let at = |pos: [f32; 3], r: f32| {
            disc_inside_triangle(&scene, &bvh, &photon_at(pos, [0.0, 1.0, 0.0]), r, 0.5 * r)
        };
        assert!(at([0.0, 0.0, -0.75], 0.1));
        assert!(!at([0.0, 0.0, -0.75], 0.3), "crosses the back wall");
        assert!(!at([-0.95, 0.0, 0.3], 0.1), "crosses the left wall");
        assert!(!at([0.05, 0.0, 0.0], 0.1), "crosses the diagonal");
    }
}
