//! The emitters as the GPU direct pass lights them in one frame: the emitting objects whose
//! unshadowed diffuse light it sums in closed form (polygon groups, each with its own
//! visibility ratio: the ratio estimator of Heitz, Hill & McGuire 2018), and points drawn
//! on the emitters stratified over those groups and the other emitters, so that every group
//! has points for its ratio and every emitter its share of the points.

use super::quads::{self, EmitterPolygon};
use super::round::{self, Round};
use super::{EmitterPoint, EmitterTriangle, Emitters};
use crate::sampling::AliasTable;
use crate::scene::Scene;
use glam::Vec3;

/// The emitting objects whose light the GPU direct pass sums in closed form, each a group
/// of triangles (see [`Emitters::polygon_groups`]).
#[derive(Clone, Debug, Default)]
pub struct PolygonGroups {
    /// Their triangles, group by group (none of a round group's: its one polygon is the
    /// sphere, [`super::round`]).
    pub triangles: Vec<EmitterTriangle>,
    /// The same light as polygons, group by group: the triangles with coplanar pairs merged
    /// into quads ([`quads::merge`]). The GPU direct pass sums these.
    pub polygons: Vec<EmitterPolygon>,
    pub groups: u32,
    /// What [`Emitters::stratified_points`] draws from, built once: the groups, then the
    /// other emitters.
    strata: Vec<Stratum>,
}

/// A part of the emitters that gets its own share of the points.
#[derive(Clone, Debug)]
struct Stratum {
    /// Its polygon group (`None`: the emitters of no group).
    group: Option<u32>,
    /// Its emitting triangles (indices into `Emitters::triangles`) and their table by power.
    slots: Vec<u32>,
    table: AliasTable,
    /// Its points.
    count: u32,
}

impl PolygonGroups {
    /// The range of `triangles` that group `g` holds.
    pub fn triangles_of(&self, g: u32) -> std::ops::Range<u32> {
        let first = self.triangles.partition_point(|t| t.group < g);
        let end = self.triangles.partition_point(|t| t.group <= g);
        first as u32..end as u32
    }

    /// The emitters of no group (indices into `Emitters::triangles`), if any.
    pub fn rest(&self) -> Option<&[u32]> {
        self.strata
            .iter()
            .find(|s| s.group.is_none())
            .map(|s| s.slots.as_slice())
    }

    /// The range of `polygons` that group `g` holds.
    pub fn polygons_of(&self, g: u32) -> std::ops::Range<u32> {
        let first = self.polygons.partition_point(|t| t.group < g);
        let end = self.polygons.partition_point(|t| t.group <= g);
        first as u32..end as u32
    }
}

/// `n` points shared among strata of power `powers`: one each (when there are at least as
/// many points), the rest in proportion to power, by largest remainder.
fn allocate(n: u32, powers: &[f64]) -> Vec<u32> {
    let total: f64 = powers.iter().sum();
    let base = if n as usize >= powers.len() { 1 } else { 0 };
    let spare = n - base * powers.len() as u32;
    if total.is_nan() || total <= 0.0 {
        return vec![base; powers.len()];
    }
    let shares: Vec<f64> = powers.iter().map(|p| spare as f64 * p / total).collect();
    let mut counts: Vec<u32> = shares.iter().map(|s| base + s.floor() as u32).collect();
    let mut left = n - counts.iter().sum::<u32>();
    let mut order: Vec<usize> = (0..powers.len()).collect();
    order.sort_by(|&a, &b| {
        (shares[b] - shares[b].floor()).total_cmp(&(shares[a] - shares[a].floor()))
    });
    for i in order.into_iter().cycle() {
        if left == 0 {
            break;
        }
        counts[i] += 1;
        left -= 1;
    }
    counts
}

impl Emitters {
    /// The emitters whose unshadowed diffuse light is summed in closed form (the ratio
    /// estimator's numerator): whole objects, each a group of polygons of uniform radiance
    /// (none with an emission texture), taken by power, most powerful first, while they fit
    /// in `max_polygons` triangles and `max_groups` groups, and the groups and the other
    /// emitters (one stratum) in `points`; with the strata that
    /// [`Emitters::stratified_points`] draws those `points` from, each with at least one.
    /// The other emitters' light is sampled only.
    pub fn polygon_groups(
        &self,
        scene: &Scene,
        (max_polygons, max_groups): (usize, usize),
        points: u32,
    ) -> PolygonGroups {
        // The emitting triangles of each object, its power, and whether it can be a group.
        let mut objects: Vec<(usize, Vec<usize>, f32, bool)> = Vec::new();
        for (slot, &t) in self.triangles.iter().enumerate() {
            let object = scene.objects.partition_point(|o| o.triangles.end <= t);
            let closed = scene.maps_of(t as usize).emission.is_none();
            let power = self.weights[slot];
            match objects.last_mut() {
                Some(o) if o.0 == object => {
                    o.1.push(slot);
                    o.2 += power;
                    o.3 &= closed;
                }
                _ => objects.push((object, vec![slot], power, closed)),
            }
        }
        let emitting = self.weights.iter().filter(|&&w| w > 0.0).count();
        objects.retain(|o| o.3 && o.2 > 0.0);
        objects.sort_by(|a, b| b.2.total_cmp(&a.2));
        // Each chosen object's slots and, for a tessellated sphere, its one round polygon.
        let mut chosen: Vec<(Vec<usize>, Option<Round>)> = Vec::new();
        let (mut polygons, mut in_groups) = (0, 0);
        for (_, slots, _, _) in objects {
            let corners: Vec<[Vec3; 3]> = slots.iter().map(|&i| self.corners[i].0).collect();
            let round = round::round(&corners);
            let cost = if round.is_some() { 1 } else { slots.len() };
            if chosen.len() < max_groups && polygons + cost <= max_polygons {
                polygons += cost;
                in_groups += slots.len();
                chosen.push((slots, round));
            }
        }
        // At most `points` strata: the weakest groups join the other emitters.
        while let Some((last, _)) = chosen.last() {
            let rest = in_groups < emitting;
            if chosen.len() + rest as usize <= points as usize {
                break;
            }
            in_groups -= last.len();
            chosen.pop();
        }
        let mut rounds = Vec::new();
        let mut triangles = Vec::new();
        let mut in_group = vec![false; self.triangles.len()];
        let mut strata: Vec<(Option<u32>, Vec<u32>)> = Vec::new();
        for (g, (slots, round)) in chosen.into_iter().enumerate() {
            if round.is_some() {
                let m = scene.material_of(self.triangles[slots[0]] as usize);
                rounds.push(EmitterPolygon {
                    corners: [Vec3::ZERO; 3],
                    fourth: None,
                    radiance: m.emission,
                    two_sided: m.two_sided,
                    group: g as u32,
                    round,
                });
            }
            for &slot in &slots {
                in_group[slot] = true;
                if round.is_some() {
                    continue;
                }
                let m = scene.material_of(self.triangles[slot] as usize);
                triangles.push(EmitterTriangle {
                    corners: self.corners[slot].0,
                    radiance: m.emission,
                    two_sided: m.two_sided,
                    group: g as u32,
                });
            }
            strata.push((Some(g as u32), slots.iter().map(|&i| i as u32).collect()));
        }
        let rest: Vec<u32> = (0..self.triangles.len())
            .filter(|&i| !in_group[i] && self.weights[i] > 0.0)
            .map(|i| i as u32)
            .collect();
        if !rest.is_empty() {
            strata.push((None, rest));
        }
        let powers: Vec<f64> = strata
            .iter()
            .map(|(_, slots)| slots.iter().map(|&i| self.weights[i as usize] as f64).sum())
            .collect();
        let counts = allocate(points, &powers);
        let strata = strata
            .into_iter()
            .zip(counts)
            .filter_map(|((group, slots), count)| {
                let weights: Vec<f32> = slots.iter().map(|&i| self.weights[i as usize]).collect();
                let table = AliasTable::new(&weights)?;
                Some(Stratum {
                    group,
                    slots,
                    table,
                    count,
                })
            })
            .collect();
        let mut polygons = quads::merge(&triangles);
        polygons.append(&mut rounds);
        polygons.sort_by_key(|p| p.group);
        PolygonGroups {
            groups: polygons.last().map_or(0, |t| t.group + 1),
            polygons,
            triangles,
            strata,
        }
    }

    /// Points as [`Emitters::points`] draws them, but stratified over the polygon groups of
    /// `groups` and the other emitters (the last stratum), as many as `groups` was made for
    /// ([`Emitters::polygon_groups`]): each stratum gets at least one and the rest by power,
    /// drawn by power within it. Group by group, then the others, each with its group. Their
    /// lighting is an unbiased estimate of the emitters' too, and every group has points for
    /// its ratio estimator.
    pub fn stratified_points(
        &self,
        scene: &Scene,
        groups: &PolygonGroups,
        seed: u64,
    ) -> Vec<(Option<u32>, EmitterPoint)> {
        let mut out = Vec::new();
        for (k, st) in groups.strata.iter().enumerate() {
            let points = self.points_from(
                scene,
                (&st.table, Some(&st.slots)),
                st.count,
                (seed, k as u64),
            );
            out.extend(points.into_iter().map(|p| (st.group, p)));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use std::collections::HashMap;

    /// A ceiling panel (2 triangles), an emitting box (12) and an emitting geodesic sphere
    /// (320), in that order of power, over a grey floor that does not emit.
    const ROOM: &str = r#"{
        "camera": {"position": [0, 1, 4], "look_at": [0, 1, 0]},
        "materials": {
            "grey": {"diffuse": [0.5, 0.5, 0.5]},
            "panel": {"diffuse": [0, 0, 0], "emission": [8, 8, 8]},
            "lantern": {"diffuse": [0, 0, 0], "emission": [6, 3, 1]},
            "globe": {"diffuse": [0, 0, 0], "emission": [1, 2, 4]}
        },
        "objects": [
            {"shape": {"type": "quad", "size": [4, 4]}, "material": "grey"},
            {"shape": {"type": "quad", "size": [1, 1]}, "material": "panel",
             "transform": {"rotate": [180, 0, 0], "translate": [0, 2.5, 0]}},
            {"shape": {"type": "box", "size": [0.3, 0.3, 0.3]}, "material": "lantern",
             "transform": {"translate": [1, 1, 0]}},
            {"shape": {"type": "sphere", "radius": 0.2, "subdivisions": 2}, "material": "globe",
             "transform": {"translate": [-1, 0.2, 0]}}
        ]
    }"#;

    fn room() -> (Scene, Emitters) {
        let scene = Scene::from_json(ROOM, "room", &HashMap::new()).unwrap();
        let e = Emitters::of(&scene);
        (scene, e)
    }

    #[test]
    fn allocation_gives_each_stratum_a_point_and_the_rest_by_power() {
        // 1 each, then 13 spare as 6.5 / 3.25 / 3.25: floors 6, 3, 3 and the last to the
        // largest remainder.
        assert_eq!(allocate(16, &[8.0, 4.0, 4.0]), vec![8, 4, 4]);
        assert_eq!(allocate(16, &[1000.0, 1e-3]), vec![15, 1]);
        assert_eq!(allocate(4, &[0.0, 0.0]), vec![1, 1]);
        for n in 0..40 {
            for powers in [
                &[1.0][..],
                &[3.0, 1.0],
                &[1.0, 1.0, 1.0],
                &[5.0, 0.1, 2.0, 9.0],
            ] {
                let counts = allocate(n, powers);
                assert_eq!(counts.iter().sum::<u32>(), n, "{n} {powers:?}");
                if n as usize >= powers.len() {
                    assert!(counts.iter().all(|&c| c >= 1), "{n} {powers:?} {counts:?}");
                }
            }
        }
    }

    #[test]
    fn groups_are_whole_objects_by_power_within_the_budgets() {
        let (scene, e) = room();
        assert_eq!(e.len(), 2 + 12 + 320);
        let radiance = |g: &PolygonGroups, k: u32| {
            let r = g.triangles_of(k);
            g.triangles[r.start as usize].radiance
        };
        // The panel, the box, then the sphere: round (`round::sphere`), one polygon and no
        // triangles of its own.
        let g = e.polygon_groups(&scene, (64, 8), 16);
        assert_eq!(g.groups, 3);
        assert_eq!(g.triangles_of(0), 0..2);
        assert_eq!(g.triangles_of(1), 2..14);
        assert_eq!(g.triangles_of(2), 14..14);
        // As polygons: the panel one quad, the box six, the sphere one.
        assert_eq!(g.polygons_of(0), 0..1);
        assert_eq!(g.polygons_of(1), 1..7);
        assert_eq!(g.polygons_of(2), 7..8);
        assert_eq!(g.polygons[0].radiance, Vec3::splat(8.0));
        assert_eq!(radiance(&g, 0), Vec3::splat(8.0));
        assert_eq!(radiance(&g, 1), Vec3::new(6.0, 3.0, 1.0));
        let sphere = g.polygons[7];
        assert_eq!(sphere.radiance, Vec3::new(1.0, 2.0, 4.0));
        let r = sphere.round.expect("the sphere is round");
        assert!(
            (r.centre - Vec3::new(-1.0, 0.2, 0.0)).length() < 1e-5,
            "{r:?}"
        );
        assert!(r.radius < 0.2 && r.radius > 0.198, "{r:?}");
        // 12 triangles: the box does not fit after the panel, the sphere does.
        let g = e.polygon_groups(&scene, (12, 8), 16);
        assert_eq!(g.groups, 2);
        assert!(g.polygons[1].round.is_some());
        // One group at most.
        assert_eq!(e.polygon_groups(&scene, (64, 1), 16).groups, 1);
        // Two points: one group and the other emitters; one point: no group.
        assert_eq!(e.polygon_groups(&scene, (64, 8), 2).groups, 1);
        assert_eq!(e.polygon_groups(&scene, (64, 8), 1).groups, 0);
        // Three points: every object a group, nothing else emits.
        let all = e.polygon_groups(&scene, (400, 8), 3);
        assert_eq!((all.groups, all.triangles.len()), (3, 14));
        assert_eq!(all.polygons.len(), 8);
    }

    /// Each stratum's points carry its light exactly: within a stratum of one radiance a
    /// point drawn by power stands for intensity L·A_s/n_s, so Σ I over its points is
    /// Σ L·A over its triangles, whatever the seed; the points come group by group, then
    /// the others, and lie on their group's triangles.
    #[test]
    fn stratified_points_carry_each_stratum_s_light() {
        let (scene, e) = room();
        let groups = e.polygon_groups(&scene, (64, 8), 16);
        let light = |from: std::ops::Range<usize>| -> Vec3 {
            e.triangles[from]
                .iter()
                .map(|&t| {
                    let [a, b, c] = scene.triangle(t as usize);
                    scene.material_of(t as usize).emission * (0.5 * (b - a).cross(c - a).length())
                })
                .sum()
        };
        let expected = [light(0..2), light(2..14), light(14..334)];
        for seed in 0..5 {
            let points = e.stratified_points(&scene, &groups, seed);
            assert_eq!(points.len(), 16);
            let order: Vec<u32> = points.iter().map(|p| p.0.unwrap_or(2)).collect();
            assert!(order.windows(2).all(|w| w[0] <= w[1]), "{order:?}");
            for (k, want) in expected.iter().enumerate() {
                let mine: Vec<&EmitterPoint> = points
                    .iter()
                    .filter(|p| p.0.unwrap_or(2) == k as u32)
                    .map(|p| &p.1)
                    .collect();
                assert!(!mine.is_empty(), "stratum {k} has no point");
                let sum: Vec3 = mine.iter().map(|p| p.intensity).sum();
                assert!(
                    (sum - *want).abs().max_element() < 1e-4 * want.max_element(),
                    "{k}: {sum} {want}"
                );
                let range = if k < 2 {
                    groups.triangles_of(k as u32)
                } else {
                    14..334
                };
                let on = |p: &EmitterPoint| {
                    e.triangles[range.start as usize..range.end as usize].contains(&p.triangle)
                };
                assert!(
                    mine.iter().all(|p| on(p)),
                    "stratum {k}: a point off its triangles"
                );
            }
        }
    }
}
