//! Method `photon`: classic (Jensen) photon mapping, the baseline for ISPM.
//!
//! 1. Emit `photons` photons and trace them, storing photons of every bounce, direct light
//!    included.
//! 2. Build the kd-tree over the stored photons.
//! 3. For each pixel sample, follow the camera ray through delta lobes (mirror, glass) to
//!    non-delta surfaces and estimate their radiance from the k nearest photons. Direct
//!    light comes from the photons too, so the image converges to the full solution as the
//!    photon count grows and the gather radius shrinks; except the sky's: its photons are
//!    stored from their second hit on, and its direct light is estimated at the camera's
//!    surface by a sky direction and a BSDF ray (`trace::direct_mis`). Photons sample the
//!    sky's directions by power, blind to the surface's lobes: a glossy (GGX) lobe of
//!    α = 0.04 covers about 10⁻³ of them, so the density estimate of its sky light is
//!    heavy-tailed and reads dark (−43% on DamagedHelmet's pixels at 50k photons, −7% on a
//!    glossy sphere at 200k); a point light's or sun's photons all come from its one
//!    direction, which the lobe evaluates exactly.

use super::options::derived::{camera_samples, knn_gather};
use super::options::PhotonOptions;
use super::{FrameParams, RenderOutput, RenderStats};
use crate::cancel::Progress;
use crate::error::Result;
use crate::image::Image;
use crate::photon::camera_pass::render_image;
use crate::photon::focus::Focus;
use crate::photon::knn::PhotonMap;
use crate::photon::trace::Checked;
use crate::photon::trace::{emit_and_trace_sources, TraceControl};
use crate::photon::{Neighbour, PhotonSet, PhotonTraceSettings};
use crate::scene::sources::{Source, Sources as PhotonSources};
use crate::scene::Scene;
use crate::trace::direct::DirectLight;
use crate::trace::direct_mis::{mis_direct, Sources};
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
    let set = trace_photons(scene, bvh, options.photons, &pts, frame.seed, &control)?;
    stage("photon trace", t);

    let t = Instant::now();
    let map = PhotonMap::try_build(set.photons, progress)?;
    stage("kd-tree build", t);

    let t = Instant::now();
    let gather = knn_gather(scene, options.k, &options.kernel, frame);
    let samples = camera_samples(options.spp, options.max_depth, frame);
    let lights = DirectLight::of(scene);
    let (radiance, first) = render_image(
        scene,
        bvh,
        &samples,
        progress,
        |it, wo, rng, scratch: &mut Vec<Neighbour>| {
            let sky = mis_direct(scene, bvh, &lights, (it, wo), rng, Sources::Environment);
            sky + map.radiance(it, wo, &gather, scratch)
        },
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

/// `n` photons from the scene's sources, each source's share by power: those of the lights
/// and emitters stored from their first hit (`pts`), the sky's from their second (the
/// camera pass estimates its direct light).
fn trace_photons(
    scene: &Scene,
    bvh: &SceneBvh,
    n: u64,
    pts: &PhotonTraceSettings,
    seed: u64,
    control: &dyn TraceControl,
) -> Result<PhotonSet> {
    let all = PhotonSources::of(scene);
    let n_sky = (n as f64 * all.prob(Source::Environment) as f64).round() as u64;
    let focus = Focus::default();
    let local = PhotonSources::filtered(scene, |s| s != Source::Environment);
    let mut set =
        emit_and_trace_sources(scene, bvh, &local, n - n_sky, pts, seed, control, &focus)?;
    if n_sky > 0 {
        let sky = PhotonSources::filtered(scene, |s| s == Source::Environment);
        let indirect = PhotonTraceSettings {
            store_direct: false,
            ..*pts
        };
        // Another seed: the two sets' paths must not share random numbers.
        let seed = seed ^ 0x5b1e_5a5c_0fe1_7e11;
        set.append(emit_and_trace_sources(
            scene, bvh, &sky, n_sky, &indirect, seed, control, &focus,
        )?);
    }
    Ok(set)
}
