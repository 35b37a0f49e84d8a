//! The photon map (photons + kd-tree) and Jensen's k-nearest-neighbour radiance estimate
//!
//! `L(x, ωo) ≈ Σ_p f(ωo, ωp)·Φp·κ(|xp − x|, r)`
//!
//! over the k nearest photons within the maximum radius (r = the k-th distance, or the
//! maximum radius when fewer are found), with a kernel κ normalised over the disc of radius
//! r (1/m²). Only photons whose stored normal agrees with the shading normal count, which
//! keeps light from leaking through thin walls. Kernels that vanish at r (cone,
//! Epanechnikov) make the k-th photon weightless, so the estimate is effectively
//! (k − 1)/(πr²), the unbiased kNN density for uniformly spread photons.

use super::{KdTree, Neighbour, Photon};
use crate::cancel::{self, Progress};
use crate::error::{Error, Result};
use crate::memory;
use crate::trace::Interaction;
use glam::Vec3;
use std::f32::consts::PI;
use std::str::FromStr;

/// Minimum cosine between a photon's normal and the shading normal for it to count.
pub const NORMAL_AGREEMENT: f32 = 0.5;

/// Density estimation kernel over the gather disc.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Kernel {
    /// Constant 1/(πr²).
    Box,
    /// Jensen's cone filter (k = 1): 3/(πr²)·(1 − d/r).
    #[default]
    Cone,
    /// 2D Epanechnikov: 2/(πr²)·(1 − d²/r²).
    Epanechnikov,
}

impl Kernel {
    pub const ALL: &'static [Kernel] = &[Kernel::Box, Kernel::Cone, Kernel::Epanechnikov];

    pub fn name(self) -> &'static str {
        match self {
            Kernel::Box => "box",
            Kernel::Cone => "cone",
            Kernel::Epanechnikov => "epanechnikov",
        }
    }

    /// Weight (1/m²) at squared distance `d2` inside a disc of squared radius `r2`.
    #[inline]
    pub fn weight(self, d2: f32, r2: f32) -> f32 {
        let norm = 1.0 / (PI * r2);
        match self {
            Kernel::Box => norm,
            Kernel::Cone => 3.0 * norm * (1.0 - (d2 / r2).sqrt()).max(0.0),
            Kernel::Epanechnikov => 2.0 * norm * (1.0 - d2 / r2).max(0.0),
        }
    }
}

impl FromStr for Kernel {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        crate::error::parse_named(s, Kernel::ALL, Kernel::name, "kernel", "kernel")
    }
}

/// Parameters of a radiance estimate.
#[derive(Clone, Copy, Debug)]
pub struct Gather {
    /// Photons per estimate.
    pub k: usize,
    /// Maximum gather radius (m).
    pub max_radius: f32,
    pub kernel: Kernel,
}

/// Default maximum gather radius, as a fraction of the scene's bounding-box diagonal.
const DEFAULT_RADIUS_FRACTION: f32 = 0.05;

impl Gather {
    /// The estimate of `k` photons within `max_radius` (`None`: 5% of the scene's
    /// diagonal) with `kernel`, both shrunk by a progressive pass's `radius_scale` (the
    /// count through k ∝ r²).
    pub fn new(
        scene: &crate::scene::Scene,
        k: u32,
        max_radius: Option<f32>,
        kernel: Kernel,
        radius_scale: f32,
    ) -> Gather {
        let s2 = radius_scale * radius_scale;
        Gather {
            k: ((k as f32 * s2).round() as usize).max(1),
            max_radius: radius_scale
                * max_radius.unwrap_or_else(|| DEFAULT_RADIUS_FRACTION * scene.diagonal()),
            kernel,
        }
    }
}

/// Stored photons and the kd-tree over their positions.
#[derive(Clone, Debug, Default)]
pub struct PhotonMap {
    pub photons: Vec<Photon>,
    tree: KdTree,
}

impl PhotonMap {
    pub fn build(photons: Vec<Photon>) -> Self {
        let positions: Vec<Vec3> = photons.iter().map(Photon::position).collect();
        PhotonMap {
            tree: KdTree::build(&positions),
            photons,
        }
    }

    /// [`PhotonMap::build`] after checking that the kd-tree fits in memory, cancelled
    /// (between nodes) when `progress` asks.
    pub fn try_build(photons: Vec<Photon>, progress: &dyn Progress) -> Result<Self> {
        let n = photons.len() as u64;
        // Positions, the (position, index) items being sorted, and the tree's arrays.
        let bytes = n * (12 + 16 + 12 + 4 + 1);
        memory::check(|| format!("the kd-tree over {n} photons"), bytes)?;
        let stage = cancel::StageProgress::new(progress, "kd-tree build", 1);
        let positions: Vec<Vec3> = photons.iter().map(Photon::position).collect();
        let tree = KdTree::build_until(&positions, &|| stage.stopped()).ok_or(Error::Cancelled)?;
        stage.advance(1);
        stage.finish()?;
        Ok(PhotonMap { tree, photons })
    }

    /// Radiance (W·sr⁻¹·m⁻² per channel) leaving `it` towards `wo` (world space, pointing
    /// away from the surface) by the non-delta lobes. `scratch` is reused between calls.
    pub fn radiance(
        &self,
        it: &Interaction,
        wo: Vec3,
        g: &Gather,
        scratch: &mut Vec<Neighbour>,
    ) -> Vec3 {
        if it.material.is_purely_specular() {
            return Vec3::ZERO;
        }
        let n = it.frame.n * it.ng.dot(wo).signum();
        match self.neighbours(it.position, n, |_| true, g, scratch) {
            Some(r2) => self.kernel_sum(it, wo, g, scratch, r2),
            None => Vec3::ZERO,
        }
    }

    /// The k nearest photons to `at` within the maximum radius whose normals agree with the
    /// oriented normal `n` and which `eligible` accepts, into `scratch`, and the squared
    /// estimate radius: the k-th distance, or the maximum radius when fewer are found
    /// (`None`: none found).
    fn neighbours(
        &self,
        at: Vec3,
        n: Vec3,
        eligible: impl Fn(u32) -> bool,
        g: &Gather,
        scratch: &mut Vec<Neighbour>,
    ) -> Option<f32> {
        let max_r2 = g.max_radius * g.max_radius;
        let accept =
            |i: u32| eligible(i) && self.photons[i as usize].normal().dot(n) > NORMAL_AGREEMENT;
        self.tree.nearest(at, g.k, max_r2, accept, scratch);
        let r2 = if scratch.len() == g.k {
            scratch.last().map_or(max_r2, |nb| nb.dist2)
        } else {
            max_r2
        };
        (!scratch.is_empty() && r2 > 0.0).then_some(r2)
    }

    /// Σ f(wo, wᵢ)·Φ·κ(d², r²) over the `picked` neighbours. Where the material is
    /// Lambertian (`Material::lambertian`), f is ρ/π on the side of `wo` and 0 on the other,
    /// so the sum is ρ/π times the kernel-weighted power of the photons arriving on that
    /// side: one product instead of a BSDF evaluation per photon.
    fn kernel_sum(
        &self,
        it: &Interaction,
        wo: Vec3,
        g: &Gather,
        picked: &[Neighbour],
        r2: f32,
    ) -> Vec3 {
        let wo_l = it.frame.to_local(wo);
        if let Some(f) = it.material.lambertian() {
            let side = wo_l.z;
            let power: Vec3 = picked
                .iter()
                .map(|nb| {
                    let p = &self.photons[nb.index as usize];
                    if side * it.frame.n.dot(p.incident()) > 0.0 {
                        p.power() * g.kernel.weight(nb.dist2, r2)
                    } else {
                        Vec3::ZERO
                    }
                })
                .sum();
            return f * power;
        }
        picked
            .iter()
            .map(|nb| {
                let p = &self.photons[nb.index as usize];
                it.material.eval(wo_l, it.frame.to_local(p.incident()))
                    * p.power()
                    * g.kernel.weight(nb.dist2, r2)
            })
            .sum()
    }
}

impl PhotonMap {
    /// The kernel-weighted power Σ Φ·κ(d², r²) of the k nearest photons to `at` whose
    /// normals agree with the oriented normal `n` and which arrived on its side, and the
    /// squared estimate radius r² (`None`: no photon found): what [`PhotonMap::radiance`]
    /// multiplies by ρ/π on a Lambertian surface, here for a normal of the caller's choice.
    /// Only the photons `eligible` accepts count.
    pub fn side_power(
        &self,
        at: Vec3,
        n: Vec3,
        eligible: impl Fn(u32) -> bool,
        g: &Gather,
        scratch: &mut Vec<Neighbour>,
    ) -> Option<(Vec3, f32)> {
        let r2 = self.neighbours(at, n, eligible, g, scratch)?;
        let power = scratch
            .iter()
            .map(|nb| {
                let p = &self.photons[nb.index as usize];
                if n.dot(p.incident()) > 0.0 {
                    p.power() * g.kernel.weight(nb.dist2, r2)
                } else {
                    Vec3::ZERO
                }
            })
            .sum();
        Some((power, r2))
    }
}

/// Anchors a [`GatherCache`] keeps (a camera path's landing points alternate between a few
/// regions, e.g. the reflected and the refracted path of a glass sample).
const ANCHORS: usize = 8;
/// An anchor holds the photons within (1 + this) × its own k-th neighbour distance.
const ANCHOR_MARGIN: f32 = 1.0;

/// A photon near an anchor, with what the normal test needs.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    position: Vec3,
    normal: Vec3,
    index: u32,
}

/// Every photon within `radius` of `centre`, whatever its normal.
#[derive(Clone, Debug, Default)]
struct Anchor {
    centre: Vec3,
    radius: f32,
    photons: Vec<Candidate>,
}

/// Per-thread state of [`PhotonMap::radiance_cached`]: the photons around a few recent
/// query points, so that a query near one of them selects its k nearest among a few
/// hundred candidates instead of searching the kd-tree.
#[derive(Clone, Debug, Default)]
pub struct GatherCache {
    anchors: Vec<Anchor>,
    next: usize,
    picked: Vec<Neighbour>,
    found: Vec<(Vec3, u32)>,
    /// Queries answered from an anchor, and anchors built (a search each).
    pub hits: u64,
    pub misses: u64,
}

impl GatherCache {
    /// The `k` nearest photons to `q` within `max_r2` whose normal agrees with `n`, into
    /// `picked` (unordered), when anchor `a` provably holds all of them: every photon
    /// closer to `q` than the k-th (or than the maximum radius when fewer are found) lies
    /// within the anchor's radius. Returns the squared estimate radius, else `None`.
    fn select(&mut self, a: usize, q: Vec3, n: Vec3, k: usize, max_r2: f32) -> Option<f32> {
        let anchor = &self.anchors[a];
        // Photons within `limit` of q lie within the anchor's radius of its centre; shrunk
        // a little against rounding.
        let limit = (anchor.radius - anchor.centre.distance(q)) * (1.0 - 1e-5);
        if limit < 0.0 {
            return None;
        }
        let limit2 = limit * limit;
        self.picked.clear();
        for c in &anchor.photons {
            if c.normal.dot(n) > NORMAL_AGREEMENT {
                let dist2 = c.position.distance_squared(q);
                if dist2 <= max_r2 {
                    self.picked.push(Neighbour {
                        index: c.index,
                        dist2,
                    });
                }
            }
        }
        if self.picked.len() < k {
            return (max_r2 <= limit2).then_some(max_r2);
        }
        // The k smallest by (distance, index), as the kd-tree's query orders them.
        if self.picked.len() > k {
            self.picked.select_nth_unstable(k - 1);
            self.picked.truncate(k);
        }
        let r2 = self.picked.iter().map(|nb| nb.dist2).fold(0.0, f32::max);
        (r2 <= limit2).then_some(r2)
    }
}

impl PhotonMap {
    /// [`PhotonMap::radiance`], the same estimate (the same photons; summed in another
    /// order), answered from `cache` where one of its anchors holds the neighbourhood
    /// (else a kd-tree search builds a new anchor there). Fast for coherent queries.
    pub fn radiance_cached(
        &self,
        it: &Interaction,
        wo: Vec3,
        g: &Gather,
        cache: &mut GatherCache,
    ) -> Vec3 {
        if it.material.is_purely_specular() || g.k == 0 {
            return Vec3::ZERO;
        }
        let n = it.frame.n * it.ng.dot(wo).signum();
        let q = it.position;
        let max_r2 = g.max_radius * g.max_radius;
        let mut r2 = (0..cache.anchors.len()).find_map(|a| cache.select(a, q, n, g.k, max_r2));
        if r2.is_some() {
            cache.hits += 1;
        } else {
            cache.misses += 1;
            let accept = |i: u32| self.photons[i as usize].normal().dot(n) > NORMAL_AGREEMENT;
            self.tree.nearest(q, g.k, max_r2, accept, &mut cache.picked);
            let rk = if cache.picked.len() == g.k {
                cache
                    .picked
                    .last()
                    .map_or(g.max_radius, |nb| nb.dist2.sqrt())
            } else {
                g.max_radius
            };
            let radius = rk * (1.0 + ANCHOR_MARGIN);
            cache.found.clear();
            self.tree.within(q, radius * radius, &mut cache.found);
            let anchor = Anchor {
                centre: q,
                radius,
                photons: cache
                    .found
                    .iter()
                    .map(|&(position, index)| Candidate {
                        position,
                        normal: self.photons[index as usize].normal(),
                        index,
                    })
                    .collect(),
            };
            if cache.anchors.len() < ANCHORS {
                cache.anchors.push(anchor);
            } else {
                cache.anchors[cache.next] = anchor;
            }
            cache.next = (cache.next + 1) % ANCHORS;
            // `picked` holds the search's answer.
            r2 = Some(if cache.picked.len() == g.k {
                cache.picked.last().map_or(max_r2, |nb| nb.dist2)
            } else {
                max_r2
            });
        }
        let r2 = r2.unwrap_or(max_r2);
        if cache.picked.is_empty() || r2 <= 0.0 {
            return Vec3::ZERO;
        }
        self.kernel_sum(it, wo, g, &cache.picked, r2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each kernel integrates to 1 over its disc (midpoint rule over rings).
    #[test]
    fn kernels_are_normalised() {
        let r2 = 0.04f32;
        let r = r2.sqrt();
        for &k in Kernel::ALL {
            let n = 10_000;
            let sum: f32 = (0..n)
                .map(|i| {
                    let d = (i as f32 + 0.5) / n as f32 * r;
                    k.weight(d * d, r2) * 2.0 * PI * d * (r / n as f32)
                })
                .sum();
            assert!((sum - 1.0).abs() < 1e-3, "{k:?}: {sum}");
        }
    }
}

#[cfg(test)]
mod cache_tests {
    use super::*;
    use crate::photon::{emit_and_trace, PhotonTraceSettings};
    use crate::trace::SceneBvh;

    /// `radiance_cached` gives `radiance`'s estimate (the same k photons; another summation
    /// order, so within 1e-5 relative) at the landing points of coherent camera rays
    /// reflected by `cornell-glass`'s spheres and at every first hit, for a small and a
    /// large k, with the cache both hit and missed.
    #[test]
    fn cached_gather_equals_the_kd_tree_gather() {
        let mut scene = crate::scene::builtin::load("cornell-glass").unwrap();
        scene.camera = scene.camera.with_size(64, 48);
        let bvh = SceneBvh::build(&scene);
        let pts = PhotonTraceSettings {
            max_bounces: 4,
            store_direct: true,
            differentials: None,
        };
        let map = PhotonMap::build(emit_and_trace(&scene, &bvh, 30_000, &pts, 3).photons);
        for k in [8, 100] {
            let g = Gather {
                k,
                max_radius: 0.2,
                kernel: Kernel::Cone,
            };
            let (mut cache, mut scratch, mut checked) = (GatherCache::default(), Vec::new(), 0);
            for y in 0..48 {
                for x in 0..64 {
                    let cam = &scene.camera;
                    let d = cam.direction(x as f32 + 0.5, y as f32 + 0.5);
                    let Some(hit) = bvh.intersect(cam.position, d, f32::INFINITY) else {
                        continue;
                    };
                    let mut it = Interaction::new(&scene, &hit, d);
                    let mut wo = -d;
                    if it.material.is_purely_specular() {
                        // Follow the mirror direction once (glass: its reflection).
                        let wi = 2.0 * wo.dot(it.ng) * it.ng - wo;
                        let Some(h2) = bvh.intersect(it.spawn(wi), wi, f32::INFINITY) else {
                            continue;
                        };
                        it = Interaction::new(&scene, &h2, wi);
                        wo = -wi;
                    }
                    let want = map.radiance(&it, wo, &g, &mut scratch);
                    let got = map.radiance_cached(&it, wo, &g, &mut cache);
                    let tol = want.abs() * 1e-5 + Vec3::splat(1e-7);
                    assert!(
                        (got - want).abs().cmple(tol).all(),
                        "k {k}, pixel ({x}, {y}): {got} vs {want}"
                    );
                    checked += 1;
                }
            }
            assert!(checked > 2000, "{checked} queries");
            // With k = 100 many queries reuse an anchor (k = 8 anchors are too small).
            let (hits, misses) = (cache.hits, cache.misses);
            assert!(
                misses > 10 && (k < 100 || hits > 500),
                "{hits} hits, {misses} misses"
            );
        }
    }
}
