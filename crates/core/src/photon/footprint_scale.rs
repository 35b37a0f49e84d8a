//! Footprints sized for a number of photons per estimate (method `gather`).
//!
//! Photon differentials size each footprint from the photon density, so a footprint holds
//! about as many photons whatever the photon count (~120 at s = 1 in `cornell`, 140–180 in
//! `cornell-glass`, at 20k and 200k photons alike), and that number depends on the scene.
//! Fabianowski and Dingliana adjust the smoothing factor s "for optimal image quality in
//! each scene", which puts 175–480 photon hits in each estimate (§7, Table 2). Here that
//! choice is made per frame: the diffusely reflected photons' footprints are scaled
//! uniformly so that the mean number of footprints containing a stored photon's position
//! is a target (`gather`'s smoothing s asks for s² times [`PHOTONS_PER_ESTIMATE`]). The
//! gather's cost per shading point follows that number, not the photon count; more photons
//! make the footprints smaller (less bias) at the same noise.
//!
//! Caustic photons keep their sizes (their density bound, [`super::density`], already
//! sizes them by their neighbours).

use super::footprint::Footprint;
use super::footprint_map::THICKNESS;
use super::lbvh::LinearBvh;
use super::{differential, PathKind, PhotonSet};
use glam::Vec3;
use rayon::prelude::*;

/// Diffuse photon footprints containing a shading point, on average, at smoothing s = 1,
/// where the camera's surfaces read the map.
pub const PHOTONS_PER_ESTIMATE: f32 = 240.0;
/// The same where a final gather reads the map one bounce further
/// ([`super::final_gather`]): each camera sample reads it at another point, so the
/// estimates' noise averages out with the samples and smaller footprints (less blur, a
/// cheaper gather) serve. `cornell` at 128², 64 spp, 200k photons: relMSE (3×3 box) and
/// the low-frequency error (8×8 blocks) the same at 30 and 60 photons, at 0.6 times the
/// time (docs/bench/gather-smoothing.md).
pub const PHOTONS_PER_ESTIMATE_FINAL_GATHER: f32 = 30.0;

/// The photons per estimate `gather` sizes its diffuse footprints for: s² times
/// [`PHOTONS_PER_ESTIMATE`], or [`PHOTONS_PER_ESTIMATE_FINAL_GATHER`] with a final gather.
pub fn photons_per_estimate(final_gather: bool, smoothing: f32) -> f32 {
    let base = match final_gather {
        true => PHOTONS_PER_ESTIMATE_FINAL_GATHER,
        false => PHOTONS_PER_ESTIMATE,
    };
    base * smoothing * smoothing
}
/// Stored photons at whose positions the overlap is counted.
const SAMPLES: usize = 1024;
/// Footprints per leaf of the counting hierarchy.
const LEAF: usize = 8;
/// Most the footprints are scaled by, either way.
const MAX_FACTOR: f32 = 4.0;
/// Least cosine between two photons' normals for one's footprint to count at the other
/// (as in the gather, [`super::footprint_map`]).
const NORMAL_AGREEMENT: f32 = 0.5;

/// Mean number of diffuse photons' footprints that contain the position of a diffuse photon
/// (up to `SAMPLES` of them, evenly spread through the set), counting its own. `None`
/// without diffuse photons.
pub fn mean_overlap(set: &PhotonSet) -> Option<f64> {
    let diffuse: Vec<(Vec3, Vec3, Footprint)> = set
        .photons
        .iter()
        .zip(&set.footprints)
        .filter(|(_, f)| f.kind == PathKind::Diffuse)
        .filter_map(|(p, f)| {
            let thickness = THICKNESS * f.axes[0].length().min(f.axes[1].length());
            let fp = Footprint::new(p.position(), f.axes, p.normal(), thickness)?;
            Some((p.position(), p.normal(), fp))
        })
        .collect();
    if diffuse.is_empty() {
        return None;
    }
    let bounds: Vec<_> = diffuse.iter().map(|(_, _, f)| f.bounds).collect();
    let bvh = LinearBvh::build(&bounds, LEAF);
    let step = diffuse.len().div_ceil(SAMPLES);
    let counts: Vec<usize> = (0..diffuse.len())
        .step_by(step)
        .collect::<Vec<_>>()
        .par_iter()
        .map(|&i| {
            let (p, n, _) = diffuse[i];
            let mut count = 0;
            bvh.for_each_candidate(p, |j| {
                let (_, nj, f) = &diffuse[j as usize];
                if nj.dot(n) > NORMAL_AGREEMENT && f.weight(p, super::Kernel::Box).is_some() {
                    count += 1;
                }
            });
            count
        })
        .collect();
    Some(counts.iter().sum::<usize>() as f64 / counts.len() as f64)
}

/// Scales the footprints of the diffusely reflected photons of `set` uniformly so that their
/// mean overlap ([`mean_overlap`]) becomes about `target` (by at most `MAX_FACTOR` either
/// way), each semi-axis kept within `r_max`; returns the factor (1 when there is nothing to
/// scale).
pub fn scale_to_overlap(set: &mut PhotonSet, target: f32, r_max: f32) -> f32 {
    let Some(overlap) = mean_overlap(set) else {
        return 1.0;
    };
    // The overlap grows with the footprints' area, the square of the factor.
    let factor =
        ((target as f64 / overlap.max(1.0)).sqrt() as f32).clamp(1.0 / MAX_FACTOR, MAX_FACTOR);
    for (p, f) in set.photons.iter_mut().zip(&mut set.footprints) {
        if f.kind == PathKind::Diffuse {
            f.axes = f.axes.map(|a| differential::clamp_axis(a * factor, r_max));
            p.footprint_radius = f.radius();
        }
    }
    factor
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon::{FootprintAxes, Photon};

    /// Photons on a regular grid of a plane with round footprints of radius r: the overlap
    /// at a photon is the number of grid points within r (π r² / spacing², less at the
    /// edges), and scaling to a target reaches it.
    #[test]
    fn overlap_of_a_grid_and_its_scaling() {
        let mut set = PhotonSet::default();
        let (side, spacing, r) = (120, 0.01f32, 0.05f32);
        for i in 0..side {
            for j in 0..side {
                set.photons.push(Photon {
                    position: [i as f32 * spacing, 0.0, j as f32 * spacing],
                    normal: [0.0, 1.0, 0.0],
                    bounce: 1,
                    ..Default::default()
                });
                set.footprints.push(FootprintAxes {
                    axes: [Vec3::X * r, Vec3::Z * r],
                    kind: PathKind::Diffuse,
                });
            }
        }
        let inner = std::f64::consts::PI * (r / spacing) as f64 * (r / spacing) as f64;
        let o = mean_overlap(&set).unwrap();
        // Edge photons see fewer: within [0.8, 1.05] of the interior count (≈ 81).
        assert!(o > 0.8 * inner && o < 1.05 * inner, "{o} vs {inner}");
        let factor = scale_to_overlap(&mut set, 4.0 * o as f32, 1.0);
        assert!((factor - 2.0).abs() < 1e-3, "{factor}");
        let o2 = mean_overlap(&set).unwrap();
        assert!((o2 / o / 4.0 - 1.0).abs() < 0.12, "{o2} vs 4 × {o}");
        assert!((set.photons[0].footprint_radius - 2.0 * r).abs() < 1e-5);
        // The largest semi-axis holds.
        scale_to_overlap(&mut set, 1e6, 0.12);
        assert!(set
            .footprints
            .iter()
            .all(|f| f.axes[0].length() <= 0.12 + 1e-6));
    }
}
