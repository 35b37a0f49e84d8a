//! Round emitters: an emitting object whose triangles tessellate a sphere (Mitsuba's
//! `sphere`, gi's geodesic spheres) is lit by the GPU direct pass in closed form as the
//! sphere it stands for, one record instead of thousands of triangles, so that it can be a
//! polygon group (its unshadowed light summed per pixel, its shadows by the ratio
//! estimator) however finely it is tessellated. From a shading point outside it, a sphere
//! of radius r at distance d covers the cone of the disc of radius r·√(1 − r²/d²) centred
//! (1 − r²/d²) of the way to its centre and facing the point; the direct pass integrates
//! that disc as the regular polygon of [`EDGES`] corners of the same area
//! (`shaders/common/round_lights.wgsl`), both its diffuse light (Lambert's vector
//! irradiance) and its glossy light (linearly transformed cosines, `raster::ltc`).

use glam::Vec3;
use std::f32::consts::PI;

/// Corners of the regular polygon that stands for a round emitter's disc.
pub const EDGES: u32 = 12;

/// The radius of the regular polygon of [`EDGES`] corners with the area of the unit disc:
/// √(2π / (N·sin(2π/N))).
pub fn polygon_scale() -> f32 {
    let n = EDGES as f32;
    (2.0 * PI / (n * (2.0 * PI / n).sin())).sqrt()
}

/// Fewest triangles of a tessellated sphere taken as round (a geodesic sphere of 2
/// subdivisions, 320 triangles, has 1.2% less area than its sphere; of 4, 5120, 0.08%).
pub const MIN_TRIANGLES: usize = 320;

/// Largest relative spread of the corners' distances from the centre.
pub const ROUNDNESS: f32 = 1e-3;

/// A sphere that emits (from outside).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Round {
    pub centre: Vec3,
    /// The radius of the sphere of the tessellation's area, √(A/4π): its power.
    pub radius: f32,
}

/// The sphere `triangles` (world-space corners, front faces outwards) tessellate, if they
/// do: at least [`MIN_TRIANGLES`], every corner within [`ROUNDNESS`] of one distance from
/// their area-weighted centroid, every face turned outwards, the area within 2% of the
/// sphere's.
pub fn sphere(triangles: &[[Vec3; 3]]) -> Option<Round> {
    if triangles.len() < MIN_TRIANGLES {
        return None;
    }
    let mut area = 0.0f64;
    let mut centroid = Vec3::ZERO.as_dvec3();
    for [a, b, c] in triangles {
        let s = 0.5 * (*b - *a).cross(*c - *a).length() as f64;
        area += s;
        centroid += ((*a + *b + *c) / 3.0).as_dvec3() * s;
    }
    if area <= 0.0 {
        return None;
    }
    let centre = (centroid / area).as_vec3();
    let mean = triangles
        .iter()
        .flatten()
        .map(|p| (*p - centre).length() as f64)
        .sum::<f64>()
        / (3 * triangles.len()) as f64;
    let mean = mean as f32;
    let round = triangles
        .iter()
        .flatten()
        .all(|p| ((*p - centre).length() - mean).abs() <= ROUNDNESS * mean);
    let outwards = triangles.iter().all(|[a, b, c]| {
        let mid = (*a + *b + *c) / 3.0 - centre;
        (*b - *a).cross(*c - *a).dot(mid) > 0.0
    });
    let radius = (area / (4.0 * std::f64::consts::PI)).sqrt() as f32;
    let whole = (radius / mean - 1.0).abs() < 0.01;
    (round && outwards && whole).then_some(Round { centre, radius })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::primitives;

    fn triangles(m: &primitives::TriMesh, offset: Vec3, scale: f32) -> Vec<[Vec3; 3]> {
        m.indices
            .iter()
            .map(|t| t.map(|i| m.positions[i as usize] * scale + offset))
            .collect()
    }

    #[test]
    fn geodesic_spheres_are_round_and_other_shapes_not() {
        let at = Vec3::new(1.0, -2.0, 0.5);
        let s = sphere(&triangles(&primitives::sphere(1.0, 4), at, 0.3)).expect("round");
        assert!((s.centre - at).length() < 1e-5, "{s:?}");
        // Its area's radius: a little inside the corners' sphere.
        assert!(s.radius < 0.3 && s.radius > 0.299, "{s:?}");
        // Too coarse (80 triangles), a box, a sphere turned inside out.
        assert!(sphere(&triangles(&primitives::sphere(1.0, 1), at, 1.0)).is_none());
        let b = primitives::cuboid(Vec3::ONE);
        assert!(sphere(&triangles(&b, at, 1.0)).is_none());
        let inside: Vec<_> = triangles(&primitives::sphere(1.0, 4), at, 1.0)
            .into_iter()
            .map(|[a, b, c]| [a, c, b])
            .collect();
        assert!(sphere(&inside).is_none());
    }

    #[test]
    fn the_polygon_has_the_disc_s_area() {
        let n = EDGES as f32;
        let r = polygon_scale();
        let area = 0.5 * n * r * r * (2.0 * PI / n).sin();
        assert!((area - PI).abs() < 1e-5, "{area}");
    }
}
