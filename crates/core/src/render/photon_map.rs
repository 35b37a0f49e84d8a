//! Method `photon`: classic (Jensen) photon mapping, the baseline for ISPM.
//!
//! 1. Emit `photons` photons and trace them, storing photons of every bounce, direct light
//!    included.
//! 2. Build the kd-tree over the stored photons.
//! 3. For each pixel sample, follow the camera ray through delta lobes (mirror, glass) to
//!    non-delta surfaces and estimate their radiance from the k nearest photons. Nothing
//!    else: direct light comes from the photons too, so the image converges to the full
//!    solution as the photon count grows and the gather radius shrinks.

use super::camera_pass::{render_image, scene_diagonal, start_frame};
use super::{Progress, RenderOutput, Settings};
use crate::error::Result;
use crate::photon::estimate::{Gather, PhotonMap};
use crate::photon::trace::Checked;
use crate::photon::{emit_and_trace_checked, Neighbour, PhotonTraceSettings};
use crate::scene::Scene;
use crate::trace::SceneBvh;
use std::time::Instant;

/// Default maximum gather radius, as a fraction of the scene's bounding-box diagonal.
const DEFAULT_RADIUS_FRACTION: f32 = 0.05;

/// The kNN estimate of `settings` (`k`, `max_radius` or its default, `kernel`); also the
/// gather of ISPM's specular paths.
pub fn gather_settings(scene: &Scene, settings: &Settings) -> Gather {
    // Progressive passes shrink the k-NN radius by `radius_scale` through k ∝ r².
    let s2 = settings.radius_scale * settings.radius_scale;
    Gather {
        k: ((settings.k as f32 * s2).round() as usize).max(1),
        max_radius: settings.radius_scale
            * settings
                .max_radius
                .unwrap_or_else(|| DEFAULT_RADIUS_FRACTION * scene_diagonal(scene)),
        kernel: settings.kernel,
    }
}

pub fn render(
    scene: &Scene,
    bvh: &SceneBvh,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<RenderOutput> {
    let t0 = Instant::now();
    let mut stats = start_frame(scene);
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
    let mut out = render_image(
        scene,
        bvh,
        settings,
        progress,
        stats,
        |it, wo, scratch: &mut Vec<Neighbour>| map.radiance(it, wo, &gather, scratch),
    )?;
    out.stats
        .stages
        .push(("radiance estimate".into(), t.elapsed().as_secs_f64()));
    out.stats.light_paths = set.emitted;
    out.stats.total_seconds = t0.elapsed().as_secs_f64();
    Ok(out)
}
