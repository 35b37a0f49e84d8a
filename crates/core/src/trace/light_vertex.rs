//! A second way for the path tracer to find light that reaches a camera path's vertex `x`
//! after one diffuse or glossy bounce from a point or spot light: a light vertex `y` (where
//! a ray from the light, drawn by power and by the light's own distribution of directions,
//! first lands; one per camera path) connected to `x` by a shadow ray, at every vertex of
//! the path. This is bidirectional path tracing's strategy with two light vertices (the
//! light and `y`) and the camera path's (Veach 1997, §10.2), combined with the path
//! tracer's own (a BSDF sample from `x` reaching `y`, then next-event estimation there) by
//! the power heuristic. Both sides weigh with the BSDF sample's density without Russian
//! roulette's survival probability, so that the two weights of a path still add up to 1.
//!
//! It pays where the light's first bounce is concentrated, as on a wall or ceiling next to
//! the light: a BSDF ray from a surface lit only indirectly finds that small bright patch
//! rarely, and the path tracer's image is noisy there, while the light's rays land on it
//! in proportion to its brightness. On the Cornell box with a point light of
//! `docs/bench/path-vs-mitsuba.md` the shadowed floor and the boxes' unlit sides hold most
//! of the path tracer's error.

use super::direct::BsdfVertex;
use super::path::power_heuristic;
use super::{Interaction, SceneBvh};
use crate::sampling::Rng;
use crate::scene::{Scene, Source, Sources};
use glam::Vec3;

/// Dimensions of a low-discrepancy sample that drawing a light vertex takes: the light (1)
/// and the direction from it (2).
pub const DIMENSIONS: u32 = 3;

/// How the path tracer uses light vertices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Connection {
    /// Light vertices and BSDF samples, weighted by multiple importance sampling.
    #[default]
    Mis,
    /// Light vertices alone for the paths they can sample (for tests: converges to the
    /// same image as the others).
    Alone,
    /// BSDF samples alone (no light vertices).
    Off,
}

/// The point and spot lights a light vertex can start from, drawn by power. Built once per
/// frame.
#[derive(Clone, Debug)]
pub struct LightVertices {
    sources: Sources,
}

/// Where a light's ray first landed on a surface that is not a perfect mirror or glass.
#[derive(Clone, Copy, Debug)]
pub struct LightVertex {
    it: Interaction,
    /// Unit direction from the vertex to its light.
    to_light: Vec3,
    /// The light's intensity along the ray over the density of drawing that ray (light
    /// and direction, W), divided by the cosine at the vertex to the geometric normal.
    power: Vec3,
    /// The density over area of drawing this vertex: the ray's density times the cosine
    /// at the vertex over the squared distance from the light.
    pdf_area: f32,
}

impl LightVertices {
    /// The point and spot lights of `scene`, or `None` when it has none.
    pub fn of(scene: &Scene) -> Option<Self> {
        let sources = Sources::filtered(scene, |s| match s {
            Source::Light(i) => scene.lights[i].is_local(),
            _ => false,
        });
        (!sources.is_empty()).then_some(LightVertices { sources })
    }

    /// Draws a light and a direction from it ([`DIMENSIONS`] draws from `rng`) and follows
    /// the ray to the first surface, which must not be purely specular.
    pub fn sample(&self, scene: &Scene, bvh: &SceneBvh, rng: &mut Rng) -> Option<LightVertex> {
        let (source, _, e) = self.sources.emit(scene, rng)?;
        let Source::Light(light) = source else {
            return None;
        };
        let hit = bvh.intersect(e.origin, e.direction, f32::INFINITY)?;
        let it = Interaction::new(scene, &hit, e.direction);
        let cos = e.direction.dot(it.ng).abs();
        if it.material.is_purely_specular() || cos < 1e-6 {
            return None;
        }
        let pdf_area = self.pdf_area(scene, light, it.position, it.ng);
        (pdf_area > 0.0 && pdf_area.is_finite()).then_some(LightVertex {
            it,
            to_light: -e.direction,
            power: e.power / cos,
            pdf_area,
        })
    }

    /// The density over area with which [`LightVertices::sample`] lands on `point` (with
    /// geometric normal `ng`) from `scene.lights[light]`: 0 for lights it does not draw.
    pub fn pdf_area(&self, scene: &Scene, light: usize, point: Vec3, ng: Vec3) -> f32 {
        let p = self.sources.prob(Source::Light(light));
        if p <= 0.0 {
            return 0.0;
        }
        let l = &scene.lights[light];
        let d = point - l.position();
        let dist2 = d.length_squared();
        let dir = d / dist2.sqrt();
        p * l.emit_pdf(dir) * dir.dot(ng).abs() / dist2
    }

    /// The light of `v` reflected at the camera path's vertex `it` towards `wo` (world,
    /// away from the surface), through a shadow ray between them, weighted by `connection`
    /// against the path tracer's BSDF sample from `it` (which finds `v` with the BSDF's
    /// density over solid angle, here converted to area at `v`).
    pub fn connect(
        bvh: &SceneBvh,
        it: &Interaction,
        wo: Vec3,
        v: &LightVertex,
        connection: Connection,
    ) -> Vec3 {
        let d = v.it.position - it.position;
        let dist2 = d.length_squared();
        if connection == Connection::Off || it.material.is_purely_specular() || dist2 <= 0.0 {
            return Vec3::ZERO;
        }
        let wi = d / dist2.sqrt();
        // Reflection at both ends: the light on the viewer's side of `y`, `y` on the
        // viewer's side of `x` (what next-event estimation and BSDF sampling allow).
        let wy = -wi;
        if wi.dot(it.ng) * wo.dot(it.ng) <= 0.0 || wy.dot(v.it.ng) * v.to_light.dot(v.it.ng) <= 0.0
        {
            return Vec3::ZERO;
        }
        let (wo_l, wi_l) = (it.frame.to_local(wo), it.frame.to_local(wi));
        let fx = it.material.eval(wo_l, wi_l);
        if fx == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let (wy_l, wl_l) = (v.it.frame.to_local(wy), v.it.frame.to_local(v.to_light));
        let fy = v.it.material.eval(wy_l, wl_l);
        if fy == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let (from, to) = (it.spawn(wi), v.it.spawn(wy));
        let gap = to - from;
        let len = gap.length();
        if bvh.occluded(from, gap / len, len * (1.0 - 1e-4)) {
            return Vec3::ZERO;
        }
        // Solid angle at `x` per area at `y`.
        let g = wy.dot(v.it.ng).abs() / dist2;
        let w = match connection {
            Connection::Mis => power_heuristic(v.pdf_area, it.material.pdf(wo_l, wi_l) * g),
            _ => 1.0,
        };
        fx * wi_l.z.abs() * fy * wl_l.z.abs() * v.power * (g * w)
    }

    /// The weight of next-event estimation from `scene.lights[light]` at `it`, reached by a
    /// non-delta BSDF sample from the camera path's previous vertex `from`: the share that
    /// the connection of `from` to a light vertex leaves to the path tracer.
    pub fn nee_weight(
        &self,
        scene: &Scene,
        light: usize,
        it: &Interaction,
        from: &BsdfVertex,
        connection: Connection,
    ) -> f32 {
        if connection == Connection::Off || it.material.is_purely_specular() {
            return 1.0;
        }
        let pdf_light = self.pdf_area(scene, light, it.position, it.ng);
        if pdf_light <= 0.0 {
            return 1.0;
        }
        if connection == Connection::Alone {
            return 0.0;
        }
        let d = it.position - from.position;
        let dist2 = d.length_squared();
        let cos = (d / dist2.sqrt()).dot(it.ng).abs();
        power_heuristic(from.pdf * cos / dist2, pdf_light)
    }
}
