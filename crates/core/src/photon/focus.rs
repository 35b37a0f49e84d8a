//! Photon focusing with projection maps (Jensen 1996; issue 11): per light, the cones under
//! which it sees the bounding spheres of the specular objects (mirrors, glass). A fraction
//! `f` of the light's photons is aimed into those cones, the rest leave as usual, and every
//! photon's power is I(ω)/q(ω) with the mixture density
//! q(ω) = (1 − f)·p_light(ω) + f·Σⱼ 1[ω ∈ cone j] / (m·Ωⱼ) (one-sample mixture, Veach's
//! balance heuristic over the whole mixture), so the estimate stays unbiased while caustic
//! photons, which start by hitting a specular object, become far more frequent.

use crate::sampling::{uniform_cone, uniform_sphere, Frame, Rng};
use crate::scene::{Light, Scene};
use glam::Vec3;
use std::collections::HashMap;
use std::f32::consts::PI;
use std::sync::Arc;

/// A cone of directions from a light: unit axis and cosine of its half-angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    pub axis: Vec3,
    pub cos_max: f32,
}

impl Cone {
    /// The cone under which `from` sees the sphere (`centre`, `radius`); `None` from inside
    /// it, or where the cone holds too large a share of the sphere of directions (a solid
    /// angle of π or more, a quarter): aiming there gains little.
    pub(crate) fn around(from: Vec3, centre: Vec3, radius: f32) -> Option<Cone> {
        let to = centre - from;
        let d = to.length();
        if d <= radius || !d.is_finite() {
            return None;
        }
        let sin = radius / d;
        let cone = Cone {
            axis: to / d,
            cos_max: (1.0 - sin * sin).max(0.0).sqrt(),
        };
        (cone.solid_angle() < PI).then_some(cone)
    }
    pub(crate) fn contains(&self, d: Vec3) -> bool {
        d.dot(self.axis) >= self.cos_max
    }
    pub(crate) fn solid_angle(&self) -> f32 {
        2.0 * PI * (1.0 - self.cos_max)
    }
}

/// The projection map of one light: the cones of the specular objects it sees.
#[derive(Clone, Debug, Default)]
pub struct ProjectionMap {
    pub cones: Vec<Cone>,
}

/// Per light, its projection map, and the fraction of photons aimed by it.
#[derive(Clone, Debug, Default)]
pub struct Focus {
    pub fraction: f32,
    pub maps: Vec<ProjectionMap>,
    /// Specular objects of the scene (each light's map has a cone per object it can aim at).
    pub objects: usize,
    /// The sky's photons aimed at the openings they enter through (`None`: as emitted).
    pub sky: Option<super::sky_guide::SkyGuide>,
}

/// Bounding spheres (centre, radius) of the scene's objects with a delta lobe.
pub(crate) fn specular_spheres(scene: &Scene) -> Vec<(Vec3, f32)> {
    specular_bounds(scene).iter().map(|b| b.sphere).collect()
}

/// The bounds of an object with a delta lobe: its vertices' box and a sphere around them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SpecularBounds {
    pub lo: Vec3,
    pub hi: Vec3,
    /// Centre and radius.
    pub sphere: (Vec3, f32),
}

/// [`SpecularBounds`] of each of the scene's objects with a delta lobe.
pub(crate) fn specular_bounds(scene: &Scene) -> Vec<SpecularBounds> {
    // Per object its materials, not per placed triangle (O(objects) for single-material
    // objects; a face table's distinct offsets found once per shared table).
    let delta = |m: u32| scene.materials[m as usize].is_specular_traced();
    let mut tables: HashMap<*const Vec<u32>, Vec<u32>> = HashMap::new();
    let mut out = Vec::new();
    for o in &scene.objects {
        let specular = match &o.face_materials {
            None => delta(o.material),
            Some(f) => tables
                .entry(Arc::as_ptr(f))
                .or_insert_with(|| {
                    let mut d = f.to_vec();
                    d.sort_unstable();
                    d.dedup();
                    d
                })
                .iter()
                .any(|&off| delta(o.material + off)),
        };
        if !specular {
            continue;
        }
        let ps: Vec<Vec3> = scene.object_vertices(o).collect();
        if ps.is_empty() {
            continue;
        }
        let (lo, hi) = ps
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        let c = 0.5 * (lo + hi);
        let r = ps.iter().map(|p| (*p - c).length()).fold(0.0f32, f32::max);
        out.push(SpecularBounds {
            lo,
            hi,
            sphere: (c, r * 1.001 + 1e-5),
        });
    }
    out
}

impl Focus {
    /// Projection maps of every light of `scene`, aiming `fraction` of each light's photons
    /// (0 or no specular object: no focusing). A light inside a sphere, or a cone that
    /// holds too large a share of the sphere of directions (> 1/4), gets no map: aiming
    /// there gains little.
    pub fn of_scene(scene: &Scene, fraction: f32) -> Focus {
        let spheres = if fraction > 0.0 {
            specular_spheres(scene)
        } else {
            Vec::new()
        };
        let maps = scene
            .lights
            .iter()
            .map(|l| {
                let p = l.position();
                // A distant light has no point to aim from.
                let spheres = if l.is_local() { &spheres[..] } else { &[] };
                let cones: Vec<Cone> = spheres
                    .iter()
                    .filter_map(|&(c, r)| Cone::around(p, c, r))
                    .collect();
                ProjectionMap { cones }
            })
            .collect();
        Focus {
            fraction: fraction.clamp(0.0, 1.0),
            maps,
            objects: spheres.len(),
            sky: None,
        }
    }

    /// Whether light `li`'s map has a cone around every specular object: then every
    /// direction in which the light first meets a mirror or glass lies in its cones.
    pub fn covers_all(&self, li: usize) -> bool {
        self.active(li) && self.maps[li].cones.len() == self.objects
    }

    /// Whether light `li` aims any photons.
    pub fn active(&self, li: usize) -> bool {
        self.fraction > 0.0 && self.maps.get(li).is_some_and(|m| !m.cones.is_empty())
    }

    /// Samples a direction of light `li` from the mixture; returns it with the mixture
    /// density q(ω) (per steradian) and the light's own density p_light(ω).
    pub fn sample(&self, light: &Light, li: usize, rng: &mut Rng) -> (Vec3, f32) {
        let cones = &self.maps[li].cones;
        let d = if rng.next_f32() < self.fraction {
            let j = ((rng.next_f32() * cones.len() as f32) as usize).min(cones.len() - 1);
            let c = cones[j];
            Frame::new(c.axis).to_world(uniform_cone(rng.next_2d(), c.cos_max))
        } else {
            match *light {
                Light::Point { .. } => uniform_sphere(rng.next_2d()),
                Light::Spot {
                    direction,
                    cos_outer,
                    ..
                } => Frame::new(direction).to_world(uniform_cone(rng.next_2d(), cos_outer)),
                Light::Directional { direction, .. } => direction,
            }
        };
        (d, self.pdf(light, li, d))
    }

    /// The mixture density q(ω) of light `li`.
    pub fn pdf(&self, light: &Light, li: usize, d: Vec3) -> f32 {
        let cones = &self.maps[li].cones;
        let base = match *light {
            Light::Point { .. } => 1.0 / (4.0 * PI),
            Light::Directional { .. } => 0.0,
            Light::Spot {
                direction,
                cos_outer,
                ..
            } => {
                if d.dot(direction) >= cos_outer {
                    1.0 / (2.0 * PI * (1.0 - cos_outer))
                } else {
                    0.0
                }
            }
        };
        let aimed: f32 = cones
            .iter()
            .filter(|c| c.contains(d))
            .map(|c| 1.0 / c.solid_angle())
            .sum::<f32>()
            / cones.len().max(1) as f32;
        (1.0 - self.fraction) * base + self.fraction * aimed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The definition `specular_spheres` implements per object: the objects one of whose
    /// placed triangles has a material with a delta lobe.
    fn specular_by_triangle(scene: &Scene) -> Vec<usize> {
        (0..scene.objects.len())
            .filter(|&i| {
                let o = &scene.objects[i];
                (o.triangles.start as usize..o.triangles.end as usize)
                    .any(|t| scene.material_of(t).has_delta_lobe())
            })
            .collect()
    }

    /// The objects whose spheres `specular_spheres` returns (centres are distinct here).
    fn specular_objects(scene: &Scene) -> Vec<usize> {
        let spheres = specular_spheres(scene);
        let found: Vec<usize> = (0..scene.objects.len())
            .filter(|&i| {
                let ps: Vec<Vec3> = scene.object_vertices(&scene.objects[i]).collect();
                let (lo, hi) = ps
                    .iter()
                    .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
                        (lo.min(*p), hi.max(*p))
                    });
                spheres.iter().any(|(c, _)| *c == 0.5 * (lo + hi))
            })
            .collect();
        assert_eq!(found.len(), spheres.len());
        found
    }

    #[test]
    fn specular_objects_are_those_with_a_delta_triangle() {
        for name in [
            "cornell",
            "cornell-glass",
            "caustic-ring",
            "ring-room",
            "mirror-shadow",
        ] {
            let scene = crate::scene::builtin::load(name).unwrap();
            let want = specular_by_triangle(&scene);
            assert_eq!(specular_objects(&scene), want, "{name}");
            assert_eq!(want.is_empty(), name == "cornell", "{name}");
        }
        // Face tables: two walls share one table naming offsets 0 and 1; from one wall's
        // first material offset 1 is a mirror, from the other's both are diffuse.
        let mut scene = crate::scene::builtin::load("cornell-glass").unwrap();
        let glass = scene
            .materials
            .iter()
            .position(|m| m.has_delta_lobe())
            .unwrap();
        let diffuse = scene
            .materials
            .iter()
            .position(|m| !m.has_delta_lobe())
            .unwrap();
        let base = scene.materials.len() as u32;
        for m in [diffuse, glass, diffuse, diffuse] {
            scene.materials.push(scene.materials[m]);
        }
        let (a, b) = (0, 1);
        assert_eq!(scene.objects[a].mesh, scene.objects[b].mesh);
        let n = scene.meshes[scene.objects[a].mesh as usize].indices.len();
        let table = Arc::new((0..n as u32).map(|t| t % 2).collect::<Vec<u32>>());
        for (i, first) in [(a, base), (b, base + 2)] {
            scene.objects[i].material = first;
            scene.objects[i].face_materials = Some(table.clone());
        }
        let want = specular_by_triangle(&scene);
        assert!(want.contains(&a) && !want.contains(&b), "{want:?}");
        assert_eq!(specular_objects(&scene), want);
    }

    #[test]
    fn mixture_weights_integrate_to_the_light_power() {
        // E[I(ω)/q(ω)] = power: the focused photons carry the light's power in expectation.
        let light = Light::Point {
            position: Vec3::ZERO,
            intensity: Vec3::ONE,
        };
        let focus = Focus {
            sky: None,
            fraction: 0.5,
            maps: vec![ProjectionMap {
                cones: vec![
                    Cone {
                        axis: Vec3::X,
                        cos_max: 0.99,
                    },
                    Cone {
                        axis: Vec3::new(0.0, 0.6, 0.8),
                        cos_max: 0.95,
                    },
                ],
            }],
            objects: 2,
        };
        let n = 400_000;
        let mut sum = 0.0f64;
        let mut aimed = 0;
        for i in 0..n {
            let mut rng = Rng::new(3, 0, i);
            let (d, q) = focus.sample(&light, 0, &mut rng);
            sum += 1.0 / q as f64;
            aimed += focus.maps[0].cones.iter().any(|c| c.contains(d)) as u32;
        }
        let mean = sum / n as f64;
        // 4π within 1% (the estimator's relative standard error here is about 0.3%).
        assert!(
            (mean / (4.0 * std::f64::consts::PI) - 1.0).abs() < 0.01,
            "{mean}"
        );
        assert!(aimed as f64 / n as f64 > 0.5);
    }
}
