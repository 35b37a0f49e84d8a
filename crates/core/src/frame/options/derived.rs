//! Settings derived from a method's options for one frame (`FrameParams`:
//! its seed and kernel scale): the photon trace of `gather` (also `ispm`'s footprint
//! volumes), the camera samples and the k-nearest-neighbour gather (`photon`, and the
//! specular paths of `ispm` and `bidir`). Here, not in one method's module, because several
//! methods derive them alike.

use super::super::FrameParams;
use super::{KernelOptions, Method, MethodOptions, RenderOptions};
use crate::photon::camera_pass::CameraSamples;
use crate::photon::differential::global_spacing;
use crate::photon::knn::Gather;
use crate::photon::trace::DifferentialSettings;
use crate::photon::PhotonTraceSettings;
use crate::scene::Scene;

/// Default largest footprint semi-axis, as a fraction of the scene's diagonal.
const DEFAULT_R_MAX_FRACTION: f32 = 0.1;

/// Photon-trace settings of the gather method for `photons` photons traced to `max_depth`
/// with differentials smoothed by `smoothing` and footprints capped at the kernel's
/// `max_radius`, both shrunk by `radius_scale` (shared with the statistics of
/// `footprint_statistics` and ISPM's footprint volumes).
pub fn trace_settings(
    scene: &Scene,
    photons: u64,
    max_depth: u32,
    smoothing: f32,
    kernel: &KernelOptions,
    radius_scale: f32,
) -> PhotonTraceSettings {
    PhotonTraceSettings {
        max_bounces: max_depth.saturating_sub(1).max(1),
        store_direct: false,
        differentials: Some(DifferentialSettings {
            spacing: global_spacing(4.0 * std::f32::consts::PI, photons),
            smoothing: smoothing * radius_scale,
            r_max: radius_scale
                * kernel
                    .max_radius
                    .unwrap_or_else(|| DEFAULT_R_MAX_FRACTION * scene.diagonal()),
        }),
    }
}

/// [`trace_settings`] of method `gather` with the photon options of `options` (those of
/// `gather` or `ispm`; another method's: `gather`'s defaults), at the first pass's kernel
/// scale.
pub fn gather_trace_settings(scene: &Scene, options: &RenderOptions) -> PhotonTraceSettings {
    let o = options.with_method(Method::Gather);
    let MethodOptions::Gather(g) = &o.method else {
        unreachable!("with_method(Gather) gives gather options")
    };
    trace_settings(
        scene,
        g.photons,
        g.max_depth,
        g.refine.smoothing,
        &g.kernel,
        1.0,
    )
}

/// The k-nearest-neighbour gather of `k` photons with `kernel`, shrunk for the frame: the
/// radiance estimate of method `photon`, and the gather of ISPM's specular paths.
pub(crate) fn knn_gather(
    scene: &Scene,
    k: u32,
    kernel: &KernelOptions,
    frame: &FrameParams,
) -> Gather {
    Gather::new(
        scene,
        k,
        kernel.max_radius,
        kernel.kernel,
        frame.radius_scale,
    )
}

/// The frame's camera samples: `spp` per pixel through delta lobes up to `max_depth`.
pub(crate) fn camera_samples(spp: u32, max_depth: u32, frame: &FrameParams) -> CameraSamples {
    CameraSamples {
        spp,
        seed: frame.seed,
        max_depth,
        first_hit_aovs: frame.first_hit_aovs,
    }
}
