//! Where a frame's GPU-traced photons go (`photon_trace` = `gpu`): left on the GPU, where
//! the binned estimators copy them into their photon texture (`gpu::photon::resident`: only
//! the record and caustic counts come back), or read back into the CPU ring when a CPU step
//! needs the photons themselves. The stat `photon_records` says which ran and why.

use super::super::context::FrameCtx;
use super::super::options::{Estimator, IspmOptions};
use super::super::Images;
use crate::gpu::photon::resident::{forced, RECORDS_ENV};
use crate::gpu::photon::resident::{ResidentPhotons, Sizing};
use crate::photon::focus::Focus;
use crate::photon::radius::VolumeRadius;
use crate::photon::ring::RingPhotons;
use crate::scene::Scene;

/// What a frame decides the photons need.
pub(super) struct Need<'a> {
    pub fc: &'a FrameCtx<'a>,
    pub options: &'a IspmOptions,
    pub estimator: Estimator,
    pub images: Images,
    /// The ring keeps more than this frame's photons.
    pub ring_frames: usize,
    /// Photons emitted on the CPU (area lights, sun, sky): traced on the GPU with
    /// `photon_trace=gpu` (`gpu::photon::emitted`), but not yet joined into the resident
    /// buffer (their traces come back as records).
    pub cpu_photons: u64,
    /// The photon side of the boundary compensation runs.
    pub compensate: bool,
}

/// Why the GPU-traced photons must be read back, `None` when the estimator can take them
/// on the GPU.
pub(super) fn readback_reason(n: &Need) -> Option<String> {
    let (o, scene) = (n.options, n.fc.scene);
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
        "area, sun and sky photons are not joined on the GPU yet".into()
    } else if n.fc.params.progressive {
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

/// How the photons left on the GPU are sized (`records` is `Some(None)`: they stay there):
/// the frame's volume radii, caustic kernels widened to a pixel of an image `height` high.
pub(super) fn sizing(
    records: &Option<Option<String>>,
    scene: &Scene,
    radius: VolumeRadius,
    height: u32,
) -> Option<Sizing> {
    matches!(records, Some(None)).then(|| Sizing {
        radius,
        eye: scene.camera.position.into(),
        pixel_per_metre: super::indirect::pixel_per_metre(&scene.camera, height),
    })
}

/// The frame's stored photons: those kept on the GPU, else the ring's.
pub(super) fn stored(kept: &Option<ResidentPhotons>, ring: &RingPhotons) -> u64 {
    kept.as_ref()
        .map_or(ring.splat.len() as u64, |r| r.count as u64)
}
