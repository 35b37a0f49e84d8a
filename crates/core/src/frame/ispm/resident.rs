//! Where a frame's GPU-traced photons go (`photon_trace` = `gpu`): left on the GPU, where
//! the binned estimators copy them into their photon texture (`gpu::photon::resident`: only
//! the record and caustic counts come back), or read back into the CPU ring when a CPU step
//! needs the photons themselves. The stat `photon_records` says which ran and why.

use super::super::options::{Estimator, IspmOptions};
use super::super::{FrameParams, Images};
use crate::gpu::photon::resident::{forced, RECORDS_ENV};
use crate::photon::focus::Focus;
use crate::scene::Scene;

/// What a frame decides the photons need.
pub(super) struct Need<'a> {
    pub scene: &'a Scene,
    pub options: &'a IspmOptions,
    pub params: &'a FrameParams,
    pub estimator: Estimator,
    pub images: Images,
    /// The ring keeps more than this frame's photons.
    pub ring_frames: usize,
    /// Photons emitted on the CPU (area lights, sun, sky).
    pub cpu_photons: u64,
    /// The photon side of the boundary compensation runs.
    pub compensate: bool,
}

/// Why the GPU-traced photons must be read back, `None` when the estimator can take them
/// on the GPU.
pub(super) fn readback_reason(n: &Need) -> Option<String> {
    let (o, scene) = (n.options, n.scene);
    let why = if forced() {
        format!("{RECORDS_ENV}=readback or force_readback")
    } else if !matches!(
        n.estimator,
        Estimator::Tiled | Estimator::Cluster | Estimator::Directional
    ) {
        format!(
            "the `{}` estimator takes the photons from the CPU",
            n.estimator.name()
        )
    } else if o.subsample > 1 {
        "subsample > 1 splats the caustic photons apart, split on the CPU".into()
    } else if n.compensate {
        "boundary_compensation runs on the CPU".into()
    } else if o.refine.caustic_density_bound {
        "caustic_density_bound runs on the CPU".into()
    } else if n.ring_frames > 1 {
        "temporal_frames > 1 keeps the photons in the CPU ring".into()
    } else if n.cpu_photons > 0 {
        "area lights, sun and sky are traced on the CPU".into()
    } else if n.params.progressive {
        "progressive passes gather on the CPU".into()
    } else if scene.has_specular_traced() {
        "mirrors and glass seen by the camera gather the photons on the CPU".into()
    } else if n.images.extras {
        "the `photons` image places the photons on the CPU".into()
    } else {
        let focus = Focus::of_scene(scene, (o.refine.photon_focus > 0.0) as u32 as f32);
        let aimed = (0..scene.lights.len()).any(|l| focus.covers_all(l));
        if !aimed {
            return None;
        }
        "photon_focus aims caustic photons on the CPU".into()
    };
    Some(why)
}

/// The stat `photon_records` of a GPU-traced frame: `gpu` or `readback: why`.
pub(super) fn stat(reason: &Option<String>) -> String {
    match reason {
        None => "gpu".into(),
        Some(why) => format!("readback: {why}"),
    }
}
