//! Method `gather`: photons traced with photon differentials, a linear-BVH footprint photon
//! map, and a CPU gather estimate (Fabianowski & Dingliana 2009). Direct light comes from
//! next-event estimation at each shading point; the photons carry indirect light and
//! caustics. Camera rays follow mirrors and glass (`camera_pass`), so reflections and
//! refractions show indirect light too.

use super::photon::camera_samples;
use super::{RenderOutput, RenderStats, Settings};
use crate::cancel::Progress;
use crate::error::Result;
use crate::image::Image;
use crate::photon::camera_pass::render_image;
use crate::photon::differential::global_spacing;
use crate::photon::gather::{scene_area, FootprintMap, LeafSize};
use crate::photon::trace::emit_and_trace_focused;
use crate::photon::trace::Checked;
use crate::photon::trace::DifferentialSettings;
use crate::photon::PhotonTraceSettings;
use crate::scene::Scene;
use crate::trace::path::direct_light;
use crate::trace::SceneBvh;
use std::time::Instant;

/// Default largest footprint semi-axis, as a fraction of the scene's diagonal.
const DEFAULT_R_MAX_FRACTION: f32 = 0.1;

/// Photon-trace settings of the gather method for `n` photons (shared with the statistics
/// of `footprint_statistics`).
pub fn trace_settings(scene: &Scene, settings: &Settings) -> PhotonTraceSettings {
    PhotonTraceSettings {
        max_bounces: settings.max_depth.saturating_sub(1).max(1),
        store_direct: false,
        differentials: Some(DifferentialSettings {
            spacing: global_spacing(4.0 * std::f32::consts::PI, settings.photons),
            smoothing: settings.smoothing * settings.radius_scale,
            r_max: settings.radius_scale
                * settings
                    .max_radius
                    .unwrap_or_else(|| DEFAULT_R_MAX_FRACTION * scene.diagonal()),
        }),
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

    let t = Instant::now();
    let pts = trace_settings(scene, settings);
    let focus = crate::photon::focus::Focus::of_scene(scene, settings.photon_focus);
    let mut set = emit_and_trace_focused(
        scene,
        bvh,
        settings.photons,
        &pts,
        settings.seed,
        &Checked::new(progress, "photon trace"),
        &focus,
    )?;
    if let (true, Some(ds)) = (settings.caustic_density_bound, &pts.differentials) {
        crate::photon::density::bound_footprints(&mut set, settings.radius_scale, ds.r_max);
    }
    stage("photon trace", t);
    if settings.boundary_compensation {
        // Footprints cut by an edge lose the energy off the surface: a darkening along
        // edges and corners that shrinks only as fast as the radius (in progressive mode
        // the slowest term of the error), so each photon's power is divided by the
        // share of its footprint on surfaces.
        let t = Instant::now();
        crate::photon::boundary::compensate_footprints(
            scene,
            bvh,
            &mut set,
            crate::photon::gather::THICKNESS,
            settings.kernel,
            settings.seed,
        );
        stage("boundary compensation", t);
    }

    let t = Instant::now();
    let leaf = settings
        .leaf_size
        .map_or(LeafSize::Auto, |n| LeafSize::Fixed(n as usize));
    let map = FootprintMap::try_build(&set, 1, scene_area(scene), leaf, settings.kernel, progress)?;
    stage("photon map build", t);

    let t = Instant::now();
    let samples = camera_samples(settings);
    let (radiance, first) = render_image(scene, bvh, &samples, progress, |it, wo, _: &mut ()| {
        direct_light(scene, bvh, it, wo) + map.radiance(it, wo)
    })?;
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
