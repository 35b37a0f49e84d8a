//! A third way for the path tracer to find light that reaches a camera path's vertex `x`
//! after one diffuse or glossy bounce from a point or spot light or an emitting triangle:
//! a light vertex `y` (where a ray from the source, drawn by power and by the source's own
//! distribution of directions, first lands; one per camera path) connected to `x` by a
//! shadow ray, at every vertex of the path. This is bidirectional path tracing's strategy
//! with two light vertices (the source's point and `y`) and the camera path's (Veach 1997,
//! §10.2), combined by the power heuristic with the path tracer's own two: a BSDF sample
//! from `x` reaching `y`, then next-event estimation there or (emitters) a BSDF sample from
//! `y` hitting the emitter. All sides weigh with the BSDF samples' densities without
//! Russian roulette's survival probability, so that the weights of a path still add up
//! to 1.
//!
//! It pays where the light's first bounce is concentrated, as on a wall or ceiling next to
//! the light: a BSDF ray from a surface lit only indirectly finds that small bright patch
//! rarely, and the path tracer's image is noisy there, while the light's rays land on it
//! in proportion to its brightness. On the Cornell box with a point light of
//! `docs/bench/path-vs-mitsuba.md` the shadowed floor and the boxes' unlit sides hold most
//! of the path tracer's error.

use super::direct::{power_weight, BsdfVertex, DirectLight, SharedLight};
use super::path::{power_heuristic, Strategy};
use super::{Interaction, SceneBvh};
use crate::sampling::Rng;
use crate::scene::{Scene, Source, Sources};
use glam::Vec3;
use std::f32::consts::PI;

/// Dimensions of a low-discrepancy sample that drawing a light vertex takes: the source (1),
/// a point on an emitter (3: the triangle and a point on it) and the direction from it (3:
/// the side of a two-sided emitter and the direction).
pub const DIMENSIONS: u32 = 7;

/// How the path tracer uses light vertices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Connection {
    /// Light vertices and the path tracer's samples, weighted by multiple importance
    /// sampling.
    #[default]
    Mis,
    /// Light vertices alone for the paths they can sample (for tests: converges to the
    /// same image as the others).
    Alone,
    /// The path tracer's samples alone (no light vertices).
    Off,
}

/// The point and spot lights and the emitting triangles a light vertex can start from,
/// drawn by power. Built once per frame.
#[derive(Clone, Debug)]
pub struct LightVertices {
    sources: Sources,
}

/// Where a light vertex's ray started.
#[derive(Clone, Copy, Debug)]
enum Origin {
    /// `scene.lights[i]`.
    Light(usize),
    /// A point on emitting scene triangle `triangle`.
    Emitter { point: Vec3, triangle: u32 },
}

/// Where a source's ray first landed on a surface that is not a perfect mirror or glass.
#[derive(Clone, Copy, Debug)]
pub struct LightVertex {
    it: Interaction,
    origin: Origin,
    /// Unit direction from the vertex to where its ray started.
    to_light: Vec3,
    /// The source's radiant intensity along the ray over the density of drawing that ray
    /// (source, point and direction; W), divided by the cosine at the vertex to the
    /// geometric normal.
    power: Vec3,
}

impl LightVertices {
    /// The point and spot lights and the emitters of `scene`, or `None` when it has none.
    pub fn of(scene: &Scene) -> Option<Self> {
        let sources = Sources::filtered(scene, |s| match s {
            Source::Light(i) => scene.lights[i].is_local(),
            Source::Emitters => true,
            Source::Environment => false,
        });
        (!sources.is_empty()).then_some(LightVertices { sources })
    }

    /// Draws a source, a point on it and a direction from it ([`DIMENSIONS`] draws from
    /// `rng` at most) and follows the ray to the first surface, which must not be purely
    /// specular.
    pub fn sample(&self, scene: &Scene, bvh: &SceneBvh, rng: &mut Rng) -> Option<LightVertex> {
        let (source, p) = self.sources.choose(rng.next_f32())?;
        let (e, origin) = match source {
            Source::Light(i) => (
                scene.lights[i].emit(rng, self.sources.bounds),
                Origin::Light(i),
            ),
            Source::Emitters => {
                let (e, s) = self.sources.emitters.emit_sample(scene, rng)?;
                let (point, triangle) = (s.point, s.triangle);
                (e, Origin::Emitter { point, triangle })
            }
            Source::Environment => return None,
        };
        let hit = bvh.intersect(e.origin, e.direction, f32::INFINITY)?;
        let it = Interaction::new(scene, &hit, e.direction);
        let cos = e.direction.dot(it.ng).abs();
        if it.material.is_purely_specular() || cos < 1e-6 || p.is_nan() || p <= 0.0 {
            return None;
        }
        Some(LightVertex {
            it,
            origin,
            to_light: -e.direction,
            power: e.power / (p * cos),
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

    /// For the path `x → y → e` (`e` a point of emitting triangle `triangle`), the density
    /// of drawing `e` and then `y` from it, over the density `pdf_x` (solid angle at `x`) of
    /// the BSDF sample from `x` that reaches `y`: on the scale of the densities over solid
    /// angle at `y` of next-event estimation and BSDF sampling finding `e`, against which it
    /// is weighed. 0 where `e` does not emit towards `y`.
    fn emitter_pdf(
        &self,
        (x, pdf_x): (Vec3, f32),
        (y, ng): (Vec3, Vec3),
        (e, triangle): (Vec3, u32),
    ) -> f32 {
        let emitters = &self.sources.emitters;
        let pdf_e = self.sources.prob(Source::Emitters) * emitters.pdf_area(triangle);
        let Some((front, two_sided)) = emitters.face(triangle).filter(|_| pdf_e > 0.0) else {
            return 0.0;
        };
        let (to_e, to_x) = (e - y, x - y);
        if !two_sided && front.dot(-to_e) <= 0.0 {
            return 0.0;
        }
        let sides = if two_sided { 2.0 } else { 1.0 };
        let cos_e = ng.dot(to_e).abs() / to_e.length();
        let (dx2, cos_x) = (to_x.length_squared(), ng.dot(to_x).abs() / to_x.length());
        let r = pdf_e / (PI * sides) * cos_e * dx2 / (pdf_x * cos_x);
        if r.is_nan() {
            0.0
        } else {
            r
        }
    }

    /// The light of `v` reflected at the camera path's vertex `it` towards `wo` (world,
    /// away from the surface), through a shadow ray between them, weighted by `connection`
    /// against the path tracer's strategies (`strategy`): a BSDF sample from `it` that
    /// finds `v`, then next-event estimation or a BSDF sample there that finds its source.
    #[allow(clippy::too_many_arguments)]
    pub fn connect(
        &self,
        scene: &Scene,
        (bvh, lights): (&SceneBvh, &DirectLight),
        it: &Interaction,
        wo: Vec3,
        v: &LightVertex,
        connection: Connection,
        strategy: Strategy,
    ) -> Vec3 {
        let d = v.it.position - it.position;
        let dist2 = d.length_squared();
        if connection == Connection::Off || it.material.is_purely_specular() || dist2 <= 0.0 {
            return Vec3::ZERO;
        }
        let wi = d / dist2.sqrt();
        // Reflection at both ends: the source on the viewer's side of `y`, `y` on the
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
        let w = match (connection, v.origin) {
            (Connection::Mis, Origin::Light(i)) => {
                let pdf = self.pdf_area(scene, i, v.it.position, v.it.ng);
                power_heuristic(pdf, it.material.pdf(wo_l, wi_l) * g)
            }
            (Connection::Mis, Origin::Emitter { point, triangle }) => {
                let pdf_x = it.material.pdf(wo_l, wi_l);
                let y = (v.it.position, v.it.ng);
                let own = self.emitter_pdf((it.position, pdf_x), y, (point, triangle));
                let nee = if strategy == Strategy::Bsdf {
                    0.0
                } else {
                    // Next-event estimation's density over solid angle at `y`.
                    let front = self
                        .sources
                        .emitters
                        .face(triangle)
                        .map_or(Vec3::ZERO, |f| f.0);
                    let to_e = point - v.it.position;
                    let d2 = to_e.length_squared();
                    let cos_e = front.dot(to_e).abs() / d2.sqrt();
                    let pdf_area = lights.emitters.pdf_area(
                        v.it.position,
                        super::direct::sampling_normal(&v.it),
                        triangle,
                    );
                    if cos_e > 0.0 {
                        pdf_area * d2 / cos_e
                    } else {
                        0.0
                    }
                };
                let bsdf = if strategy == Strategy::Light {
                    0.0
                } else {
                    v.it.material.pdf(wy_l, wl_l)
                };
                power_weight(own, [nee, bsdf])
            }
            _ => 1.0,
        };
        fx * wi_l.z.abs() * fy * wl_l.z.abs() * v.power * (g * w)
    }

    /// The weights that light vertices connected to the camera path's vertex `from` leave
    /// to the path tracer's samples at the next vertex (reached by a non-delta BSDF sample
    /// from `from`).
    pub fn sharing<'a>(
        &'a self,
        scene: &'a Scene,
        from: BsdfVertex,
        connection: Connection,
    ) -> Sharing<'a> {
        Sharing {
            lv: self,
            scene,
            from,
            connection,
        }
    }

    /// The light vertices' density for the path tracer's BSDF sample from `y` (which left
    /// the camera path's previous vertex `x` by a non-delta BSDF sample) hitting emitter
    /// point `e` of triangle `triangle`, on the scale of that sample's density over solid
    /// angle; infinite where light vertices alone take those paths.
    pub fn emitter_hit_pdf(
        &self,
        (x, y): (&BsdfVertex, &BsdfVertex),
        (e, triangle): (Vec3, u32),
        connection: Connection,
    ) -> f32 {
        let r = self.emitter_pdf((x.position, x.pdf), (y.position, y.ng), (e, triangle));
        match connection {
            Connection::Off => 0.0,
            Connection::Alone if r > 0.0 => f32::INFINITY,
            _ => r,
        }
    }
}

/// The light vertices' share of the light next-event estimation finds at a vertex reached
/// by a non-delta BSDF sample from the camera path's vertex `from`
/// ([`LightVertices::sharing`]).
pub struct Sharing<'a> {
    lv: &'a LightVertices,
    scene: &'a Scene,
    from: BsdfVertex,
    connection: Connection,
}

impl SharedLight for Sharing<'_> {
    fn light_weight(&self, light: usize, it: &Interaction) -> f32 {
        if self.connection == Connection::Off || it.material.is_purely_specular() {
            return 1.0;
        }
        let pdf_light = self.lv.pdf_area(self.scene, light, it.position, it.ng);
        if pdf_light <= 0.0 {
            return 1.0;
        }
        if self.connection == Connection::Alone {
            return 0.0;
        }
        let d = it.position - self.from.position;
        let dist2 = d.length_squared();
        let cos = (d / dist2.sqrt()).dot(it.ng).abs();
        power_heuristic(self.from.pdf * cos / dist2, pdf_light)
    }

    fn emitter_pdf(&self, it: &Interaction, point: Vec3, triangle: u32) -> f32 {
        if self.connection == Connection::Off || it.material.is_purely_specular() {
            return 0.0;
        }
        let x = (self.from.position, self.from.pdf);
        let r = self
            .lv
            .emitter_pdf(x, (it.position, it.ng), (point, triangle));
        match self.connection {
            Connection::Alone if r > 0.0 => f32::INFINITY,
            _ => r,
        }
    }
}
