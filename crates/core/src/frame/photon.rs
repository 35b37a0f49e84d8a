//! Method `photon`: classic (Jensen) photon mapping, the baseline for ISPM.
//!
//! 1. Emit `photons` photons and trace them, storing photons of every bounce, direct light
//!    included.
//! 2. Build the kd-tree over the stored photons.
//! 3. For each pixel sample, follow the camera ray through delta lobes (mirror, glass) to
//!    non-delta surfaces and estimate their radiance from the k nearest photons. Nothing
//!    else: direct light comes from the photons too, so the image converges to the full
//!    solution as the photon count grows and the gather radius shrinks.

use super::{RenderOutput, RenderStats, Settings};
use crate::cancel::Progress;
use crate::error::Result;
use crate::image::Image;
use crate::photon::camera_pass::{render_image, CameraSamples};
use crate::photon::estimate::{Gather, PhotonMap};
use crate::photon::trace::Checked;
use crate::photon::{emit_and_trace_checked, Neighbour, PhotonTraceSettings};
use crate::scene::Scene;
use crate::trace::SceneBvh;
use std::time::Instant;

/// The kNN estimate of `settings` (`k`, `max_radius` or its default, `kernel`); also the
/// gather of ISPM's specular paths.
pub fn gather_settings(scene: &Scene, settings: &Settings) -> Gather {
    Gather::new(
        scene,
        settings.k,
        settings.max_radius,
        settings.kernel,
        settings.radius_scale,
    )
}

/// The camera samples of `settings`.
pub(super) fn camera_samples(settings: &Settings) -> CameraSamples {
    CameraSamples {
        spp: settings.spp,
        seed: settings.seed,
        max_depth: settings.max_depth,
        first_hit_aovs: settings.first_hit_aovs,
    }
}

pub fn render(
    scene: &Scene,
    bvh: &SceneBvh,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<RenderOutput> {
    let t0 = Instant::now();
    let mut stats = RenderStats::of(scene);
    let mut stage =
        |name: &str, t: Instant| stats.stages.push((name.into(), t.elapsed().as_secs_f64()));

    // Photon tracing: every bounce, direct light included.
    let t = Instant::now();
    let pts = PhotonTraceSettings {
        max_bounces: settings.max_depth - 1,
        store_direct: true,
        differentials: None,
    };
    let control = Checked::new(progress, "photon trace");
    let set = emit_and_trace_checked(scene, bvh, settings.photons, &pts, settings.seed, &control)?;
    stage("photon trace", t);

    let t = Instant::now();
    let map = PhotonMap::try_build(set.photons, progress)?;
    stage("kd-tree build", t);

    let t = Instant::now();
    let gather = gather_settings(scene, settings);
    let samples = camera_samples(settings);
    let (radiance, first) = render_image(
        scene,
        bvh,
        &samples,
        progress,
        |it, wo, scratch: &mut Vec<Neighbour>| map.radiance(it, wo, &gather, scratch),
    )?;
    let caustics = Image::new(radiance.width, radiance.height);
    let mut out = RenderOutput::of_cpu(radiance, first, caustics, stats);
    out.stats.samples_per_pixel = samples.spp;
    out.stats.camera_paths = samples.spp as u64 * scene.camera.width as u64 * scene.camera.height as u64;
    out.stats
        .stages
        .push(("radiance estimate".into(), t.elapsed().as_secs_f64()));
    out.stats.light_paths = set.emitted;
    out.stats.total_seconds = t0.elapsed().as_secs_f64();
    Ok(out)
}
