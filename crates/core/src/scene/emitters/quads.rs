//! The closed-form emitter polygons: the polygon groups' triangles with coplanar pairs that
//! share an edge merged into convex quads. Lambert's vector irradiance of a polygon is a sum
//! over its edges, and the shared edge's two terms cancel, so a quad is two triangles' light
//! in four edge terms instead of six: a box or a rectangle costs the GPU direct pass a
//! third less per pixel, with the same light (up to rounding).

use super::EmitterTriangle;
use glam::Vec3;
use std::collections::HashMap;

/// An emitting polygon of uniform radiance: a triangle or a convex planar quad.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterPolygon {
    /// Corners in winding order (the front face's normal is (b − a) × (c − a)); the fourth
    /// is `None` for a triangle.
    pub corners: [Vec3; 3],
    pub fourth: Option<Vec3>,
    pub radiance: Vec3,
    pub two_sided: bool,
    /// Its polygon group.
    pub group: u32,
    /// A sphere in place of the corners (its group's one polygon: [`super::round`]).
    pub round: Option<super::round::Round>,
}

impl EmitterPolygon {
    fn triangle(t: &EmitterTriangle) -> Self {
        EmitterPolygon {
            corners: t.corners,
            fourth: None,
            radiance: t.radiance,
            two_sided: t.two_sided,
            group: t.group,
            round: None,
        }
    }

    /// The bound on |(a − p)·((b − a) × (c − a))| under which a receiver `p` counts as in
    /// the polygon's plane and gets none of its light (every direction to it grazing): the
    /// plane taken as 1e-4 of the polygon's size thick, the size √|(b − a) × (c − a)|. Such
    /// receivers are the emitter's own face (either side: the G-buffer draws back faces too)
    /// and surfaces flush with it; rounding puts them off the plane, where the polygon would
    /// seem to fill their hemisphere (E = π). A polygon constant, so the direct pass reads it
    /// (`polygons_diffuse` of `direct_shade.wgsl`).
    pub fn in_plane_bound(&self) -> f32 {
        let [a, b, c] = self.corners;
        let area2 = (b - a).cross(c - a).length();
        1e-4 * area2 * area2.sqrt()
    }

    /// Its corners in winding order.
    #[cfg(test)]
    fn points(&self) -> Vec<Vec3> {
        let mut p = self.corners.to_vec();
        p.extend(self.fourth);
        p
    }
}

/// Environment variable that turns the merging off (`0`: every triangle its own polygon),
/// for comparing the images and costs with and without it.
pub const QUADS_ENV: &str = "GI_EMITTER_QUADS";

/// Whether [`merge`] merges ([`QUADS_ENV`]; on unless it is `0`).
pub fn enabled() -> bool {
    std::env::var(QUADS_ENV).map_or(true, |v| v != "0")
}

/// Largest 1 − cos of the angle between two triangles' normals for them to count as
/// coplanar (about 0.03°): far below what the light of the pair could show, and above the
/// rounding of a transformed mesh's coplanar faces.
const COPLANAR: f32 = 1e-7;

/// The triangles of `triangles` (sorted by group) with every pair merged into a quad that
/// shares an edge (the same two corners, in opposite order), lies in one plane, has one
/// radiance and sidedness and one group, and makes a convex quad; greedily, in order. The
/// order of the groups is kept. Unmerged when [`QUADS_ENV`] is `0`.
pub fn merge(triangles: &[EmitterTriangle]) -> Vec<EmitterPolygon> {
    if !enabled() {
        return triangles.iter().map(EmitterPolygon::triangle).collect();
    }
    let key = |a: Vec3, b: Vec3| {
        (
            a.to_array().map(f32::to_bits),
            b.to_array().map(f32::to_bits),
        )
    };
    // Directed edge -> the triangle that has it, and the index of its first corner.
    let mut edges = HashMap::new();
    for (i, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            edges.insert(key(t.corners[k], t.corners[(k + 1) % 3]), (i, k));
        }
    }
    let mut used = vec![false; triangles.len()];
    let mut out = Vec::with_capacity(triangles.len());
    for (i, t) in triangles.iter().enumerate() {
        if used[i] {
            continue;
        }
        used[i] = true;
        let quad = (0..3).find_map(|k| {
            let (p, q) = (t.corners[k], t.corners[(k + 1) % 3]);
            let &(j, kj) = edges.get(&key(q, p))?;
            if used[j] || j == i {
                return None;
            }
            let quad = quad_of(t, k, &triangles[j], kj)?;
            Some((j, quad))
        });
        match quad {
            Some((j, quad)) => {
                used[j] = true;
                out.push(quad);
            }
            None => out.push(EmitterPolygon::triangle(t)),
        }
    }
    out
}

/// The convex quad of triangle `t`, whose edge from corner `k` is triangle `u`'s edge from
/// corner `ku` reversed, when the two merge (see [`merge`]).
fn quad_of(
    t: &EmitterTriangle,
    k: usize,
    u: &EmitterTriangle,
    ku: usize,
) -> Option<EmitterPolygon> {
    if t.group != u.group || t.radiance != u.radiance || t.two_sided != u.two_sided {
        return None;
    }
    let normal = |c: [Vec3; 3]| (c[1] - c[0]).cross(c[2] - c[0]).normalize_or_zero();
    let (n, m) = (normal(t.corners), normal(u.corners));
    if n == Vec3::ZERO || m == Vec3::ZERO || n.dot(m) < 1.0 - COPLANAR {
        return None;
    }
    // t = (x0, x1, x2) from its shared edge x0 → x1; u's corner off the edge is y. The
    // boundary of the union: x0 → y → x1 → x2.
    let [x0, x1, x2] = [0, 1, 2].map(|i| t.corners[(k + i) % 3]);
    let y = u.corners[(ku + 2) % 3];
    let quad = [x0, y, x1, x2];
    // Convex: every corner turns the same way as the normal (collinear corners allowed: a
    // zero turn adds nothing to the edge sum).
    let scale = (y - x2).length_squared().max((x1 - x0).length_squared());
    let convex = (0..4).all(|i| {
        let (a, b, c) = (quad[i], quad[(i + 1) % 4], quad[(i + 2) % 4]);
        (b - a).cross(c - b).dot(n) >= -1e-6 * scale
    });
    convex.then_some(EmitterPolygon {
        corners: [x0, y, x1],
        fourth: Some(x2),
        radiance: t.radiance,
        two_sided: t.two_sided,
        group: t.group,
        round: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(corners: [Vec3; 3], group: u32) -> EmitterTriangle {
        EmitterTriangle {
            corners,
            radiance: Vec3::ONE,
            two_sided: false,
            group,
        }
    }

    /// The unit square in z = 0 as two triangles along its diagonal (normal +z).
    fn square(group: u32) -> [EmitterTriangle; 2] {
        let [a, b, c, d] = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        [tri([a, b, c], group), tri([a, c, d], group)]
    }

    /// Twice the vector area Σ pᵢ × pᵢ₊₁ of a closed polygon: its normal times twice its
    /// area.
    fn vector_area(points: &[Vec3]) -> Vec3 {
        (0..points.len())
            .map(|i| points[i].cross(points[(i + 1) % points.len()]))
            .sum()
    }

    #[test]
    fn a_square_s_two_triangles_make_one_quad_of_the_same_area_and_facing() {
        let [t, u] = square(0);
        let merged = merge(&[t, u]);
        assert_eq!(merged.len(), 1);
        let q = merged[0];
        assert!(q.fourth.is_some());
        let want = vector_area(&t.corners) + vector_area(&u.corners);
        assert!((vector_area(&q.points()) - want).length() < 1e-6, "{q:?}");
        assert_eq!(want, Vec3::new(0.0, 0.0, 2.0));
        // Its four corners are the square's.
        let mut corners = q.points();
        corners.sort_by(|a, b| (a.x, a.y).partial_cmp(&(b.x, b.y)).unwrap());
        assert_eq!(
            corners,
            vec![Vec3::ZERO, Vec3::Y, Vec3::X, Vec3::new(1.0, 1.0, 0.0)]
        );
    }

    #[test]
    fn a_box_s_twelve_triangles_make_six_quads() {
        let scene = crate::scene::Scene::from_json(
            r#"{"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0]},
                "materials": {"lamp": {"diffuse": [0, 0, 0], "emission": [1, 2, 3]}},
                "objects": [{"shape": {"type": "box", "size": [1, 2, 3]}, "material": "lamp",
                             "transform": {"rotate": [30, 40, 50], "translate": [1, 2, 3]}}]}"#,
            "box",
            &Default::default(),
        )
        .unwrap();
        let e = super::super::Emitters::of(&scene);
        let groups = e.polygon_groups(&scene, (64, 8), 16);
        assert_eq!(groups.triangles.len(), 12);
        assert_eq!(groups.polygons.len(), 6);
        assert!(groups.polygons.iter().all(|p| p.fourth.is_some()));
        let sum = |ps: Vec<Vec<Vec3>>| ps.iter().map(|p| vector_area(p).length()).sum::<f32>();
        let triangles = sum(groups
            .triangles
            .iter()
            .map(|t| t.corners.to_vec())
            .collect());
        let quads = sum(groups.polygons.iter().map(|p| p.points()).collect());
        // Twice the box's surface area, 2·(2 + 3 + 6).
        assert!((triangles - 44.0).abs() < 1e-4 && (quads - 44.0).abs() < 1e-4);
    }

    #[test]
    fn triangles_that_must_not_merge_stay_triangles() {
        let [t, u] = square(0);
        let other_group = square(1)[1];
        let mut brighter = u;
        brighter.radiance = Vec3::splat(2.0);
        let mut two_sided = u;
        two_sided.two_sided = true;
        // Folded along the diagonal: not coplanar.
        let mut folded = u;
        folded.corners[2].z = 0.1;
        // Facing +z across the diagonal, but the union of t and this triangle is not convex
        // (it turns back at t's corner (1, 1)).
        let dart = tri([t.corners[0], t.corners[2], Vec3::new(2.0, 3.0, 0.0)], 0);
        // The same winding on the shared edge: one of them faces the other way.
        let flipped = tri([u.corners[0], u.corners[2], u.corners[1]], 0);
        for u in [other_group, brighter, two_sided, folded, dart, flipped] {
            let merged = merge(&[t, u]);
            assert_eq!(merged.len(), 2, "{u:?}");
            assert!(merged.iter().all(|p| p.fourth.is_none()));
        }
    }

    #[test]
    fn each_triangle_joins_one_quad_at_most() {
        // A strip of three triangles in one plane: the middle one can pair with either
        // neighbour, and does with one.
        let [a, b, c, d, e] = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::Y,
            Vec3::new(2.0, 0.0, 0.0),
        ];
        let tris = [tri([a, b, c], 0), tri([a, c, d], 0), tri([b, e, c], 0)];
        let merged = merge(&tris);
        assert_eq!(merged.len(), 2);
        assert_eq!(merged.iter().filter(|p| p.fourth.is_some()).count(), 1);
        let total: Vec3 = merged.iter().map(|p| vector_area(&p.points())).sum();
        assert!((total - Vec3::new(0.0, 0.0, 3.0)).length() < 1e-6);
    }
}
