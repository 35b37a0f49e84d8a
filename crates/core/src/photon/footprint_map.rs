//! The footprint photon map (Fabianowski & Dingliana 2009): every stored photon carries the
//! footprint ellipsoid of its differentials, a linear BVH indexes the footprints, and the
//! radiance at a point gathers every photon whose footprint contains it — no k-nearest
//! search, so each photon's contribution is independent of the others.

use super::footprint::{t_auto, Footprint};
use super::lbvh::{Aabb, LinearBvh};
use super::{Kernel, Photon, PhotonSet};
use crate::cancel;
use crate::cancel::Progress;
use crate::error::Result;
use crate::memory;
use crate::trace::Interaction;
use glam::Vec3;

/// Minimum cosine between a photon's surface normal and the shading normal for the photon
/// to count, which keeps light from leaking through thin walls.
const NORMAL_AGREEMENT: f32 = 0.5;
/// Footprint half-thickness along the normal, as a fraction of its smaller semi-axis.
pub(crate) const THICKNESS: f32 = 0.3;

/// How many footprints a BVH leaf holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LeafSize {
    /// The paper's T_auto: proportional to Σ footprint areas / scene area.
    Auto,
    Fixed(usize),
}

/// Photons with footprints and their linear BVH.
pub struct FootprintMap {
    photons: Vec<Photon>,
    footprints: Vec<Footprint>,
    bvh: LinearBvh,
    pub kernel: Kernel,
}

impl FootprintMap {
    /// Builds the map over the photons of `set` (traced with differentials) whose bounce is
    /// at least `min_bounce`. `scene_area` is the total surface area, for T_auto.
    pub fn build(
        set: &PhotonSet,
        min_bounce: u32,
        scene_area: f64,
        leaf: LeafSize,
        kernel: Kernel,
    ) -> Self {
        let mut photons = Vec::new();
        let mut footprints = Vec::new();
        for (p, f) in set.photons.iter().zip(&set.footprints) {
            if p.bounce < min_bounce {
                continue;
            }
            let thickness = THICKNESS * f.axes[0].length().min(f.axes[1].length());
            if let Some(fp) = Footprint::new(p.position(), f.axes, p.normal(), thickness) {
                photons.push(*p);
                footprints.push(fp);
            }
        }
        let leaf_size = match leaf {
            LeafSize::Fixed(n) => n.max(1),
            LeafSize::Auto => {
                let sum: f64 = footprints.iter().map(|f| f.area as f64).sum();
                t_auto(sum, scene_area, T_AUTO_SCALE)
            }
        };
        let bounds: Vec<Aabb> = footprints.iter().map(|f| f.bounds).collect();
        let bvh = LinearBvh::build(&bounds, leaf_size);
        FootprintMap {
            photons,
            footprints,
            bvh,
            kernel,
        }
    }

    /// [`FootprintMap::build`] after checking that it fits in memory, and `Cancelled`
    /// when `progress` asks (before and after the build).
    pub fn try_build(
        set: &PhotonSet,
        min_bounce: u32,
        scene_area: f64,
        leaf: LeafSize,
        kernel: Kernel,
        progress: &dyn Progress,
    ) -> Result<Self> {
        let n = set.photons.len() as u64;
        // A photon and footprint copy, bounds, centres, Morton keys and orders, nodes.
        let per_photon = (std::mem::size_of::<Photon>()
            + std::mem::size_of::<Footprint>()
            + std::mem::size_of::<Aabb>()
            + 12
            + 8
            + 8
            + std::mem::size_of::<Aabb>()) as u64;
        memory::check(
            || format!("the footprint photon map over {n} photons"),
            n * per_photon,
        )?;
        let stage = cancel::StageProgress::new(progress, "photon map build", 1);
        stage.finish()?;
        let map = Self::build(set, min_bounce, scene_area, leaf, kernel);
        stage.advance(1);
        stage.finish()?;
        Ok(map)
    }

    pub fn len(&self) -> usize {
        self.photons.len()
    }

    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    pub fn leaf_size(&self) -> usize {
        self.bvh.leaf_size
    }

    /// The footprints, in the order of the photons they belong to (for benchmarks against
    /// other hierarchies over the same boxes).
    pub fn footprints(&self) -> &[Footprint] {
        &self.footprints
    }

    /// Radiance (W·sr⁻¹·m⁻²) leaving `it` towards `wo` by its non-delta lobes, from every
    /// photon whose footprint contains the shading point.
    pub fn radiance(&self, it: &Interaction, wo: Vec3) -> Vec3 {
        let n = it.frame.n * it.ng.dot(wo).signum();
        let wo_l = it.frame.to_local(wo);
        let mut sum = Vec3::ZERO;
        self.bvh.for_each_candidate(it.position, |i| {
            let (p, f) = (&self.photons[i as usize], &self.footprints[i as usize]);
            if p.normal().dot(n) <= NORMAL_AGREEMENT {
                return;
            }
            if let Some(w) = f.weight(it.position, self.kernel) {
                sum += it.material.eval(wo_l, it.frame.to_local(p.incident())) * p.power() * w;
            }
        });
        sum
    }
}

/// Proportionality constant of T_auto, from the leaf-size sweep in docs/bench/photon-map.md:
/// at a mean footprint overlap (Σ area / scene area) of ≈ 105 for `cornell`, 400k photons,
/// s = 1, the best leaf size was T = 8 in two of three runs and T = 4 in the third (on a
/// loaded machine), so 0.08. It was 2.5 while the literal ‖∂p‖^(−3/4) compression left ~5
/// footprints per point; the paper's own T_auto / k_PD (Tables 1–2) is 0.03–0.12.
pub const T_AUTO_SCALE: f64 = 0.08;

/// Footprint radii per path kind (the paper's Table 3): for each kind present, the photon
/// count and the radii (m) at the percentiles `qs` (0–100).
pub fn radius_percentiles(set: &PhotonSet, qs: &[f64]) -> Vec<(super::PathKind, usize, Vec<f32>)> {
    use super::PathKind;
    [PathKind::Direct, PathKind::Caustic, PathKind::Diffuse]
        .into_iter()
        .filter_map(|kind| {
            let mut r: Vec<f32> = set
                .footprints
                .iter()
                .filter(|f| f.kind == kind)
                .map(|f| f.radius())
                .collect();
            if r.is_empty() {
                return None;
            }
            r.sort_by(f32::total_cmp);
            let at = |q: f64| r[((q / 100.0 * r.len() as f64) as usize).min(r.len() - 1)];
            Some((kind, r.len(), qs.iter().map(|&q| at(q)).collect()))
        })
        .collect()
}
