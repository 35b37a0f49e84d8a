//! Area lights: the triangles whose material emits (`Material::emission`). Each emits
//! radiance L from its front face (both faces when two-sided), so a triangle of area A
//! emits πLA (2πLA) watts. They are drawn with probability proportional to that power
//! (an alias table), and a point uniformly on the drawn triangle, for next-event estimation
//! and for photons and light paths.

use super::light::Emission;
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
    /// Per scene triangle its index in `triangles`, `u32::MAX` where it does not emit.
    slot: Vec<u32>,
    alias: Option<AliasTable>,
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
        e.slot = vec![u32::MAX; scene.triangles.len()];
        let mut weights = Vec::new();
        for t in 0..scene.triangles.len() {
            if !scene.material_of(t).emits() {
                continue;
            }
            let [a, b, c] = scene.triangle(t);
            let area = 0.5 * (b - a).cross(c - a).length();
            if !(area > 0.0 && area.is_finite()) {
                continue;
            }
            let power = triangle_power(scene, t, area);
            e.slot[t] = e.triangles.len() as u32;
            e.triangles.push(t as u32);
            e.areas.push(area);
            e.power += power;
            weights.push(power.element_sum());
        }
        e.alias = AliasTable::new(&weights);
        e
    }

    pub fn is_empty(&self) -> bool {
        self.alias.is_none()
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
        let t = self.triangles[i] as usize;
        let [a, b, c] = scene.triangle(t);
        let (b1, b2) = uniform_triangle(u);
        let point = a * (1.0 - b1 - b2) + b * b1 + c * b2;
        let normal = (b - a).cross(c - a).normalize_or_zero();
        let [t0, t1, t2] = scene.uvs[t];
        Some(EmitterSample {
            triangle: t as u32,
            point,
            normal,
            uv: t0 * (1.0 - b1 - b2) + t1 * b1 + t2 * b2,
            pdf_area: p / self.areas[i],
        })
    }

    /// Density over area with which [`Emitters::sample`] draws a point of scene triangle
    /// `triangle` (0 where it does not emit).
    pub fn pdf_area(&self, triangle: u32) -> f32 {
        let (Some(alias), Some(&slot)) = (&self.alias, self.slot.get(triangle as usize)) else {
            return 0.0;
        };
        if slot == u32::MAX {
            return 0.0;
        }
        alias.prob(slot as usize) / self.areas[slot as usize]
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
        let s = self.sample(scene, rng.next_f32(), rng.next_2d())?;
        let m = scene.material_at(s.triangle as usize, s.uv, 0.0);
        let (mut n, mut sides) = (s.normal, 1.0);
        if m.two_sided {
            sides = 2.0;
            if rng.next_f32() < 0.5 {
                n = -n;
            }
        }
        let dir = Frame::new(n).to_world(cosine_hemisphere(rng.next_2d()));
        Some(Emission {
            origin: s.point,
            direction: dir,
            // L cos θ / (p_A · cos θ / (sides·π)).
            power: m.emission * (sides * PI / s.pdf_area),
        })
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
}
