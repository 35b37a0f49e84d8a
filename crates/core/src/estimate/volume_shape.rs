//! The bounding shape that splats ISPM photon volumes (Mara et al. 2013): an icosahedron or
//! a screen-aligned quad per photon, and the per-photon choice of [`VolumeShape::Auto`].
//!
//! Both shapes feed the same fragment test (the exact ellipsoid against the eye G-buffer),
//! so the choice changes the cost, not the image.

use crate::error::{Error, Result};
use crate::photon::radius::VolumeRadius;
use crate::photon::Photon;
use crate::scene::Camera;
use std::borrow::Cow;
use std::str::FromStr;

/// Photons whose volume projects to a radius below this many pixels of the volume target
/// are drawn as quads by [`VolumeShape::Auto`], the rest as icosahedra. Measured on lavapipe
/// (`volume_shape_bench`, docs/bench/ispm.md "Photon volume shapes"; Cornell box, 640×480):
/// the "photon volumes" stage with quads costs 0.43–0.52× the icosahedra's at median radii
/// of 2–4 px and 0.64–0.75× at 8 px (vertex work: 4 vertices instead of 60), 0.90–0.96× at
/// 16 px, and 1.03–1.05× at 32–64 px, where the rectangle's extra rejected fragments around
/// the ellipse outweigh the saved vertices. The crossover lies between 16 and 32 px.
pub const AUTO_QUAD_MAX_PIXELS: f32 = 16.0;

/// Which bounding shape draws the photon volumes (method `ispm`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VolumeShape {
    /// Per photon by projected size: quads below [`AUTO_QUAD_MAX_PIXELS`], else icosahedra.
    #[default]
    Auto,
    /// An icosahedron around the ellipsoid, back faces only (20 triangles).
    Icosahedron,
    /// The screen-space bounding rectangle of the ellipsoid's bounding box (2 triangles).
    Quad,
}

impl VolumeShape {
    pub const ALL: &'static [VolumeShape] = &[
        VolumeShape::Auto,
        VolumeShape::Icosahedron,
        VolumeShape::Quad,
    ];

    pub fn name(self) -> &'static str {
        match self {
            VolumeShape::Auto => "auto",
            VolumeShape::Icosahedron => "icosahedron",
            VolumeShape::Quad => "quad",
        }
    }
}

impl FromStr for VolumeShape {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        crate::error::parse_named(
            s,
            VolumeShape::ALL,
            VolumeShape::name,
            "volume_shape",
            "volume shape",
        )
    }
}

/// Projected radius, in pixels of a target `1/subsample` the camera's size, of a sphere of
/// radius `r` at `center`; infinite when the sphere reaches the eye plane.
pub fn projected_radius(camera: &Camera, subsample: u32, center: glam::Vec3, r: f32) -> f32 {
    // View depth, not distance: the perspective scale is 1/z across the whole image.
    let z = (center - camera.position).dot(camera.forward);
    if z <= r {
        return f32::INFINITY;
    }
    let pixels_per_unit = camera.height as f32 / (2.0 * camera.tan_half_fov() * subsample as f32);
    r / z * pixels_per_unit
}

/// `photons` reordered for two instanced draws: the first `quads` are drawn as quads, the
/// rest as icosahedra.
pub fn partition<'a>(
    shape: VolumeShape,
    photons: &'a [Photon],
    camera: &Camera,
    subsample: u32,
    radius: VolumeRadius,
) -> (Cow<'a, [Photon]>, usize) {
    match shape {
        VolumeShape::Quad => (Cow::Borrowed(photons), photons.len()),
        VolumeShape::Icosahedron => (Cow::Borrowed(photons), 0),
        VolumeShape::Auto => {
            let (mut quads, ico): (Vec<Photon>, Vec<Photon>) = photons.iter().partition(|p| {
                projected_radius(camera, subsample, p.position(), radius.of(p))
                    < AUTO_QUAD_MAX_PIXELS
            });
            let n = quads.len();
            quads.extend(ico);
            (Cow::Owned(quads), n)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn names_round_trip() {
        for &v in VolumeShape::ALL {
            assert_eq!(v.name().parse::<VolumeShape>().ok(), Some(v));
        }
        assert!(matches!(
            "sphere".parse::<VolumeShape>(),
            Err(Error::Setting { .. })
        ));
        assert_eq!(VolumeShape::default(), VolumeShape::Auto);
    }

    #[test]
    fn projected_radius_scales_with_depth_and_subsample() {
        // 90° vertical field of view, 100 px high: 50 px per unit at depth 1.
        let cam = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 90.0, 100, 100);
        let px = projected_radius(&cam, 1, Vec3::new(0.0, 0.0, -2.0), 0.1);
        assert!((px - 2.5).abs() < 1e-4, "{px}");
        let px2 = projected_radius(&cam, 2, Vec3::new(0.0, 0.0, -2.0), 0.1);
        assert!((px2 - 1.25).abs() < 1e-4, "{px2}");
        assert!(projected_radius(&cam, 1, Vec3::new(0.0, 0.0, -0.05), 0.1).is_infinite());
        assert!(projected_radius(&cam, 1, Vec3::new(0.0, 0.0, 3.0), 0.1).is_infinite());
    }

    #[test]
    fn auto_puts_small_volumes_first() {
        let cam = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 90.0, 100, 100);
        let photon = |z: f32| Photon {
            position: [0.0, 0.0, z],
            path_density: 1.0,
            normal: [0.0, 0.0, 1.0],
            ..Default::default()
        };
        // r = 0.1 at 50 px per unit: 25 px and 16.7 px near, 0.5 px and 0.25 px far.
        let photons = [photon(-0.2), photon(-10.0), photon(-0.3), photon(-20.0)];
        let radius = VolumeRadius {
            r_base: 0.1,
            r_max: 1.0,
        };
        let (order, quads) = partition(VolumeShape::Auto, &photons, &cam, 1, radius);
        assert_eq!(quads, 2);
        assert_eq!(order[0].position[2], -10.0);
        assert_eq!(order[1].position[2], -20.0);
        let (_, all) = partition(VolumeShape::Quad, &photons, &cam, 1, radius);
        assert_eq!(all, 4);
        let (_, none) = partition(VolumeShape::Icosahedron, &photons, &cam, 1, radius);
        assert_eq!(none, 0);
    }
}
