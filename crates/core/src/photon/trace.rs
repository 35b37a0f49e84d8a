//! CPU photon tracing (ISPM Appendix A, with the path density of section 4.3).
//!
//! A photon is stored at every hit on a surface with a non-delta lobe, then scattered by
//! sampling the BSDF and kept alive by Russian roulette with survival probability
//! `q = min(1, max(Φ·w) / max(Φ))` (`w` = the sample's f·cos/pdf), so that a survivor's
//! power `Φ·w/q` keeps its largest channel: stored photons have roughly equal power.
//!
//! Work is split into fixed chunks of paths, each traced with its own per-path generator
//! `Rng::new(seed, stream, path)` into its own [`PhotonSet`]; the chunks are concatenated
//! in order, so the result depends on the seed only, not on the thread schedule.

use super::{path_density_factor, Photon, PhotonRay, PhotonSet};
use crate::bsdf::Lobe;
use crate::sampling::Rng;
use crate::scene::Scene;
use crate::trace::light_tracer::{choose_light, light_weights};
use crate::trace::{Interaction, SceneBvh};
use rayon::prelude::*;

/// Paths per parallel work item.
const CHUNK: u64 = 4096;
/// Random stream of emitted photon paths.
const STREAM_EMIT: u64 = 0x9407_0000;
/// Random stream of continued photon paths.
const STREAM_CONTINUE: u64 = 0x9407_0001;

/// Photon tracer settings.
#[derive(Clone, Copy, Debug)]
pub struct PhotonTraceSettings {
    /// Maximum number of scatterings of a path; stored bounce indices are `0..=max_bounces`.
    pub max_bounces: u32,
    /// Whether hits of bounce 0 (direct light) are stored.
    pub store_direct: bool,
}

impl Default for PhotonTraceSettings {
    fn default() -> Self {
        PhotonTraceSettings {
            max_bounces: 16,
            store_direct: true,
        }
    }
}

/// Emits `n_photons` photons from the scene's lights (each light chosen with probability
/// proportional to its power, so each photon carries about total power / n) and traces them.
pub fn emit_and_trace(
    scene: &Scene,
    bvh: &SceneBvh,
    n_photons: u64,
    s: &PhotonTraceSettings,
    seed: u64,
) -> PhotonSet {
    let weights = light_weights(scene);
    let mut set = trace_chunks(n_photons, |i, out| {
        let mut rng = Rng::new(seed, STREAM_EMIT, i);
        let Some((li, p_light)) = choose_light(&weights, rng.next_f32()) else {
            out.absorbed += 1;
            return;
        };
        let e = scene.lights[li].emit(&mut rng);
        let power = e.power / (p_light * n_photons as f32);
        let ray = PhotonRay::new(e.origin, e.direction, power, 1.0, 0);
        follow(scene, bvh, &ray, s, &mut rng, out);
    });
    set.emitted = n_photons;
    set
}

/// Continues photons that already scattered elsewhere (e.g. in the GPU bounce map): each
/// ray's next hit is stored with the ray's bounce index.
pub fn continue_paths(
    scene: &Scene,
    bvh: &SceneBvh,
    rays: &[PhotonRay],
    s: &PhotonTraceSettings,
    seed: u64,
) -> PhotonSet {
    let mut set = trace_chunks(rays.len() as u64, |i, out| {
        let mut rng = Rng::new(seed, STREAM_CONTINUE, i);
        follow(scene, bvh, &rays[i as usize], s, &mut rng, out);
    });
    set.emitted = rays.len() as u64;
    set
}

/// Runs `path(i, set)` for every `i < n` in parallel chunks and concatenates the chunks' sets
/// in order.
fn trace_chunks(n: u64, path: impl Fn(u64, &mut PhotonSet) + Sync) -> PhotonSet {
    let sets: Vec<PhotonSet> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|chunk| {
            let mut set = PhotonSet::default();
            for i in chunk * CHUNK..((chunk + 1) * CHUNK).min(n) {
                path(i, &mut set);
            }
            set
        })
        .collect();
    let mut all = PhotonSet {
        photons: Vec::with_capacity(sets.iter().map(|s| s.photons.len()).sum()),
        ..Default::default()
    };
    for set in sets {
        all.append(set);
    }
    all
}

/// Follows one photon until it is absorbed, escapes or reaches the bounce limit.
fn follow(
    scene: &Scene,
    bvh: &SceneBvh,
    ray: &PhotonRay,
    s: &PhotonTraceSettings,
    rng: &mut Rng,
    out: &mut PhotonSet,
) {
    let (mut o, mut d) = (ray.origin.into(), glam::Vec3::from(ray.direction));
    let mut power = glam::Vec3::from(ray.power);
    let mut density = ray.path_density;
    let mut bounce = ray.bounce;
    if power.max_element() <= 0.0 || !power.is_finite() {
        out.absorbed += 1;
        return;
    }
    loop {
        let Some(hit) = bvh.intersect(o, d, f32::INFINITY) else {
            out.escaped += 1;
            return;
        };
        let it = Interaction::new(scene, &hit, d);
        let wo = -d;

        // Store the photon where a non-delta lobe can reflect it towards a viewer.
        if !it.material.is_purely_specular() && (bounce > 0 || s.store_direct) {
            let normal = it.frame.n * it.ng.dot(wo).signum();
            out.store(Photon {
                position: it.position.into(),
                bounce,
                incident: wo.into(),
                path_density: density,
                power: power.into(),
                normal: normal.into(),
                ..Default::default()
            });
        }
        if bounce >= s.max_bounces {
            out.truncated += 1;
            return;
        }

        // Scatter: sample the BSDF; reflections must stay on the arrival side, refractions cross.
        let Some(bs) = it.material.sample(it.frame.to_local(wo), rng) else {
            out.absorbed += 1;
            return;
        };
        let wi = it.frame.to_world(bs.wi);
        let same_side = wi.dot(it.ng) * wo.dot(it.ng) > 0.0;
        if same_side == matches!(bs.lobe, Lobe::GlassRefract) {
            out.absorbed += 1;
            return;
        }

        // Possibly terminate the photon path with Russian roulette.
        let scattered = power * bs.weight;
        let q = (scattered.max_element() / power.max_element()).min(1.0);
        if q.is_nan() || q <= 0.0 || rng.next_f32() >= q {
            out.absorbed += 1;
            return;
        }
        power = scattered / q;
        density *= path_density_factor(it.material, bs.lobe);
        bounce += 1;
        o = it.spawn(wi);
        d = wi;
    }
}
