//! Local-density bound of caustic photon kernels (issue 11).
//!
//! A caustic photon (light → mirrors/glass → a diffuse surface) keeps the narrowest kernel
//! that path density or its differentials give it, whatever the local photon density: where
//! a curved mirror spreads light thinly, each photon is splatted as an isolated bright dot.
//! Here each caustic photon's kernel radius is bounded by the distance d_k to the k-th
//! nearest caustic photon of the same frame (and light): kept within [LO·d_k, HI·d_k], it is
//! small where caustics focus and wide where they spread (a sample-point density estimate,
//! Jensen's adaptive k-NN radius seen from the photon's side). Methods `ispm` (photon-volume
//! radius) and `gather` (footprint ellipse) apply the same bound, computed on the CPU into
//! the photon data.

use super::{FootprintAxes, KdTree, Neighbour, PathKind, Photon, PhotonSet};
use glam::Vec3;
use rayon::prelude::*;

/// Neighbours that set a caustic photon's density radius.
pub const K: usize = 16;
/// The kernel radius stays within [LO, HI] times the density radius d_k.
pub const LO: f32 = 0.75;
pub const HI: f32 = 1.5;
/// Path density above which an ISPM photon took no Lambertian bounce (one Lambertian bounce
/// multiplies ρp by ρL/1000 ≤ 10⁻³; mirrors, glass and glossy lobes by more).
pub const CAUSTIC_DENSITY: f32 = 2e-3;

/// Whether an ISPM photon (bounce ≥ 1) is a caustic photon.
pub fn is_caustic(p: &Photon) -> bool {
    p.bounce >= 1 && p.path_density > CAUSTIC_DENSITY
}

/// Per point, the distance to its `k`-th nearest other point, at most `max` (also when
/// fewer than `k` others lie within `max`).
pub fn knn_radii(points: &[Vec3], k: usize, max: f32) -> Vec<f32> {
    if points.len() <= k {
        return vec![max; points.len()];
    }
    let tree = KdTree::build(points);
    points
        .par_iter()
        .map_init(Vec::<Neighbour>::new, |scratch, p| {
            tree.nearest(*p, k + 1, max * max, |_| true, scratch);
            if scratch.len() < k + 1 {
                max
            } else {
                scratch[k].dist2.sqrt().min(max)
            }
        })
        .collect()
}

/// `r` kept within [LO·d, HI·d].
pub fn bound(r: f32, d: f32) -> f32 {
    r.clamp(LO * d, HI * d)
}

/// Bounds the ISPM kernel radius (`footprint_radius`, already set) of the caustic photons
/// in `photons` (one light's) by their density radius times `scale` (the progressive
/// pass's radius scale), at most `r_max`.
pub fn bound_volume_radii(photons: &mut [Photon], scale: f32, r_max: f32) {
    let idx: Vec<usize> = (0..photons.len())
        .filter(|&i| is_caustic(&photons[i]))
        .collect();
    let points: Vec<Vec3> = idx.iter().map(|&i| photons[i].position()).collect();
    // d_k is of this pass's photon count: the progressive scale shrinks it as it does the
    // other kernels.
    let d = knn_radii(&points, K, r_max / scale.max(1e-6));
    for (&i, d) in idx.iter().zip(d) {
        let p = &mut photons[i];
        p.footprint_radius = bound(p.footprint_radius, d * scale).min(r_max);
    }
}

/// Bounds the footprints (method `gather`) of the caustic photons of `set` the same way:
/// both semi-axes scaled so that the footprint's radius √|a₁ × a₂| lies within the bound
/// (a degenerate footprint becomes a disc of the bound's lower end).
pub fn bound_footprints(set: &mut PhotonSet, scale: f32, r_max: f32) {
    if set.footprints.len() != set.photons.len() {
        return;
    }
    let idx: Vec<usize> = (0..set.photons.len())
        .filter(|&i| set.footprints[i].kind == PathKind::Caustic)
        .collect();
    let points: Vec<Vec3> = idx.iter().map(|&i| set.photons[i].position()).collect();
    let d = knn_radii(&points, K, r_max / scale.max(1e-6));
    for (&i, d) in idx.iter().zip(d) {
        let p = &mut set.photons[i];
        let f: &mut FootprintAxes = &mut set.footprints[i];
        let r = f.radius();
        let target = bound(r, d * scale).min(r_max);
        if r > 1e-12 && f.axes.iter().all(|a| a.is_finite()) {
            let s = target / r;
            f.axes = f.axes.map(|a| a * s);
        } else {
            let frame = crate::sampling::Frame::new(p.normal());
            f.axes = [frame.t * target, frame.b * target];
        }
        p.footprint_radius = f.radius();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_follows_density() {
        // A dense cluster and a sparse one: d_k 10x apart (spacing 0.01 vs 0.1 on a grid).
        let mut pts = Vec::new();
        for i in 0..10 {
            for j in 0..10 {
                pts.push(Vec3::new(i as f32 * 0.01, 0.0, j as f32 * 0.01));
                pts.push(Vec3::new(10.0 + i as f32 * 0.1, 0.0, j as f32 * 0.1));
            }
        }
        let d = knn_radii(&pts, K, 100.0);
        let (dense, sparse) = (d[2 * 55], d[2 * 55 + 1]);
        assert!((sparse / dense - 10.0).abs() < 0.5, "{dense} {sparse}");
        assert_eq!(bound(0.0, 1.0), LO);
        assert_eq!(bound(9.0, 1.0), HI);
        assert_eq!(bound(1.0, 1.0), 1.0);
        assert!(knn_radii(&pts[..5], K, 3.0).iter().all(|&r| r == 3.0));
    }
}
