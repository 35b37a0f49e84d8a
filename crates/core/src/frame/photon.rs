//! Method `photon`: classic (Jensen) photon mapping, the baseline for ISPM.
//!
//! 1. Emit `photons` photons and trace them, storing photons of every bounce, direct light
//!    included.
//! 2. Build the kd-tree over the stored photons.
//! 3. For each pixel sample, follow the camera ray through delta lobes (mirror, glass) to
//!    non-delta surfaces and estimate their radiance from the k nearest photons. Nothing
//!    else: direct light comes from the photons too, so the image converges to the full
//!    solution as the photon count grows and the gather radius shrinks.

use super::options::derived::{camera_samples, knn_gather};
use super::options::PhotonOptions;
use super::{FrameParams, RenderOutput, RenderStats};
use crate::cancel::Progress;
use crate::error::Result;
use crate::image::Image;
use crate::photon::camera_pass::render_image;
use crate::photon::knn::PhotonMap;
use crate::photon::trace::Checked;
use crate::photon::{emit_and_trace_checked, Neighbour, PhotonTraceSettings};
use crate::scene::Scene;
use crate::trace::SceneBvh;
use std::time::Instant;

/// One frame of method `photon`: every bounce traced, a k-nearest-neighbour gather of
/// the photon map at the camera paths' diffuse hits.
pub fn render(
    scene: &Scene,
    bvh: &SceneBvh,
    options: &PhotonOptions,
    frame: &FrameParams,
    progress: &dyn Progress,
) -> Result<RenderOutput> {
    let t0 = Instant::now();
    let mut stats = RenderStats::of(scene);
    let mut stage =
        |name: &str, t: Instant| stats.stages.push((name.into(), t.elapsed().as_secs_f64()));

    // Photon tracing: every bounce, direct light included.
    let t = Instant::now();
    let pts = PhotonTraceSettings {
        max_bounces: options.max_depth - 1,
        store_direct: true,
        differentials: None,
    };
    let control = Checked::new(progress, "photon trace");
    let set = emit_and_trace_checked(scene, bvh, options.photons, &pts, frame.seed, &control)?;
    stage("photon trace", t);

    let t = Instant::now();
    let map = PhotonMap::try_build(set.photons, progress)?;
    stage("kd-tree build", t);

    let t = Instant::now();
    let gather = knn_gather(scene, options.k, &options.kernel, frame);
    let samples = camera_samples(options.spp, options.max_depth, frame);
    let (radiance, first) = render_image(
        scene,
        bvh,
        &samples,
        progress,
        |it, wo, _, scratch: &mut Vec<Neighbour>| map.radiance(it, wo, &gather, scratch),
    )?;
    let caustics = Image::new(radiance.width, radiance.height);
    let mut out = RenderOutput::of_cpu(radiance, first, caustics, stats);
    out.stats.samples_per_pixel = samples.spp;
    out.stats.camera_paths =
        samples.spp as u64 * scene.camera.width as u64 * scene.camera.height as u64;
    out.stats
        .stages
        .push(("radiance estimate".into(), t.elapsed().as_secs_f64()));
    out.stats.light_paths = set.emitted;
    out.stats.total_seconds = t0.elapsed().as_secs_f64();
    Ok(out)
}
