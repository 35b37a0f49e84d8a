//! Direct light at a surface by both strategies, for camera paths that end there (`gather`,
//! the camera half of `photon`'s sky and lights): next-event estimation ([`Nee::Mis`]) and one
//! BSDF-sampled ray, whose escape finds the environment and the suns' discs and whose hit
//! finds emitters, combined by the power heuristic as the path tracer combines them.
//!
//! Light sampling alone misses the glossy (GGX) lobe: a lobe of α = 0.04 covers about
//! 10⁻³ of the sky's directions, so one sky direction per sample finds it rarely and the
//! estimate, unbiased but heavy-tailed, reads 30% dark at 16 samples per pixel on a glossy
//! sphere under a constant sky. The BSDF ray finds the lobe's light at every sample.

use super::direct::{analytic_lights, escaped, BsdfVertex, DirectLight, LightQuery, Nee};
use super::{Interaction, SceneBvh};
use crate::sampling::Rng;
use crate::scene::Scene;
use glam::Vec3;

/// Which sources [`mis_direct`] covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sources {
    /// Every source: point, spot and directional lights, emitters, suns' discs, the sky.
    All,
    /// Only the environment (the sky), for a caller whose photons carry the rest.
    Environment,
    /// The environment and the point, spot and directional lights (suns' discs included):
    /// every source but the emitting triangles, for a caller whose photons carry theirs.
    Lights,
}

/// Light arriving at `it` directly from `sources`, times the BSDF's non-delta lobes towards
/// `wo` (world space, away from the surface): next-event estimation and one BSDF ray,
/// weighted by the power heuristic. Unbiased for every lobe.
pub fn mis_direct(
    scene: &Scene,
    bvh: &SceneBvh,
    lights: &DirectLight,
    (it, wo): (&Interaction, Vec3),
    rng: &mut Rng,
    sources: Sources,
) -> Vec3 {
    if it.material.is_purely_specular() {
        return Vec3::ZERO;
    }
    let q = LightQuery {
        bvh,
        it,
        wo,
        mis: true,
    };
    let sky = |rng: &mut Rng| match scene.environment.as_deref() {
        Some(env) if env.importance => super::path::environment_light(env, q, rng),
        _ => Vec3::ZERO,
    };
    let nee = match sources {
        Sources::All => lights.estimate(scene, bvh, it, wo, rng, Nee::Mis, None),
        Sources::Environment => sky(rng),
        Sources::Lights => analytic_lights(scene, q, rng) + sky(rng),
    };
    nee + bsdf_ray(scene, lights, q, rng, sources)
}

/// One BSDF sample at `it` towards `wo` and its world direction, where it is a non-delta
/// reflection: delta lobes are the camera pass's own (it follows them), and refraction is
/// neither reflected direct light nor a final-gather ray of the reflected light.
pub fn reflection_sample(
    it: &Interaction,
    wo: Vec3,
    rng: &mut Rng,
) -> Option<(crate::bsdf::BsdfSample, Vec3)> {
    let bs = it.material.sample(it.frame.to_local(wo), rng)?;
    let wi = it.frame.to_world(bs.wi);
    (!bs.lobe.is_delta() && wi.dot(it.ng) * wo.dot(it.ng) > 0.0).then_some((bs, wi))
}

/// The light one non-delta BSDF sample finds where its ray leaves the scene or meets an
/// emitter, weighted against next-event estimation's samples of the same light.
fn bsdf_ray(
    scene: &Scene,
    lights: &DirectLight,
    q: LightQuery,
    rng: &mut Rng,
    sources: Sources,
) -> Vec3 {
    let LightQuery { bvh, it, wo, .. } = q;
    if !lights.found_by_rays {
        return Vec3::ZERO;
    }
    let Some((bs, wi)) = reflection_sample(it, wo, rng) else {
        return Vec3::ZERO;
    };
    let suns = sources != Sources::Environment;
    let Some(hit) = bvh.intersect(it.spawn(wi), wi, f32::INFINITY) else {
        return bs.weight * escaped(scene, wi, Some(bs.pdf), suns);
    };
    if sources != Sources::All {
        return Vec3::ZERO;
    }
    let at = Interaction::new(scene, &hit, wi);
    if !at.material.emits() {
        return Vec3::ZERO;
    }
    let from = BsdfVertex {
        position: it.position,
        normal: it.frame.n,
        ng: it.ng,
        pdf: bs.pdf,
    };
    let w = lights.emitter_weight(&from, (at.triangle, at.position, at.ng), true, 0.0);
    bs.weight * at.material.emitted(at.ng, -wi) * w
}
