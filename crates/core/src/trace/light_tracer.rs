//! Light tracing for the paths a path tracer cannot sample with point lights: those whose
//! first scattering after leaving the light is a delta lobe (mirror or glass). Photons are
//! emitted from the lights, followed through that specular bounce and beyond, and connected
//! to the pinhole camera at every later non-delta vertex. Paths whose first bounce is
//! non-delta end immediately: next-event estimation in the path tracer already covers them,
//! so the two estimates add up without double counting.

use super::{Interaction, SceneBvh};
use crate::sampling::Rng;
use crate::scene::Scene;
use glam::Vec3;

/// Light tracer settings.
#[derive(Clone, Copy, Debug)]
pub struct LightTraceSettings {
    pub max_depth: u32,
    pub rr_depth: u32,
}

/// Chooses a light with probability proportional to its power; returns (index, probability).
pub fn choose_light(weights: &[f32], u: f32) -> Option<(usize, f32)> {
    let total: f32 = weights.iter().sum();
    if total <= 0.0 {
        return None;
    }
    let mut acc = 0.0;
    for (i, w) in weights.iter().enumerate() {
        acc += w / total;
        if u < acc && *w > 0.0 {
            return Some((i, w / total));
        }
    }
    let last = weights.iter().rposition(|w| *w > 0.0)?;
    Some((last, weights[last] / total))
}

/// Power-proportional selection weights of the scene's lights (mean over channels).
pub fn light_weights(scene: &Scene) -> Vec<f32> {
    scene
        .lights
        .iter()
        .map(|l| l.power(scene.bounds()).element_sum() / 3.0)
        .collect()
}

/// Traces one of `total` light paths and appends its camera connections to `splats` as
/// (pixel index, pixel radiance in W·sr⁻¹·m⁻²).
pub fn trace_path(
    scene: &Scene,
    bvh: &SceneBvh,
    weights: &[f32],
    rng: &mut Rng,
    total: u64,
    s: &LightTraceSettings,
    splats: &mut Vec<(u32, Vec3)>,
) {
    let cam = &scene.camera;
    let Some((li, p_light)) = choose_light(weights, rng.next_f32()) else {
        return;
    };
    let e = scene.lights[li].emit(rng, scene.bounds());
    let mut power = e.power / (p_light * total as f32);
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
        let Some(bs) = it.material.sample(it.frame.to_local(w_prev), rng) else {
            return;
        };
        // Only paths whose first bounce is specular belong to this estimator.
        if depth == 0 && !bs.lobe.is_delta() {
            return;
        }
        let wi = it.frame.to_world(bs.wi);
        let same_side = wi.dot(it.ng) * w_prev.dot(it.ng) > 0.0;
        if same_side == matches!(bs.lobe, crate::bsdf::Lobe::GlassRefract) {
            return;
        }
        power *= bs.weight;
        if depth + 1 >= s.rr_depth {
            let q = (power.max_element() / (e.power.max_element() / (p_light * total as f32)))
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
