//! Method `photon`: classic (Jensen) photon mapping, the baseline for ISPM.
//!
//! 1. Emit `photons` photons and trace them. The emitting triangles' photons are stored
//!    from their first hit on; the sky's and the point, spot and directional lights' from
//!    their second (their direct light is estimated at the camera's surface, step 3).
//! 2. Build the kd-tree over the stored photons.
//! 3. For each pixel sample, follow the camera ray through delta lobes (mirror, glass) to
//!    non-delta surfaces and estimate their radiance from the k nearest photons, plus the
//!    direct light of the sky and the lights by next-event estimation and a BSDF ray
//!    (`trace::direct_mis`, [`Sources::Lights`]): a shadow ray per point, spot or parallel
//!    directional light (exact), a direction in a sun's disc and in the sky, weighted
//!    against the BSDF ray. As in Jensen's photon mapping, direct light is ray traced: the
//!    k-NN gather radius blurs a light's direct light over the surface's relief (a sun on
//!    Khronos' NormalTangentMirrorTest, 50k photons: −5.4% against `path` from the photons,
//!    −0.4% by a shadow ray), and photons sample the sky's directions by power, blind to
//!    a glossy (GGX) lobe of α = 0.04 that covers about 10⁻³ of them (−43% on
//!    DamagedHelmet's pixels at 50k photons when the sky's direct light came from photons).
//!    The emitters' direct light still comes from their photons, so the image converges to
//!    the full solution as the photon count grows and the gather radius shrinks.

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

    // Photon tracing: every bounce; direct light stored only for the emitters.
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
            let direct = mis_direct(scene, bvh, &lights, (it, wo), rng, Sources::Lights);
            direct + map.radiance(it, wo, &gather, scratch)
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

/// The sources whose direct light the camera pass estimates ([`Sources::Lights`]): the
/// sky and the point, spot and directional lights. Their photons are stored from their
/// second hit on; the emitting triangles' from their first.
fn by_nee(s: Source) -> bool {
    s != Source::Emitters
}

/// `n` photons from the scene's sources, each source's share by power: the emitters'
/// stored from their first hit (`pts`), the sky's and the lights' from their second (the
/// camera pass estimates their direct light).
fn trace_photons(
    scene: &Scene,
    bvh: &SceneBvh,
    n: u64,
    pts: &PhotonTraceSettings,
    seed: u64,
    control: &dyn TraceControl,
) -> Result<PhotonSet> {
    let all = PhotonSources::of(scene);
    let p_nee: f32 = all
        .list
        .iter()
        .map(|(s, _)| s)
        .filter(|s| by_nee(**s))
        .map(|s| all.prob(*s))
        .sum();
    let n_nee = ((n as f64 * p_nee as f64).round() as u64).min(n);
    let focus = Focus::default();
    let emitters = PhotonSources::filtered(scene, |s| !by_nee(s));
    let mut set =
        emit_and_trace_sources(scene, bvh, &emitters, n - n_nee, pts, seed, control, &focus)?;
    if n_nee > 0 {
        let rest = PhotonSources::filtered(scene, by_nee);
        let indirect = PhotonTraceSettings {
            store_direct: false,
            ..*pts
        };
        // Another seed: the two sets' paths must not share random numbers.
        let seed = seed ^ 0x5b1e_5a5c_0fe1_7e11;
        set.append(emit_and_trace_sources(
            scene, bvh, &rest, n_nee, &indirect, seed, control, &focus,
        )?);
    }
    Ok(set)
}
