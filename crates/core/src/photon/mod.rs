//! Photons: the records that photon tracing stores at surface hits, the rays that carry
//! them between hits, and the CPU photon tracer and kd-tree that photon mapping builds on.
//!
//! Directions follow the BSDF convention: a photon's `incident` direction points *towards*
//! where it came from (away from the surface). Power is in watts per RGB channel; the
//! powers of all photons stored for one bounce index add up to the power that reaches that
//! bounce (in expectation).

pub mod bounce;
pub mod boundary;
pub mod camera_pass;
pub mod delta_light;
pub mod delta_paths;
pub mod density;
pub mod differential;
pub mod final_gather;
pub mod focus;
pub mod footprint;
pub mod footprint_map;
pub mod footprint_scale;
pub mod irradiance;
pub mod kdtree;
pub mod knn;
pub mod lbvh;
pub mod radius;
pub mod ring;
pub mod sky_guide;
pub mod sky_pilot;
pub mod specular;
pub mod trace;

use crate::bsdf::{Lobe, Material};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

pub use kdtree::{KdTree, Neighbour};
pub use knn::Kernel;
pub use trace::{
    continue_paths, continue_paths_checked, emit_and_trace, emit_and_trace_checked,
    PhotonTraceSettings,
};

/// A stored photon, laid out for GPU upload (64 bytes; each `vec3` starts a 16-byte row).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Photon {
    /// World-space hit position (m).
    pub position: [f32; 3],
    /// Number of scatterings before this hit (0 = direct light).
    pub bounce: u32,
    /// Unit direction towards where the photon came from.
    pub incident: [f32; 3],
    /// ISPM path density ρp: product over scatterings of ρL/1000 (Lambertian), ρS/10
    /// (glossy), ρS (mirror) or T (glass); 1 for direct light. Dimensionless.
    pub path_density: f32,
    /// Power (W per channel).
    pub power: [f32; 3],
    pub _pad0: u32,
    /// Unit (shading) normal of the surface hit, on the side the photon arrived from.
    pub normal: [f32; 3],
    /// Footprint radius (m) from photon differentials, √|a₁ × a₂|; 0 when traced without.
    /// Method `ispm` sets it to the photon-volume radius before the splat.
    pub footprint_radius: f32,
}

impl Photon {
    pub fn position(&self) -> Vec3 {
        Vec3::from(self.position)
    }
    pub fn incident(&self) -> Vec3 {
        Vec3::from(self.incident)
    }
    pub fn power(&self) -> Vec3 {
        Vec3::from(self.power)
    }
    pub fn normal(&self) -> Vec3 {
        Vec3::from(self.normal)
    }
}

/// A photon in flight, e.g. one that took its first bounce in the ISPM GPU bounce map
/// (48 bytes, GPU layout).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PhotonRay {
    /// Ray origin (m), already offset off the surface it leaves.
    pub origin: [f32; 3],
    /// Scatterings so far: the bounce index the next hit is stored with.
    pub bounce: u32,
    /// Unit propagation direction.
    pub direction: [f32; 3],
    /// Path density ρp so far (1 for a photon fresh from a light).
    pub path_density: f32,
    /// Power (W per channel).
    pub power: [f32; 3],
    pub _pad: u32,
}

impl PhotonRay {
    pub fn new(origin: Vec3, direction: Vec3, power: Vec3, path_density: f32, bounce: u32) -> Self {
        PhotonRay {
            origin: origin.into(),
            bounce,
            direction: direction.into(),
            path_density,
            power: power.into(),
            _pad: 0,
        }
    }
}

/// The photons of one trace and what happened to the paths.
#[derive(Clone, Debug, Default)]
pub struct PhotonSet {
    pub photons: Vec<Photon>,
    /// Photon paths started (emitted from lights, or continued from given rays).
    pub emitted: u64,
    /// Stored photons per bounce index.
    pub stored_per_bounce: Vec<u64>,
    /// Paths ended by absorption (Russian roulette, a BSDF with no energy, or a sample on
    /// the wrong side of the geometry).
    pub absorbed: u64,
    /// Paths that left the scene.
    pub escaped: u64,
    /// Paths cut at the bounce limit.
    pub truncated: u64,
    /// Footprint semi-axes of each stored photon (same order as `photons`), when traced
    /// with photon differentials; empty otherwise.
    pub footprints: Vec<FootprintAxes>,
}

/// A stored photon's footprint from its differentials: two semi-axes (m) in the surface
/// plane, and how the photon got there.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FootprintAxes {
    pub axes: [Vec3; 2],
    pub kind: PathKind,
}

/// The scattering history of a stored photon, for footprint statistics (the paper's Table 3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum PathKind {
    /// Straight from the light.
    #[default]
    Direct,
    /// Only specular (mirror/glass) bounces since the light: a caustic photon.
    Caustic,
    /// At least one diffuse or glossy bounce.
    Diffuse,
}

impl FootprintAxes {
    /// Radius of the circle of the same area, √|a₁ × a₂| (m).
    pub fn radius(&self) -> f32 {
        self.axes[0].cross(self.axes[1]).length().sqrt()
    }
}

impl PhotonSet {
    /// Total stored power (W per channel) per bounce index, in f64 for sums of millions.
    pub fn power_per_bounce(&self) -> Vec<glam::DVec3> {
        let mut sums = vec![glam::DVec3::ZERO; self.stored_per_bounce.len()];
        for p in &self.photons {
            sums[p.bounce as usize] += p.power().as_dvec3();
        }
        sums
    }

    /// The photons of path kind `kind` with their footprints (the counts left at zero).
    pub fn of_kind(&self, kind: PathKind) -> PhotonSet {
        let (photons, footprints) = self
            .photons
            .iter()
            .zip(&self.footprints)
            .filter(|(_, f)| f.kind == kind)
            .map(|(p, f)| (*p, *f))
            .unzip();
        PhotonSet {
            photons,
            footprints,
            ..PhotonSet::default()
        }
    }

    /// Appends `other`, summing the counts.
    pub fn append(&mut self, mut other: PhotonSet) {
        self.photons.append(&mut other.photons);
        self.footprints.append(&mut other.footprints);
        self.emitted += other.emitted;
        self.absorbed += other.absorbed;
        self.escaped += other.escaped;
        self.truncated += other.truncated;
        if self.stored_per_bounce.len() < other.stored_per_bounce.len() {
            self.stored_per_bounce
                .resize(other.stored_per_bounce.len(), 0);
        }
        for (a, b) in self
            .stored_per_bounce
            .iter_mut()
            .zip(&other.stored_per_bounce)
        {
            *a += b;
        }
    }

    pub(crate) fn store(&mut self, photon: Photon) {
        let b = photon.bounce as usize;
        if self.stored_per_bounce.len() <= b {
            self.stored_per_bounce.resize(b + 1, 0);
        }
        self.stored_per_bounce[b] += 1;
        self.photons.push(photon);
    }
}

fn mean(v: Vec3) -> f32 {
    v.element_sum() / 3.0
}

/// The ISPM path-density factor of one scattering through `lobe` of `m` (section 4.3):
/// ρL/1000 for Lambertian, ρS/10 for glossy, ρS for mirror and T for refraction (means over
/// channels). Glass reflection counts as a mirror of the glass's transmittance.
pub fn path_density_factor(m: &Material, lobe: Lobe) -> f32 {
    match lobe {
        Lobe::Diffuse => mean(m.diffuse) / 1000.0,
        Lobe::Glossy => mean(m.specular) / 10.0,
        Lobe::RoughRefract => mean(m.transmission) / 10.0,
        Lobe::Mirror => mean(m.specular),
        Lobe::GlassReflect | Lobe::GlassRefract => mean(m.transmission),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn of_kind_keeps_the_photons_of_that_kind_with_their_footprints() {
        let mut set = PhotonSet::default();
        for (i, kind) in [PathKind::Diffuse, PathKind::Caustic, PathKind::Diffuse]
            .into_iter()
            .enumerate()
        {
            set.store(Photon {
                bounce: i as u32 + 1,
                ..Photon::default()
            });
            let axes = [Vec3::X * (i + 1) as f32, Vec3::Y];
            set.footprints.push(FootprintAxes { axes, kind });
        }
        let caustic = set.of_kind(PathKind::Caustic);
        assert_eq!(caustic.photons.len(), 1);
        assert_eq!(caustic.photons[0].bounce, 2);
        assert_eq!(caustic.footprints[0].axes[0], Vec3::X * 2.0);
        let diffuse = set.of_kind(PathKind::Diffuse);
        let bounces: Vec<u32> = diffuse.photons.iter().map(|p| p.bounce).collect();
        assert_eq!(bounces, [1, 3]);
        assert_eq!(diffuse.footprints.len(), 2);
        assert!(set.of_kind(PathKind::Direct).photons.is_empty());
    }

    #[test]
    fn gpu_layout() {
        assert_eq!(std::mem::size_of::<Photon>(), 64);
        assert_eq!(std::mem::size_of::<PhotonRay>(), 48);
    }
}
