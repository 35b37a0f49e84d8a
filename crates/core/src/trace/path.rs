//! The reference path tracer: next-event estimation to every point and spot light, BSDF
//! importance sampling and Russian roulette. An environment light is sampled by importance
//! and by the BSDF, the two combined by multiple importance sampling (power heuristic); rays
//! that leave the scene (camera rays included) take the environment's radiance. A camera
//! path can never reach a point light through a delta (mirror or glass) scattering, so paths
//! whose first bounce from the light is specular are left to the light tracer
//! ([`super::light_tracer`]).

use super::{Interaction, SceneBvh};
use crate::image::Image;
use crate::sampling::Rng;
use crate::scene::{Environment, Light, Scene};
use glam::Vec3;

/// Path tracer settings.
#[derive(Clone, Copy, Debug)]
pub struct PathSettings {
    /// Maximum number of surface interactions per path (1 = direct light only).
    pub max_depth: u32,
    /// Interactions before Russian roulette may end a path.
    pub rr_depth: u32,
}

/// What the camera ray sees first, for the auxiliary images.
#[derive(Clone, Copy, Debug, Default)]
pub struct FirstHit {
    pub albedo: Vec3,
    pub normal: Vec3,
    pub position: Vec3,
    /// Distance along the camera's forward axis (view-space z), 0 on a miss.
    pub depth: f32,
}

/// The first-hit images of a frame (the AOVs of the CPU methods), `width × height`.
#[derive(Clone, Debug)]
pub struct FirstHitImages {
    pub albedo: Image,
    pub normal: Image,
    pub position: Image,
    pub depth: Vec<f32>,
}

impl FirstHitImages {
    /// The images of `hits`, one per pixel in row order.
    pub fn of(width: u32, height: u32, hits: impl IntoIterator<Item = FirstHit>) -> Self {
        let mut out = FirstHitImages {
            albedo: Image::new(width, height),
            normal: Image::new(width, height),
            position: Image::new(width, height),
            depth: vec![0.0; (width * height) as usize],
        };
        for (i, fh) in hits.into_iter().enumerate() {
            out.albedo.pixels[i] = fh.albedo;
            out.normal.pixels[i] = fh.normal;
            out.position.pixels[i] = fh.position;
            out.depth[i] = fh.depth;
        }
        out
    }
}

/// Light arriving at `it` from every light by direct paths, times the BSDF towards `wo`
/// (world space, pointing away from the surface).
pub fn direct_light(scene: &Scene, bvh: &SceneBvh, it: &Interaction, wo: Vec3) -> Vec3 {
    let m = it.material;
    if m.is_purely_specular() {
        return Vec3::ZERO;
    }
    let wo_l = it.frame.to_local(wo);
    let mut sum = Vec3::ZERO;
    for light in &scene.lights {
        if let Light::Directional {
            direction,
            irradiance,
            ..
        } = *light
        {
            // Parallel light along the disc's axis.
            let wi = -direction;
            if wi.dot(it.ng) * wo.dot(it.ng) <= 0.0 || irradiance == Vec3::ZERO {
                continue;
            }
            let wi_l = it.frame.to_local(wi);
            let f = m.eval(wo_l, wi_l);
            if f != Vec3::ZERO && !bvh.occluded(it.spawn(wi), wi, f32::INFINITY) {
                sum += f * wi_l.z.abs() * irradiance;
            }
            continue;
        }
        let to_light = light.position() - it.position;
        let dist2 = to_light.length_squared();
        let dist = dist2.sqrt();
        let wi = to_light / dist;
        // Reflection only: the light must be on the viewer's side of the geometry.
        if wi.dot(it.ng) * wo.dot(it.ng) <= 0.0 {
            continue;
        }
        let li = light.intensity_towards(-wi) / dist2;
        if li == Vec3::ZERO {
            continue;
        }
        let wi_l = it.frame.to_local(wi);
        let f = m.eval(wo_l, wi_l);
        if f == Vec3::ZERO {
            continue;
        }
        let origin = it.spawn(wi);
        if bvh.occluded(
            origin,
            wi,
            (light.position() - origin).length() * (1.0 - 1e-4),
        ) {
            continue;
        }
        sum += f * wi_l.z.abs() * li;
    }
    sum
}

/// Power heuristic (β = 2) weight of a strategy of density `a` against one of density `b`.
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 && a2.is_finite() {
        a2 / (a2 + b2)
    } else if a2.is_infinite() {
        1.0
    } else {
        0.0
    }
}

/// Environment light arriving at `it` from one direction sampled by importance, times the
/// BSDF towards `wo`, weighted against BSDF sampling (the path's BSDF-sampled continuation,
/// which may also escape to the environment) by the power heuristic.
pub fn environment_light(
    env: &Environment,
    bvh: &SceneBvh,
    it: &Interaction,
    wo: Vec3,
    rng: &mut Rng,
) -> Vec3 {
    let u = rng.next_2d();
    let m = it.material;
    if m.is_purely_specular() {
        return Vec3::ZERO;
    }
    let Some(s) = env.sample(u) else {
        return Vec3::ZERO;
    };
    if s.pdf <= 0.0 || s.radiance == Vec3::ZERO || s.wi.dot(it.ng) * wo.dot(it.ng) <= 0.0 {
        return Vec3::ZERO;
    }
    let (wo_l, wi_l) = (it.frame.to_local(wo), it.frame.to_local(s.wi));
    let f = m.eval(wo_l, wi_l);
    if f == Vec3::ZERO || bvh.occluded(it.spawn(s.wi), s.wi, f32::INFINITY) {
        return Vec3::ZERO;
    }
    let w = power_heuristic(s.pdf, m.pdf(wo_l, wi_l));
    f * wi_l.z.abs() * s.radiance * (w / s.pdf)
}

/// What the ray `origin + t·dir` hits first.
pub fn first_hit(scene: &Scene, bvh: &SceneBvh, origin: Vec3, dir: Vec3) -> FirstHit {
    let Some(hit) = bvh.intersect(origin, dir, f32::INFINITY) else {
        return FirstHit::default();
    };
    let it = Interaction::new(scene, &hit, dir);
    let wo = -dir;
    let n = if it.frame.n.dot(wo) < 0.0 {
        -it.frame.n
    } else {
        it.frame.n
    };
    FirstHit {
        albedo: it.material.scatter_probability(it.frame.to_local(wo)),
        normal: n,
        position: it.position,
        depth: (it.position - scene.camera.position).dot(scene.camera.forward),
    }
}

/// Radiance arriving at `origin` from direction `-dir`.
pub fn radiance(
    scene: &Scene,
    bvh: &SceneBvh,
    origin: Vec3,
    dir: Vec3,
    rng: &mut Rng,
    s: &PathSettings,
) -> Vec3 {
    let mut l = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    let (mut o, mut d) = (origin, dir);
    let env = scene.environment.as_deref();
    // Solid-angle density of the BSDF sample that made the current ray, when the vertex it
    // left also sampled the environment (MIS applies); `None` for camera rays, delta
    // scattering and environments that are not sampled by importance.
    let mut bsdf_pdf: Option<f32> = None;
    // With an environment, the path goes one step beyond its last interaction: a BSDF
    // sample from the last vertex that escapes still carries direct light from the sky
    // (so `max_depth` 1 is direct light for both sampling strategies).
    let steps = s.max_depth + u32::from(env.is_some());
    for depth in 0..steps {
        let Some(hit) = bvh.intersect(o, d, f32::INFINITY) else {
            if let Some(env) = env {
                let w = bsdf_pdf.map_or(1.0, |p| power_heuristic(p, env.pdf(d)));
                l += beta * env.radiance(d) * w;
            }
            break;
        };
        if depth == s.max_depth {
            break; // a surface beyond the last interaction: only escapes count there
        }
        let it = Interaction::new(scene, &hit, d);
        let wo = -d;
        // Emitting surfaces are found by the paths' own rays (next-event estimation does
        // not sample them).
        l += beta * it.material.emitted(it.ng, wo);
        // Next-event estimation.
        l += beta * direct_light(scene, bvh, &it, wo);
        let env_mis = env.is_some_and(|e| e.importance);
        if let Some(env) = env.filter(|e| e.importance) {
            l += beta * environment_light(env, bvh, &it, wo, rng);
        }
        if depth + 1 == steps {
            break;
        }
        // Continue the path by sampling the BSDF.
        let wo_l = it.frame.to_local(wo);
        let Some(bs) = it.material.sample(wo_l, rng) else {
            break;
        };
        let wi = it.frame.to_world(bs.wi);
        // The sample must agree with the geometry: reflections stay on the viewer's side,
        // refractions cross.
        let same_side = wi.dot(it.ng) * wo.dot(it.ng) > 0.0;
        if same_side == matches!(bs.lobe, crate::bsdf::Lobe::GlassRefract) {
            break;
        }
        beta *= bs.weight;
        bsdf_pdf = (env_mis && !bs.lobe.is_delta()).then_some(bs.pdf);
        // Possibly terminate the path with Russian roulette.
        if depth + 1 >= s.rr_depth {
            let q = beta.max_element().min(0.95);
            if q <= 0.0 || rng.next_f32() >= q {
                break;
            }
            beta /= q;
        }
        o = it.spawn(wi);
        d = wi;
    }
    l
}
