//! Next-event estimation from every kind of source: point and spot lights and parallel
//! suns exactly (each a delta, summed), a sun with an angular diameter by one direction in
//! its disc, the emitting triangles by one point (chosen for the shading point by
//! [`EmitterSampler`]: power, or the light BVH's power, distance and orientation) and the
//! environment by one direction drawn by importance. The path tracer continues its paths by
//! BSDF sampling and finds the same emitters, sun discs and sky with its own rays: the two
//! strategies are combined by multiple importance sampling (power heuristic), the light
//! samples here and the BSDF rays' hits by [`DirectLight::emitter_weight`] and
//! [`escaped`]. Methods without that continuation (`gather`, the photon methods' specular
//! paths) take the light samples at full weight.

use super::light_vertex::LightVertices;
use super::path::power_heuristic;
use super::{Interaction, SceneBvh};
use crate::sampling::Rng;
use crate::scene::emitters::{EmitterSampler, Selection};
use crate::scene::{Light, Scene};
use glam::Vec3;

/// Which light samples next-event estimation takes and how they are weighted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Nee {
    /// Every source, each sample at full weight: the caller's rays find no light (`gather`,
    /// the photon methods), or count none of what they find (a path tracer sampling lights
    /// only).
    Alone,
    /// Every source, the samples of emitters, suns' discs and the environment weighted
    /// against BSDF sampling, whose rays find them too.
    Mis,
    /// Only the lights BSDF rays cannot find (point, spot and parallel directional lights):
    /// a path tracer sampling the BSDF only, for the rest.
    DeltaOnly,
}

/// What next-event estimation samples beyond the analytic lights: the emitters with their
/// selection. Built once per frame.
#[derive(Clone, Debug)]
pub struct DirectLight {
    pub emitters: EmitterSampler,
    /// Whether a ray can find light by hitting it (an emitter, a sun's disc or the
    /// environment): without, the path tracer's last BSDF ray is not traced.
    pub found_by_rays: bool,
    /// Where the path tracer's light vertices start ([`super::light_vertex`]): `None`
    /// without point and spot lights.
    pub light_vertices: Option<LightVertices>,
}

/// A shading point asking for direct light: the point `it` (shadow rays through `bvh`), the
/// direction `wo` towards the viewer (world space, away from the surface), and whether the
/// light samples are weighted against BSDF sampling (`mis`, power heuristic) or taken at
/// full weight.
#[derive(Clone, Copy)]
pub struct LightQuery<'a> {
    pub bvh: &'a SceneBvh,
    pub it: &'a Interaction,
    pub wo: Vec3,
    pub mis: bool,
}

/// Where a BSDF-sampled ray left from, for the multiple-importance weight of an emitter it
/// hits: the shading point and normal the light samples there were drawn for, its
/// geometric normal, and the BSDF sample's density over solid angle.
#[derive(Clone, Copy, Debug)]
pub struct BsdfVertex {
    pub position: Vec3,
    pub normal: Vec3,
    pub ng: Vec3,
    pub pdf: f32,
}

/// A third strategy that samples some of the light next-event estimation and BSDF rays
/// find: the path tracer's light vertices (`super::light_vertex`), for the weights of
/// next-event estimation's samples.
pub trait SharedLight {
    /// The weight of the light of point or spot light `light` at `it`.
    fn light_weight(&self, light: usize, it: &Interaction) -> f32;
    /// The other strategy's density for the emitter point `point` (on scene triangle
    /// `triangle`) seen from `it`, on the scale of next-event estimation's density over
    /// solid angle at `it` (0: it cannot sample that light; infinite: it takes all).
    fn emitter_pdf(&self, it: &Interaction, point: Vec3, triangle: u32) -> f32;
}

/// Whether light arriving at `it` from `wi` leaves towards `wo` (world space, both away
/// from the surface) through its non-delta lobes, as far as the sides go: on the viewer's
/// side of the geometry (reflection), or across it through rough glass (its transmission
/// is a non-delta lobe; the shading frame must agree that the pair crosses). Light samples
/// refused here must be refused by the weights of the BSDF rays that find the same light
/// too ([`sampling_normal`]): rough glass's light across it came at a reduced weight from
/// its BSDF rays alone while next-event estimation never sampled it (`path` 0.983 of
/// Mitsuba on the roughdielectric sphere, its caustic 12–25% dark).
pub fn reaches(it: &Interaction, wo: Vec3, wi: Vec3) -> bool {
    let side = wi.dot(it.ng) * wo.dot(it.ng);
    if side > 0.0 {
        return true;
    }
    side < 0.0 && it.material.rough_glass && wi.dot(it.frame.n) * wo.dot(it.frame.n) < 0.0
}

/// The surface normal the emitters are sampled for at `it` ([`EmitterSampler::sample`],
/// whose light BVH discards the emitters behind it): zero (every direction) on rough glass,
/// which transmits light from behind ([`reaches`]).
pub fn sampling_normal(it: &Interaction) -> Vec3 {
    if it.material.rough_glass {
        Vec3::ZERO
    } else {
        it.frame.n
    }
}

/// Power heuristic (β = 2) weight of a strategy of density `a` against two others.
#[inline]
pub fn power_weight(a: f32, [b, c]: [f32; 2]) -> f32 {
    let a2 = a * a;
    let sum = a2 + b * b + c * c;
    if a2.is_infinite() {
        1.0
    } else if sum.is_infinite() || sum.is_nan() || sum <= 0.0 {
        0.0
    } else {
        a2 / sum
    }
}

impl DirectLight {
    /// The scene's emitters with the selection that pays for their number
    /// ([`EmitterSampler::auto`]).
    pub fn of(scene: &Scene) -> Self {
        Self::from_emitters(scene, EmitterSampler::auto(scene))
    }

    /// The scene's emitters chosen by `selection`.
    pub fn with_selection(scene: &Scene, selection: Selection) -> Self {
        Self::from_emitters(scene, EmitterSampler::new(scene, selection))
    }

    fn from_emitters(scene: &Scene, emitters: EmitterSampler) -> Self {
        let found_by_rays = scene.materials.iter().any(|m| m.emits())
            || scene.environment.is_some()
            || scene.lights.iter().any(|l| l.disc_radiance().is_some());
        DirectLight {
            emitters,
            found_by_rays,
            light_vertices: LightVertices::of(scene),
        }
    }

    /// Light arriving at `it` directly from the sources `nee` says, times the BSDF towards
    /// `wo` (world space, pointing away from the surface); the point and spot lights' and
    /// the emitters' samples weighted against a third strategy that finds the same light,
    /// where `shared` says.
    #[allow(clippy::too_many_arguments)]
    pub fn estimate(
        &self,
        scene: &Scene,
        bvh: &SceneBvh,
        it: &Interaction,
        wo: Vec3,
        rng: &mut Rng,
        nee: Nee,
        shared: Option<&dyn SharedLight>,
    ) -> Vec3 {
        if it.material.is_purely_specular() {
            return Vec3::ZERO;
        }
        let mis = nee == Nee::Mis;
        let q = LightQuery { bvh, it, wo, mis };
        let mut sum = Vec3::ZERO;
        for (i, light) in scene.lights.iter().enumerate() {
            sum += match light.disc_radiance() {
                Some(_) if nee == Nee::DeltaOnly => Vec3::ZERO,
                Some(l) => sun_disc(light, l, q, rng),
                None => {
                    let l = analytic_light(light, bvh, it, wo);
                    match shared {
                        Some(shared) if l != Vec3::ZERO => l * shared.light_weight(i, it),
                        _ => l,
                    }
                }
            };
        }
        if nee == Nee::DeltaOnly {
            return sum;
        }
        sum += self.emitter_light_weighted(scene, q, rng, shared);
        // An environment that is not sampled by importance is left to the BSDF rays of the
        // path tracer (`EnvironmentDesc::importance`); without them it is sampled anyway.
        if let Some(env) = scene
            .environment
            .as_deref()
            .filter(|e| e.importance || !mis)
        {
            sum += super::path::environment_light(env, q, rng);
        }
        sum
    }

    /// One point on the emitters, chosen for `it`: its light times the BSDF towards `wo`.
    pub fn emitter_light(&self, scene: &Scene, q: LightQuery, rng: &mut Rng) -> Vec3 {
        self.emitter_light_weighted(scene, q, rng, None)
    }

    /// [`DirectLight::emitter_light`], weighted against `shared` too.
    fn emitter_light_weighted(
        &self,
        scene: &Scene,
        q: LightQuery,
        rng: &mut Rng,
        shared: Option<&dyn SharedLight>,
    ) -> Vec3 {
        let LightQuery { bvh, it, wo, mis } = q;
        if self.emitters.is_empty() {
            return Vec3::ZERO;
        }
        let (u_select, u) = (rng.next_f32(), rng.next_2d());
        let n = sampling_normal(it);
        let Some(s) = self.emitters.sample(scene, it.position, n, u_select, u) else {
            return Vec3::ZERO;
        };
        let to = s.point - it.position;
        let d2 = to.length_squared();
        if !(d2 > 0.0 && s.pdf_area > 0.0) {
            return Vec3::ZERO;
        }
        let wi = to / d2.sqrt();
        let cos_l = s.normal.dot(-wi).abs();
        if cos_l <= 0.0 || !reaches(it, wo, wi) {
            return Vec3::ZERO;
        }
        let le = self.emitters.emitters.radiance(scene, &s, -wi);
        if le == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let m = &it.material;
        let (wo_l, wi_l) = (it.frame.to_local(wo), it.frame.to_local(wi));
        let f = m.eval(wo_l, wi_l);
        if f == Vec3::ZERO {
            return Vec3::ZERO;
        }
        // The shadow ray runs from off the shading surface to off the emitter's side facing
        // it, along its own direction: along `wi` from the moved origin it would end beside
        // the target, behind the emitter's surface where the two offsets cancel (an emitter
        // facing the point), and find the emitter itself.
        let origin = it.spawn(wi);
        let side = s.normal * s.normal.dot(-wi).signum();
        let target = s.point + side * crate::scene::emitters::offset(s.point);
        let to_target = target - origin;
        let dist = to_target.length();
        if dist.is_nan()
            || dist <= 0.0
            || bvh.occluded(origin, to_target / dist, dist * (1.0 - 1e-4))
        {
            return Vec3::ZERO;
        }
        let pdf = s.pdf_area * d2 / cos_l;
        let bsdf = if mis { m.pdf(wo_l, wi_l) } else { 0.0 };
        let other = shared.map_or(0.0, |o| o.emitter_pdf(it, s.point, s.triangle));
        let w = power_weight(pdf, [bsdf, other]);
        f * wi_l.z.abs() * le * (w / pdf)
    }

    /// The multiple-importance weight of emitter triangle `triangle` hit at `point` (normal
    /// `ng`) by the BSDF sample that left `from`: the power heuristic of the sample's density
    /// against that of [`DirectLight::emitter_light`] drawing the same point (where `nee`)
    /// and the density `other` of a third strategy (on the same scale: solid angle at
    /// `from`).
    pub fn emitter_weight(
        &self,
        from: &BsdfVertex,
        (triangle, point, ng): (u32, Vec3, Vec3),
        nee: bool,
        other: f32,
    ) -> f32 {
        let pdf_area = if nee {
            self.emitters.pdf_area(from.position, from.normal, triangle)
        } else {
            0.0
        };
        let to = point - from.position;
        let d2 = to.length_squared();
        let cos = ng.dot(to).abs() / d2.sqrt();
        let light = if pdf_area > 0.0 && cos > 0.0 {
            pdf_area * d2 / cos
        } else {
            0.0
        };
        power_weight(from.pdf, [light, other])
    }
}

/// Light of every point, spot and directional light of `scene` arriving at `it`, times the
/// BSDF towards `wo`: the delta lights exactly (one shadow ray each), a sun with a disc by
/// one direction in it, weighted against BSDF rays with `mis`.
pub fn analytic_lights(scene: &Scene, q: LightQuery, rng: &mut Rng) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for light in &scene.lights {
        sum += match light.disc_radiance() {
            Some(l) => sun_disc(light, l, q, rng),
            None => analytic_light(light, q.bvh, q.it, q.wo),
        };
    }
    sum
}

/// Light of a point, spot or parallel directional light arriving at `it`, times the BSDF
/// towards `wo` (a directional light with a disc: along its axis).
pub fn analytic_light(light: &Light, bvh: &SceneBvh, it: &Interaction, wo: Vec3) -> Vec3 {
    let m = &it.material;
    let (wi, li, dist) = match *light {
        Light::Directional {
            direction,
            irradiance,
            ..
        } => (-direction, irradiance, f32::INFINITY),
        _ => {
            let to_light = light.position() - it.position;
            let dist2 = to_light.length_squared();
            let dist = dist2.sqrt();
            let wi = to_light / dist;
            (wi, light.intensity_towards(-wi) / dist2, dist)
        }
    };
    if !reaches(it, wo, wi) || li == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let (wo_l, wi_l) = (it.frame.to_local(wo), it.frame.to_local(wi));
    let f = m.eval(wo_l, wi_l);
    if f == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let origin = it.spawn(wi);
    let t_max = if dist.is_finite() {
        (light.position() - origin).length() * (1.0 - 1e-4)
    } else {
        f32::INFINITY
    };
    if bvh.occluded(origin, wi, t_max) {
        return Vec3::ZERO;
    }
    f * wi_l.z.abs() * li
}

/// One direction in the disc of a directional light of radiance `radiance` (uniform in
/// solid angle): its light at `it` times the BSDF towards `wo`, weighted against BSDF
/// sampling with `mis`.
fn sun_disc(light: &Light, radiance: Vec3, q: LightQuery, rng: &mut Rng) -> Vec3 {
    let LightQuery { bvh, it, wo, mis } = q;
    let Some((wi, pdf)) = light.sample_towards(rng.next_2d()) else {
        return Vec3::ZERO;
    };
    if !(pdf > 0.0 && pdf.is_finite() && reaches(it, wo, wi)) {
        return Vec3::ZERO;
    }
    let m = &it.material;
    let (wo_l, wi_l) = (it.frame.to_local(wo), it.frame.to_local(wi));
    let f = m.eval(wo_l, wi_l);
    if f == Vec3::ZERO || bvh.occluded(it.spawn(wi), wi, f32::INFINITY) {
        return Vec3::ZERO;
    }
    let w = if mis {
        power_heuristic(pdf, m.pdf(wo_l, wi_l))
    } else {
        1.0
    };
    f * wi_l.z.abs() * radiance * (w / pdf)
}

/// Radiance a ray leaving the scene in unit direction `d` finds: the environment's and the
/// suns' discs' (with `suns`). `bsdf_pdf`: the density of the BSDF sample that made the
/// ray, which weighs it against next-event estimation's samples of the same sources
/// (`None`: camera rays and delta scatterings, full weight).
pub fn escaped(scene: &Scene, d: Vec3, bsdf_pdf: Option<f32>, suns: bool) -> Vec3 {
    let mut l = Vec3::ZERO;
    if let Some(env) = scene.environment.as_deref() {
        let w = match bsdf_pdf {
            Some(p) if env.importance => power_heuristic(p, env.pdf(d)),
            _ => 1.0,
        };
        l += env.radiance(d) * w;
    }
    if suns {
        for light in &scene.lights {
            let le = light.disc_radiance_from(d);
            if le != Vec3::ZERO {
                let w = bsdf_pdf.map_or(1.0, |p| power_heuristic(p, light.disc_pdf()));
                l += le * w;
            }
        }
    }
    l
}
