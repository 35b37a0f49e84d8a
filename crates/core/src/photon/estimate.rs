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
use crate::cancel;
use crate::error::{Error, Result};
use crate::memory;
use crate::render::Progress;
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
        Kernel::ALL
            .iter()
            .copied()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Kernel::ALL.iter().map(|k| k.name()).collect();
                Error::setting(
                    "kernel",
                    format!("unknown kernel `{s}` (available: {})", names.join(", ")),
                )
            })
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
        let max_r2 = g.max_radius * g.max_radius;
        let accept = |i: u32| self.photons[i as usize].normal().dot(n) > NORMAL_AGREEMENT;
        self.tree.nearest(it.position, g.k, max_r2, accept, scratch);
        let r2 = if scratch.len() == g.k {
            scratch.last().map_or(max_r2, |nb| nb.dist2)
        } else {
            max_r2
        };
        if scratch.is_empty() || r2 <= 0.0 {
            return Vec3::ZERO;
        }
        let wo_l = it.frame.to_local(wo);
        scratch
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
