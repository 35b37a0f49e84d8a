//! Method `gather`: photons traced with photon differentials, a linear-BVH footprint photon
//! map, and a CPU gather estimate (Fabianowski & Dingliana 2009). Direct light comes from
//! next-event estimation and one BSDF ray at each shading point (`trace::direct_mis`); the
//! photons carry indirect light and caustics. By default the indirect light is read one
//! bounce further, by a final gather (`photon::final_gather`): the caustic photons at the
//! shading point, every other photon where its one BSDF ray lands; with `final_gather` off,
//! every photon at the shading point (blotchier: every sample of a pixel reads the same
//! footprints). Camera rays follow mirrors and glass (`camera_pass`), so reflections and
//! refractions show indirect light too.

use super::options::derived::camera_samples;
pub use super::options::derived::{gather_trace_settings, trace_settings};
use super::options::GatherOptions;
use super::{FrameParams, RenderOutput, RenderStats};
use crate::cancel::Progress;
use crate::error::Result;
use crate::image::Image;
use crate::photon::camera_pass::render_image;
use crate::photon::final_gather::FinalGather;
use crate::photon::footprint_map::{FootprintMap, LeafSize};
use crate::photon::footprint_scale::{photons_per_estimate, scale_to_overlap};
use crate::photon::trace::emit_and_trace_focused;
use crate::photon::trace::Checked;
use crate::photon::{PathKind, PhotonSet};
use crate::scene::Scene;
use crate::trace::direct::DirectLight;
use crate::trace::direct_mis::{mis_direct, Sources};
use crate::trace::SceneBvh;
use glam::Vec3;
use std::time::Instant;

pub(super) fn render(
    scene: &Scene,
    bvh: &SceneBvh,
    options: &GatherOptions,
    frame: &FrameParams,
    progress: &dyn Progress,
) -> Result<RenderOutput> {
    let t0 = Instant::now();
    let mut stats = RenderStats::of(scene);
    let mut stage =
        |name: &str, t: Instant| stats.stages.push((name.into(), t.elapsed().as_secs_f64()));

    let t = Instant::now();
    let refine = &options.refine;
    let pts = trace_settings(
        scene,
        options.photons,
        options.max_depth,
        refine.smoothing,
        &options.kernel,
        frame.radius_scale,
    );
    let focus = crate::photon::focus::Focus::of_scene(scene, refine.photon_focus);
    let mut set = emit_and_trace_focused(
        scene,
        bvh,
        options.photons,
        &pts,
        frame.seed,
        &Checked::new(progress, "photon trace"),
        &focus,
    )?;
    if let (true, Some(ds)) = (refine.caustic_density_bound, &pts.differentials) {
        crate::photon::density::bound_footprints(&mut set, frame.radius_scale, ds.r_max);
    }
    if let Some(ds) = &pts.differentials {
        // The diffuse footprints sized to hold s² × 240 photons each (30 with the final
        // gather; shrunk with the progressive pass's kernels), whatever the scene and photon
        // count.
        let smoothing = refine.smoothing * frame.radius_scale;
        let target = photons_per_estimate(options.final_gather, smoothing);
        scale_to_overlap(&mut set, target, ds.r_max);
    }
    stage("photon trace", t);
    if refine.boundary_compensation {
        // Footprints cut by an edge lose the energy off the surface: a darkening along
        // edges and corners that shrinks only as fast as the radius (in progressive mode
        // the slowest term of the error), so each photon's power is divided by the
        // share of its footprint on surfaces.
        let t = Instant::now();
        crate::photon::boundary::compensate_footprints(
            scene,
            bvh,
            &mut set,
            crate::photon::footprint_map::THICKNESS,
            options.kernel.kernel,
            frame.seed,
        );
        stage("boundary compensation", t);
    }

    let t = Instant::now();
    let leaf = options
        .leaf_size
        .map_or(LeafSize::Auto, |n| LeafSize::Fixed(n as usize));
    let build = |set: &PhotonSet| {
        let area = scene.surface_area();
        FootprintMap::try_build(set, 1, area, leaf, options.kernel.kernel, progress)
    };
    let map = build(&set)?;
    // With a final gather, the surface the camera sees reads only the caustic photons.
    let caustics = set.of_kind(PathKind::Caustic);
    let caustic_map = match options.final_gather && !caustics.photons.is_empty() {
        true => Some(build(&caustics)?),
        false => None,
    };
    stage("photon map build", t);

    let t = Instant::now();
    let samples = camera_samples(options.spp, options.max_depth, frame);
    // Direct light by next-event estimation and one BSDF ray, weighted by multiple
    // importance sampling: the glossy lobes' light from the sky and emitters too.
    let lights = DirectLight::of(scene);
    let fg = FinalGather {
        scene,
        bvh,
        lights: &lights,
        map: &map,
        max_depth: options.max_depth,
    };
    let (radiance, first) =
        render_image(scene, bvh, &samples, progress, |it, wo, rng, _: &mut ()| {
            let direct = mis_direct(scene, bvh, &lights, (it, wo), rng, Sources::All);
            let indirect = if options.final_gather {
                let caustic = caustic_map
                    .as_ref()
                    .map_or(Vec3::ZERO, |c| c.radiance(it, wo));
                caustic + fg.indirect(it, wo, rng)
            } else {
                map.radiance(it, wo)
            };
            direct + indirect
        })?;
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
