//! Round emitters: an emitting object whose triangles tessellate a sphere (Mitsuba's
//! `sphere`, gi's geodesic spheres) or a flat disc (Mitsuba's `disk`, a fan of 128
//! triangles) is lit by the GPU direct pass in closed form as the sphere or disc it stands
//! for, one record instead of hundreds or thousands of triangles, so that it can be a
//! polygon group (its unshadowed light summed per pixel, its shadows by the ratio
//! estimator) however finely it is tessellated. From a shading point outside it, a sphere
//! of radius r at distance d covers the cone of the disc of radius r·√(1 − r²/d²) centred
//! (1 − r²/d²) of the way to its centre and facing the point; a flat disc is itself. The
//! direct pass integrates the disc as the regular polygon of [`EDGES`] corners of the same
//! area (`shaders/common/round_lights.wgsl`), both its diffuse light (Lambert's vector
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

/// A sphere that emits (from outside), or a flat disc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Round {
    pub centre: Vec3,
    /// The radius of the sphere (the disc) of the tessellation's area, √(A/4π) (√(A/π)):
    /// its power.
    pub radius: f32,
    /// A flat disc's unit normal (its triangles' front side); `None` for a sphere.
    pub normal: Option<Vec3>,
}

/// Fewest triangles of a tessellated disc taken as round (a regular 32-gon has 0.64% less
/// area than its disc; Mitsuba's `disk` as gi imports it, 128, 0.04%).
pub const MIN_DISC_TRIANGLES: usize = 32;

/// The flat disc `triangles` (world-space corners, all facing one way) tessellate, if they
/// do: at least [`MIN_DISC_TRIANGLES`], every face's normal within [`ROUNDNESS`] (1 − cos)
/// of their mean, every corner in that plane (within [`ROUNDNESS`] of the largest distance
/// R from the area-weighted centroid) and within R of it, the area within 1% of πR² (so
/// the corners fill the disc: any tessellation of it, fan or rings).
pub fn disc(triangles: &[[Vec3; 3]]) -> Option<Round> {
    if triangles.len() < MIN_DISC_TRIANGLES {
        return None;
    }
    let (area, centre) = area_centroid(triangles)?;
    let normal = triangles
        .iter()
        .map(|[a, b, c]| (*b - *a).cross(*c - *a))
        .sum::<Vec3>()
        .try_normalize()?;
    let flat = triangles.iter().all(|[a, b, c]| {
        let n = (*b - *a).cross(*c - *a).normalize_or_zero();
        n.dot(normal) >= 1.0 - ROUNDNESS
    });
    let far = triangles
        .iter()
        .flatten()
        .map(|p| (*p - centre).length())
        .fold(0.0f32, f32::max);
    let planar = triangles
        .iter()
        .flatten()
        .all(|p| (*p - centre).dot(normal).abs() <= ROUNDNESS * far);
    let radius = (area / std::f64::consts::PI).sqrt() as f32;
    let whole = far > 0.0 && (radius / far - 1.0).abs() < 0.005;
    (flat && planar && whole).then_some(Round {
        centre,
        radius,
        normal: Some(normal),
    })
}

/// The sphere or flat disc `triangles` tessellate, if they do ([`sphere`], [`disc`]).
pub fn round(triangles: &[[Vec3; 3]]) -> Option<Round> {
    sphere(triangles).or_else(|| disc(triangles))
}

/// The area of `triangles` and their area-weighted centroid (`None`: no area).
fn area_centroid(triangles: &[[Vec3; 3]]) -> Option<(f64, Vec3)> {
    let mut area = 0.0f64;
    let mut centroid = Vec3::ZERO.as_dvec3();
    for [a, b, c] in triangles {
        let s = 0.5 * (*b - *a).cross(*c - *a).length() as f64;
        area += s;
        centroid += ((*a + *b + *c) / 3.0).as_dvec3() * s;
    }
    (area > 0.0).then(|| (area, (centroid / area).as_vec3()))
}

/// The sphere `triangles` (world-space corners, front faces outwards) tessellate, if they
/// do: at least [`MIN_TRIANGLES`], every corner within [`ROUNDNESS`] of one distance from
/// their area-weighted centroid, every face turned outwards, the area within 2% of the
/// sphere's.
pub fn sphere(triangles: &[[Vec3; 3]]) -> Option<Round> {
    if triangles.len() < MIN_TRIANGLES {
        return None;
    }
    let (area, centre) = area_centroid(triangles)?;
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
    (round && outwards && whole).then_some(Round {
        centre,
        radius,
        normal: None,
    })
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

    /// A fan of `n` triangles round a disc of radius `r` at `at`, facing `normal`
    /// (Mitsuba's `disk` as the importer builds it), turned by `turn`.
    fn fan(n: usize, r: f32, at: Vec3, turn: glam::Quat) -> Vec<[Vec3; 3]> {
        let rim = |k: usize| {
            let t = std::f32::consts::TAU * (k % n) as f32 / n as f32;
            turn * Vec3::new(r * t.cos(), r * t.sin(), 0.0) + at
        };
        (0..n).map(|k| [at, rim(k), rim(k + 1)]).collect()
    }

    #[test]
    fn fans_and_rings_of_a_disc_are_round_and_other_flat_shapes_not() {
        let at = Vec3::new(0.5, 2.0, -1.0);
        let turn = glam::Quat::from_euler(glam::EulerRot::XYZ, 2.5, 0.4, 0.1);
        let d = round(&fan(128, 0.7, at, turn)).expect("Mitsuba's disk is round");
        assert!((d.centre - at).length() < 1e-5, "{d:?}");
        // The radius of its area: 0.02% inside the rim.
        assert!(d.radius < 0.7 && d.radius > 0.6998, "{d:?}");
        let n = d.normal.expect("a disc");
        assert!((n - turn * Vec3::Z).length() < 1e-5, "{n}");
        // Facing the other way: the normal follows the winding.
        let back: Vec<_> = fan(128, 0.7, at, turn)
            .into_iter()
            .map(|[a, b, c]| [a, c, b])
            .collect();
        let nb = disc(&back).expect("round").normal.unwrap();
        assert!((nb + n).length() < 1e-5, "{nb}");
        // Rings (no fan): the 64-fan inside, a band of quads out to the rim.
        let inner = fan(64, 0.35, at, turn);
        let rim = |r: f32, k: usize| {
            let t = std::f32::consts::TAU * (k % 64) as f32 / 64.0;
            turn * Vec3::new(r * t.cos(), r * t.sin(), 0.0) + at
        };
        let mut rings = inner.clone();
        for k in 0..64 {
            rings.push([rim(0.35, k), rim(0.7, k), rim(0.7, k + 1)]);
            rings.push([rim(0.35, k), rim(0.7, k + 1), rim(0.35, k + 1)]);
        }
        assert!(disc(&rings).is_some());
        // Too coarse (16), an annulus (the band alone), a bent fan, a fine square.
        assert!(disc(&fan(16, 0.7, at, turn)).is_none());
        assert!(disc(&rings[64..]).is_none());
        let mut bent = fan(128, 0.7, at, turn);
        bent[5][1] += turn * Vec3::Z * 0.01;
        assert!(disc(&bent).is_none());
        let square: Vec<[Vec3; 3]> = (0..64)
            .flat_map(|k| {
                let (x, y) = ((k % 8) as f32, (k / 8) as f32);
                let p = |u: f32, v: f32| Vec3::new(u, v, 0.0) + at;
                [
                    [p(x, y), p(x + 1.0, y), p(x + 1.0, y + 1.0)],
                    [p(x, y), p(x + 1.0, y + 1.0), p(x, y + 1.0)],
                ]
            })
            .collect();
        assert!(disc(&square).is_none());
        // A sphere stays a sphere.
        let s = round(&triangles(&primitives::sphere(1.0, 4), at, 0.3)).expect("round");
        assert!(s.normal.is_none());
    }

    #[test]
    fn the_polygon_has_the_disc_s_area() {
        let n = EDGES as f32;
        let r = polygon_scale();
        let area = 0.5 * n * r * r * (2.0 * PI / n).sin();
        assert!((area - PI).abs() < 1e-5, "{area}");
    }
}
