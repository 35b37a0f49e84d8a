//! Light tracing for the paths a path tracer cannot sample well: those whose first
//! scattering after leaving the source is a delta lobe (mirror or glass), impossible to
//! reach from the camera for point lights and parallel suns and found only by chance for
//! small emitters and a sun's disc. Photons are emitted from every source but the sky
//! (point, spot, directional lights and emitting triangles, by power), followed through
//! that specular bounce and beyond, and connected to the pinhole camera at every later
//! non-delta vertex. Paths whose first bounce is non-delta end immediately: next-event
//! estimation in the path tracer already covers them; the path tracer in turn leaves out
//! the emitter and sun hits that these connections make (`PathSettings::light_traced`), so
//! the two estimates add up without double counting.

use super::{Interaction, SceneBvh};
use crate::cancel::StageProgress;
use crate::image::Image;
use crate::sampling::Rng;
use crate::scene::{Scene, Source, Sources};
use glam::Vec3;
use rayon::prelude::*;

/// Light paths per parallel work item of [`image`] (one progress step each).
pub const CHUNK: u64 = 1 << 14;

/// Light tracer settings.
#[derive(Clone, Copy, Debug)]
pub struct LightTraceSettings {
    pub max_depth: u32,
    pub rr_depth: u32,
    /// Only the delta chains: a path ends at its first non-delta scattering, so that it
    /// connects to the camera the vertices reached through delta lobes alone (L S+ D E;
    /// `bidir`'s emitters and suns, whose longer paths its VPLs carry).
    pub chain_only: bool,
}

/// The sources light paths start from: every one but the environment, whose caustics the
/// path tracer finds by itself (a sky is large: its rays reach it through glass often).
pub fn light_sources(scene: &Scene) -> Sources {
    Sources::filtered(scene, |s| s != Source::Environment)
}

/// The image of `paths` light paths from `sources` (path `i` drawing from
/// `Rng::new(seed, stream, i)`), up to the settings' depth. Each chunk of [`CHUNK`] paths
/// returns its camera connections, which are summed in path order, so that the image is bit
/// for bit the same for a seed on any schedule. `stage` advances one step a chunk; when it
/// is stopped the paths still untraced are left out.
pub fn image(
    scene: &Scene,
    bvh: &SceneBvh,
    sources: &Sources,
    (paths, seed, stream): (u64, u64, u64),
    s: &LightTraceSettings,
    stage: &StageProgress,
) -> Image {
    let splats: Vec<Vec<(u32, Vec3)>> = (0..paths.div_ceil(CHUNK))
        .into_par_iter()
        .map(|chunk| {
            let mut splats = Vec::new();
            for i in chunk * CHUNK..((chunk + 1) * CHUNK).min(paths) {
                if i % 256 == 0 && stage.stopped() {
                    return splats;
                }
                let mut rng = Rng::new(seed, stream, i);
                trace_path(scene, bvh, sources, &mut rng, paths, s, &mut splats);
            }
            stage.advance(1);
            splats
        })
        .collect();
    let mut image = Image::new(scene.camera.width, scene.camera.height);
    for (pixel, value) in splats.into_iter().flatten() {
        image.pixels[pixel as usize] += value;
    }
    image
}

/// Traces one of `total` light paths and appends its camera connections to `splats` as
/// (pixel index, pixel radiance in W·sr⁻¹·m⁻²).
pub fn trace_path(
    scene: &Scene,
    bvh: &SceneBvh,
    sources: &Sources,
    rng: &mut Rng,
    total: u64,
    s: &LightTraceSettings,
    splats: &mut Vec<(u32, Vec3)>,
) {
    let cam = &scene.camera;
    let Some((_, _, e)) = sources.emit(scene, rng) else {
        return;
    };
    let start = e.power / total as f32;
    let mut power = start;
    let (mut o, mut d) = (e.origin, e.direction);
    let pixel_area = cam.pixel_area();
    for depth in 0..s.max_depth {
        let Some(hit) = bvh.intersect(o, d, f32::INFINITY) else {
            return;
        };
        let it = Interaction::new(scene, &hit, d);
        let w_prev = -d;
        // Connect vertices after the first (specular) bounce to the camera.
        if depth > 0 && !it.material.is_purely_specular() {
            if let Some((px, py, cos_cam)) = cam.project(it.position) {
                let to_cam = cam.position - it.position;
                let dist2 = to_cam.length_squared();
                let wc = to_cam / dist2.sqrt();
                if wc.dot(it.ng) * w_prev.dot(it.ng) > 0.0 {
                    let f = it
                        .material
                        .eval(it.frame.to_local(wc), it.frame.to_local(w_prev));
                    let origin = it.spawn(wc);
                    if f != Vec3::ZERO
                        && !bvh.occluded(
                            origin,
                            wc,
                            (cam.position - origin).length() * (1.0 - 1e-4),
                        )
                    {
                        // Flux → pixel radiance: f·|cos θx|/d² is the radiance's solid-angle
                        // density at the eye; dividing by the pixel's solid angle
                        // (A_pixel·cos³θc) averages it over the pixel.
                        let contrib = power * f * wc.dot(it.ng).abs()
                            / (dist2 * pixel_area * cos_cam.powi(3));
                        splats.push((py as u32 * cam.width + px as u32, contrib));
                    }
                }
            }
        }
        let Some(bs) = it.material.sample_adjoint(it.frame.to_local(w_prev), rng) else {
            return;
        };
        // Only paths whose first bounce is specular belong to this estimator (with
        // `chain_only`, only their delta scatterings).
        if (depth == 0 || s.chain_only) && !bs.lobe.is_delta() {
            return;
        }
        let wi = it.frame.to_world(bs.wi);
        let same_side = wi.dot(it.ng) * w_prev.dot(it.ng) > 0.0;
        if same_side == bs.lobe.crosses() {
            return;
        }
        power *= bs.weight;
        // Russian roulette as the path tracer's (`RR_SURVIVAL_SCALE`), on the power relative
        // to the path's start.
        if depth + 1 >= s.rr_depth {
            let q = (power.max_element() / start.max_element() * super::path::RR_SURVIVAL_SCALE)
                .min(0.95);
            if q <= 0.0 || rng.next_f32() >= q {
                return;
            }
            power /= q;
        }
        o = it.spawn(wi);
        d = wi;
    }
}
