//! Area lights: the triangles whose material emits (`Material::emission`). Each emits
//! radiance L from its front face (both faces when two-sided), so a triangle of area A
//! emits πLA (2πLA) watts. They are drawn with probability proportional to that power
//! (an alias table), and a point uniformly on the drawn triangle, for next-event estimation
//! and for photons and light paths.

mod groups;
pub mod quads;
pub mod round;
mod tree;

pub use groups::PolygonGroups;
pub use quads::EmitterPolygon;
pub use tree::{PixelTree, TREE_ENTRY_TEXELS};

use super::light::Emission;
use super::light_bvh::{LightBounds, LightBvh};
use super::Scene;
use crate::sampling::{cosine_hemisphere, uniform_triangle, AliasTable, Frame, Rng};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// The emitting triangles of a scene.
#[derive(Clone, Debug, Default)]
pub struct Emitters {
    /// The scene's triangles that emit.
    pub triangles: Vec<u32>,
    /// Per emitting triangle its area (m²).
    areas: Vec<f32>,
    /// Per emitting triangle its corners (world space) and unit normal (the front face's).
    corners: Vec<([Vec3; 3], Vec3)>,
    /// Per emitting triangle whether it emits from both faces.
    two_sided: Vec<bool>,
    /// Per scene triangle its index in `triangles`, `u32::MAX` where it does not emit.
    slot: Vec<u32>,
    alias: Option<AliasTable>,
    /// Per emitting triangle the weight it is drawn with (its power summed over channels).
    weights: Vec<f32>,
    /// Total emitted power (W per channel).
    power: Vec3,
}

/// A point on an emitter.
#[derive(Clone, Copy, Debug)]
pub struct EmitterSample {
    pub triangle: u32,
    pub point: Vec3,
    /// The triangle's geometric normal (its front face's side).
    pub normal: Vec3,
    /// Texture coordinates at the point.
    pub uv: Vec2,
    /// Density over the emitters' area (m⁻²), the triangle's choice included.
    pub pdf_area: f32,
}

/// A point drawn on the emitters for a rasterized direct light: an oriented point light with
/// a cosine lobe, standing for the part of the emitters' area it was drawn from.
#[derive(Clone, Copy, Debug)]
pub struct EmitterPoint {
    /// The scene triangle it lies on.
    pub triangle: u32,
    pub position: Vec3,
    /// The triangle's geometric normal (its front face's side).
    pub normal: Vec3,
    /// Radiant intensity along the normal (W/sr per channel), L(x)/(n·p_A(x)) for `n` points
    /// of area density p_A; towards ω it is this times |cos θ'| on a side that emits.
    pub intensity: Vec3,
    pub two_sided: bool,
    /// The area the point stands for, 1/(n·p_A(x)) (m²).
    pub area: f32,
}

/// An emitting triangle of uniform radiance, for the closed-form (unshadowed) light of
/// its polygon.
#[derive(Clone, Copy, Debug)]
pub struct EmitterTriangle {
    /// Corners in winding order (the front face's normal is (b − a) × (c − a)).
    pub corners: [Vec3; 3],
    pub radiance: Vec3,
    pub two_sided: bool,
    /// The group (an emitting object) it belongs to, in [`PolygonGroups`].
    pub group: u32,
}

/// How far off a surface at `p` a ray starts so as not to hit it again (that of
/// `trace::Interaction::spawn`).
pub fn offset(p: Vec3) -> f32 {
    1e-4 * (1.0 + p.abs().max_element())
}

/// Power a triangle of `area` emits with the (untextured) radiance of its material: the
/// weight it is drawn with.
fn triangle_power(scene: &Scene, t: usize, area: f32) -> Vec3 {
    let m = scene.material_of(t);
    let sides = if m.two_sided { 2.0 } else { 1.0 };
    m.emission * (sides * PI * area)
}

impl Emitters {
    /// The emitting triangles of `scene` (those of zero area left out).
    pub fn of(scene: &Scene) -> Emitters {
        let mut e = Emitters::default();
        if !scene.materials.iter().any(|m| m.emits()) {
            return e;
        }
        e.slot = vec![u32::MAX; scene.triangle_count()];
        let mut weights = Vec::new();
        // Objects of one non-emitting material are skipped whole.
        let dark = |o: &crate::scene::SceneObject| {
            o.face_materials.is_none() && !scene.materials[o.material as usize].emits()
        };
        let mut found = Vec::new();
        scene.for_each_triangle(dark, |t, corners| {
            if scene.material_of(t).emits() {
                found.push((t, corners));
            }
        });
        for (t, [a, b, c]) in found {
            let area = 0.5 * (b - a).cross(c - a).length();
            if !(area > 0.0 && area.is_finite()) {
                continue;
            }
            let power = triangle_power(scene, t, area);
            e.slot[t] = e.triangles.len() as u32;
            e.triangles.push(t as u32);
            e.areas.push(area);
            e.corners
                .push(([a, b, c], (b - a).cross(c - a).normalize_or_zero()));
            e.two_sided.push(scene.material_of(t).two_sided);
            e.power += power;
            weights.push(power.element_sum());
        }
        e.alias = AliasTable::new(&weights);
        e.weights = weights;
        e
    }

    pub fn is_empty(&self) -> bool {
        self.alias.is_none()
    }

    /// The unit normal of emitting scene triangle `triangle` (its front face's) and
    /// whether it emits from both faces; `None` where it does not emit.
    pub fn face(&self, triangle: u32) -> Option<(Vec3, bool)> {
        let i = self.slot_of(triangle)?;
        Some((self.corners[i].1, self.two_sided[i]))
    }

    /// Emitting triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Total emitted power (W per channel; the materials' radiance, textures aside).
    pub fn power(&self) -> Vec3 {
        self.power
    }

    /// A point drawn on the emitters: a triangle with probability ∝ its power (from
    /// `u_select`), a point uniformly on it (from `u`).
    pub fn sample(&self, scene: &Scene, u_select: f32, u: Vec2) -> Option<EmitterSample> {
        let alias = self.alias.as_ref()?;
        let (i, p) = alias.sample(u_select);
        Some(self.point_on(scene, i, p, u))
    }

    /// A point uniformly on emitter `i` (an index into `triangles`), chosen with
    /// probability `p`.
    fn point_on(&self, scene: &Scene, i: usize, p: f32, u: Vec2) -> EmitterSample {
        let t = self.triangles[i] as usize;
        let ([a, b, c], normal) = self.corners[i];
        let (b1, b2) = uniform_triangle(u);
        let point = a * (1.0 - b1 - b2) + b * b1 + c * b2;
        let [t0, t1, t2] = scene.corner_uvs(t);
        EmitterSample {
            triangle: t as u32,
            point,
            normal,
            uv: t0 * (1.0 - b1 - b2) + t1 * b1 + t2 * b2,
            pdf_area: p / self.areas[i],
        }
    }

    /// `n` points on the emitters drawn by power, stratified over the selection (for
    /// passes that light a scene by many point samples of its area lights, e.g. the GPU's:
    /// a point `s` stands for power `radiance · cos / (s.pdf_area · n)` per steradian).
    /// Deterministic in `seed`.
    pub fn sample_points(&self, scene: &Scene, n: usize, seed: u64) -> Vec<EmitterSample> {
        let mut rng = Rng::new(seed, 0x9407_e317, 0);
        (0..n)
            .filter_map(|k| {
                let u_select = ((k as f32 + rng.next_f32()) / n as f32).min(1.0 - f32::EPSILON);
                self.sample(scene, u_select, rng.next_2d())
            })
            .collect()
    }

    /// The index into `triangles` of scene triangle `triangle`, if it emits.
    fn slot_of(&self, triangle: u32) -> Option<usize> {
        match self.slot.get(triangle as usize) {
            Some(&s) if s != u32::MAX => Some(s as usize),
            _ => None,
        }
    }

    /// `n` points drawn on the emitters by [`Emitters::sample`] from `seed`, stratified: the
    /// i-th triangle choice in [i/n, (i+1)/n), its position within the triangle the i-th
    /// point of the R2 sequence (Roberts 2018) moved by a random offset, whose runs of
    /// consecutive points (those that fall on one triangle) are evenly spread too. Each is
    /// an oriented point light: their lighting (Σ over points of I·cos θ'·cos θ/d²) is an
    /// unbiased estimate of the emitters'.
    pub fn points(&self, scene: &Scene, n: u32, seed: u64) -> Vec<EmitterPoint> {
        match &self.alias {
            Some(alias) => self.points_from(scene, (alias, None), n, (seed, 0)),
            None => Vec::new(),
        }
    }

    /// `n` points drawn from `table` over the emitters `slots` (all when `None`), as
    /// [`Emitters::points`] describes, from random stream `stream` of `seed`.
    fn points_from(
        &self,
        scene: &Scene,
        (table, slots): (&AliasTable, Option<&[u32]>),
        n: u32,
        (seed, stream): (u64, u64),
    ) -> Vec<EmitterPoint> {
        if n == 0 {
            return Vec::new();
        }
        let mut rng = Rng::new(seed, 0xE417_7E25, stream);
        let offset = rng.next_2d();
        let r2 = Vec2::new(0.754_877_7, 0.569_840_3);
        (0..n)
            .map(|i| {
                let u_select = ((i as f32 + rng.next_f32()) / n as f32).min(1.0 - f32::EPSILON);
                let u = (offset + r2 * i as f32).fract();
                let (j, p) = table.sample(u_select);
                let slot = slots.map_or(j, |s| s[j] as usize);
                let s = self.point_on(scene, slot, p, u);
                let m = scene.material_at(s.triangle as usize, s.uv, 0.0);
                let area = 1.0 / (n as f32 * s.pdf_area);
                EmitterPoint {
                    triangle: s.triangle,
                    position: s.point,
                    normal: s.normal,
                    intensity: m.emission * area,
                    two_sided: m.two_sided,
                    area,
                }
            })
            .collect()
    }

    /// Density over area with which [`Emitters::sample`] draws a point of scene triangle
    /// `triangle` (0 where it does not emit).
    pub fn pdf_area(&self, triangle: u32) -> f32 {
        let (Some(alias), Some(slot)) = (&self.alias, self.slot_of(triangle)) else {
            return 0.0;
        };
        alias.prob(slot) / self.areas[slot]
    }

    /// Radiance emitted at `s` towards `wo` (its material and emission texture).
    pub fn radiance(&self, scene: &Scene, s: &EmitterSample, wo: Vec3) -> Vec3 {
        let m = scene.material_at(s.triangle as usize, s.uv, 0.0);
        m.emitted(s.normal, wo)
    }

    /// Emits one photon: a point by [`Emitters::sample`], a cosine-distributed direction
    /// from a face that emits; the power is that of the emitters over one photon (divide
    /// by the photon count).
    pub fn emit(&self, scene: &Scene, rng: &mut Rng) -> Option<Emission> {
        self.emit_sample(scene, rng).map(|(e, _)| e)
    }

    /// [`Emitters::emit`] with the point it left from (its `pdf_area`: the photons' density
    /// over the emitters' surface, per photon drawn).
    pub fn emit_sample(&self, scene: &Scene, rng: &mut Rng) -> Option<(Emission, EmitterSample)> {
        self.emit_sample_towards(scene, rng, None)
    }

    /// [`Emitters::emit_sample`] with the cosine-distributed direction drawn from `u_dir`
    /// when given (so that a caller may stratify the directions), from `rng` otherwise.
    pub fn emit_sample_towards(
        &self,
        scene: &Scene,
        rng: &mut Rng,
        u_dir: Option<glam::Vec2>,
    ) -> Option<(Emission, EmitterSample)> {
        let s = self.sample(scene, rng.next_f32(), rng.next_2d())?;
        let m = scene.material_at(s.triangle as usize, s.uv, 0.0);
        let (mut n, mut sides) = (s.normal, 1.0);
        if m.two_sided {
            sides = 2.0;
            if rng.next_f32() < 0.5 {
                n = -n;
            }
        }
        let u = u_dir.unwrap_or_else(|| rng.next_2d());
        let dir = Frame::new(n).to_world(cosine_hemisphere(u));
        let e = Emission {
            // Off the surface on the side it emits from, as a ray leaving a hit
            // (`Interaction::spawn`): a ray from the surface itself may hit it again.
            origin: s.point + n * offset(s.point),
            direction: dir,
            // L cos θ / (p_A · cos θ / (sides·π)).
            power: m.emission * (sides * PI / s.pdf_area),
        };
        Some((e, s))
    }
}

/// How next-event estimation picks an emitting triangle for a shading point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Selection {
    /// Every triangle equally likely (the baseline the tests measure the others against).
    Uniform,
    /// By power, wherever the point is ([`Emitters`]' alias table).
    Power,
    /// By importance at the point, power over squared distance with the orientations of
    /// both surfaces ([`LightBvh`]).
    Bvh,
}

/// Emitting triangles from which the light BVH may pay (docs/bench/light-sampling.md): a
/// lamp of one or two triangles gains nothing from the tree's descent, which costs more
/// than the alias table's constant-time choice.
pub const BVH_MIN_EMITTERS: usize = 8;

/// The emitters' spread (the diagonal of their bounding box over the scene's) from which
/// the light BVH pays (docs/bench/light-sampling.md): emitters in one compact lamp (a
/// tessellated sphere, 9% of the room) are about equally far from every point, and the
/// BVH's choice by orientation halved their error at 2.5 times the cost; spread out, the
/// power choice wastes most samples on lights far from the point (3–7 times less efficient
/// from 8 scattered triangles on).
pub const BVH_MIN_SPREAD: f32 = 0.25;

/// The emitting triangles of a scene with a way to choose one for a shading point.
#[derive(Clone, Debug)]
pub struct EmitterSampler {
    pub emitters: Emitters,
    selection: Selection,
    bvh: Option<LightBvh>,
}

impl EmitterSampler {
    /// The emitters of `scene`, chosen by `selection`.
    pub fn new(scene: &Scene, selection: Selection) -> Self {
        EmitterSampler::of_emitters(scene, Emitters::of(scene), selection)
    }

    fn of_emitters(scene: &Scene, emitters: Emitters, selection: Selection) -> Self {
        let bvh = if selection == Selection::Bvh {
            let bounds: Vec<LightBounds> = emitters
                .triangles
                .iter()
                .zip(&emitters.areas)
                .map(|(&t, &area)| {
                    let t = t as usize;
                    let p = scene.triangle(t);
                    let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
                    let phi = triangle_power(scene, t, area).element_sum();
                    LightBounds::triangle(p, n, phi, scene.material_of(t).two_sided)
                })
                .collect();
            LightBvh::build(&bounds)
        } else {
            None
        };
        EmitterSampler {
            emitters,
            selection,
            bvh,
        }
    }

    /// The emitters of `scene` with the choice that pays for them: the BVH from
    /// [`BVH_MIN_EMITTERS`] triangles spread over at least [`BVH_MIN_SPREAD`] of the scene,
    /// the power table otherwise.
    pub fn auto(scene: &Scene) -> Self {
        let emitters = Emitters::of(scene);
        let (lo, hi) = emitters
            .triangles
            .iter()
            .flat_map(|&t| scene.triangle(t as usize))
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p), hi.max(p))
            });
        let spread = (hi - lo).length() / (2.0 * scene.bounds().radius);
        let selection = if emitters.len() >= BVH_MIN_EMITTERS && spread >= BVH_MIN_SPREAD {
            Selection::Bvh
        } else {
            Selection::Power
        };
        EmitterSampler::of_emitters(scene, emitters, selection)
    }

    pub fn selection(&self) -> Selection {
        self.selection
    }

    pub fn is_empty(&self) -> bool {
        self.emitters.is_empty()
    }

    /// A point on the emitters for shading point `p` of surface normal `n` (zero: a point in
    /// space): a triangle chosen by the selection from `u_select`, a point uniformly on it
    /// from `u`; its `pdf_area` includes the choice. `None` when no emitter can reach `p`.
    pub fn sample(
        &self,
        scene: &Scene,
        p: Vec3,
        n: Vec3,
        u_select: f32,
        u: Vec2,
    ) -> Option<EmitterSample> {
        let e = &self.emitters;
        if e.is_empty() {
            return None;
        }
        let (i, prob) = match (&self.selection, &self.bvh) {
            (Selection::Bvh, Some(bvh)) => bvh.sample(p, n, u_select)?,
            (Selection::Uniform, _) => {
                let k = e.len();
                (((u_select * k as f32) as usize).min(k - 1), 1.0 / k as f32)
            }
            _ => e.alias.as_ref()?.sample(u_select),
        };
        Some(e.point_on(scene, i, prob, u))
    }

    /// The density over area with which [`EmitterSampler::sample`] draws a point of scene
    /// triangle `triangle` for `p`, `n` (0 where it does not emit or cannot be chosen).
    pub fn pdf_area(&self, p: Vec3, n: Vec3, triangle: u32) -> f32 {
        let e = &self.emitters;
        let Some(slot) = e.slot_of(triangle) else {
            return 0.0;
        };
        let prob = match (&self.selection, &self.bvh) {
            (Selection::Bvh, Some(bvh)) => bvh.prob(p, n, slot),
            (Selection::Uniform, _) => 1.0 / e.len() as f32,
            _ => e.alias.as_ref().map_or(0.0, |a| a.prob(slot)),
        };
        prob / e.areas[slot]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// Two emitting quads of different areas and radiance: the photons carry the emitters'
    /// power (π·L·A, two-sided 2π·L·A) in total, points are drawn ∝ power and lie on the
    /// emitters, and `pdf_area` is the density `sample` reports.
    #[test]
    fn emitters_are_drawn_by_power_and_photons_carry_it() {
        let json = r#"{
            "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
            "materials": {
                "a": {"diffuse": [0, 0, 0], "emission": [1, 2, 3]},
                "b": {"diffuse": [0.5, 0.5, 0.5], "emission": [4, 4, 4], "two_sided": true},
                "c": {"diffuse": [0.5, 0.5, 0.5]}
            },
            "objects": [
                {"shape": {"type": "quad", "size": [2, 1]}, "material": "a"},
                {"shape": {"type": "quad", "size": [1, 1]}, "material": "b",
                 "transform": {"translate": [0, 1, 0]}},
                {"shape": {"type": "quad", "size": [3, 3]}, "material": "c",
                 "transform": {"translate": [0, -1, 0]}}
            ]
        }"#;
        let scene = Scene::from_json(json, "emitters", &HashMap::new()).unwrap();
        let e = Emitters::of(&scene);
        assert_eq!(e.len(), 4, "two quads of two triangles emit");
        let expected = Vec3::new(1.0, 2.0, 3.0) * (PI * 2.0) + Vec3::splat(4.0) * (2.0 * PI);
        assert!((e.power() - expected).abs().max_element() < 1e-4);
        let mut rng = Rng::new(2, 0, 0);
        let n = 200_000;
        let mut sum = Vec3::ZERO;
        let mut on_b = 0;
        for _ in 0..n {
            let s = e.sample(&scene, rng.next_f32(), rng.next_2d()).unwrap();
            assert!((s.pdf_area - e.pdf_area(s.triangle)).abs() < 1e-6 * s.pdf_area);
            if s.point.y > 0.5 {
                on_b += 1;
            }
            sum += e.emit(&scene, &mut rng).unwrap().power / n as f32;
        }
        // b's share of the power (by the sum of channels): 24π / (12π + 24π) = 2/3.
        let share = on_b as f64 / n as f64;
        assert!((share - 2.0 / 3.0).abs() < 0.005, "{share}");
        assert!(
            ((sum - expected) / expected).abs().max_element() < 0.01,
            "{sum} vs {expected}"
        );
        assert_eq!(e.pdf_area(4), 0.0, "the grey quad does not emit");
    }

    /// Every selection's points are drawn with the density it reports: `pdf_area` agrees
    /// with the samples' own, and the mean of 1/pdf over the draws is the emitters' area
    /// (Σ_t P(t)·A_t/P(t), a mean test of the densities: 1% at 100k draws, whose standard
    /// error is below 0.3% here). The point sees every emitter's front face, so the BVH can
    /// choose all of them.
    #[test]
    fn selections_draw_points_with_their_density() {
        let mut objects = Vec::new();
        let mut materials = vec![r#""grey": {"diffuse": [0.5, 0.5, 0.5]}"#.to_string()];
        for i in 0..40 {
            let (x, z) = ((i % 8) as f32 - 3.5, (i / 8) as f32 - 2.0);
            let size = 0.1 + 0.05 * (i % 5) as f32;
            materials.push(format!(
                r#""e{i}": {{"diffuse": [0, 0, 0], "emission": [{}, 1, 1]}}"#,
                1 + i % 7
            ));
            objects.push(format!(
                r#"{{"shape": {{"type": "quad", "size": [{size}, {size}]}}, "material": "e{i}",
                    "transform": {{"rotate": [180, 0, 0], "translate": [{x}, {}, {z}]}}}}"#,
                1.0 + 0.1 * (i % 3) as f32
            ));
        }
        let json = format!(
            r#"{{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0]}},
                "materials": {{{}}}, "objects": [{}]}}"#,
            materials.join(","),
            objects.join(",")
        );
        let scene = Scene::from_json(&json, "selections", &HashMap::new()).unwrap();
        let area: f32 = (0..40).map(|i| (0.1 + 0.05 * (i % 5) as f32).powi(2)).sum();
        let (p, n) = (Vec3::new(0.3, -0.5, 0.2), Vec3::Y);
        for selection in [Selection::Uniform, Selection::Power, Selection::Bvh] {
            let sampler = EmitterSampler::new(&scene, selection);
            let mut rng = Rng::new(7, 0, 0);
            let draws = 100_000;
            let mut sum = 0.0f64;
            for _ in 0..draws {
                let s = sampler
                    .sample(&scene, p, n, rng.next_f32(), rng.next_2d())
                    .expect("every emitter faces the point");
                let pdf = sampler.pdf_area(p, n, s.triangle);
                assert!((pdf - s.pdf_area).abs() <= 1e-4 * pdf, "{selection:?}");
                sum += 1.0 / s.pdf_area as f64;
            }
            let mean = sum / draws as f64;
            assert!(
                (mean / area as f64 - 1.0).abs() < 0.01,
                "{selection:?}: {mean} vs {area}"
            );
        }
    }
}
