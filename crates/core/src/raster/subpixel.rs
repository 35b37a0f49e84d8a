//! Emitters smaller than a pixel, seen by the camera: their box-filtered light.
//!
//! The G-buffer samples each pixel at its centre (and at the sub-pixel samples of edge
//! pixels, `raster::edges`, whose edges are found from the pixel centres): an emitting object
//! under a pixel wide is found only where it happens to cover a centre, and then counts as
//! covering the whole pixel. Yet such an object may carry much of a frame's light — the
//! smallest sphere of veach-mis, 0.45 px in radius at 160×90 with radiance 3039, is 22% of
//! the reference's mean, and no pixel centre sees it. What a box-filtered pixel gets from
//! it is its radiance times the part of the pixel its projection covers.
//!
//! So an emitting object of uniform, untextured radiance whose bounding sphere projects to
//! a disc of radius at most [`SMALL_RADIUS_PX`] is left out of the eye G-buffers
//! ([`without`]) and splatted instead ([`splats`]): its triangles that face the eye (those
//! facing away where it emits from both faces and shows more of its back) are projected,
//! each clipped to every pixel it overlaps, and radiance × covered area added to the pixel
//! (`raster::splat` adds them on the GPU where the G-buffer's surface at the pixel centre is
//! not nearer than the object's bounding sphere: the depth test). Bias: within a pixel the
//! occlusion is the centre's (an object half hidden behind an edge inside one pixel counts
//! whole or not at all); the surface behind the object shows through the area it covers
//! (at most a few pixels' share of the background, against an emitter's radiance); the
//! object's own reflected light is left out.

use super::instances::Draw;
use crate::scene::{Camera, Scene};
use glam::{Vec2, Vec3};

/// The largest projected radius (pixels) of an emitter's bounding sphere that is splatted:
/// at most ~7 px² of cover, where few pixel centres fall on it.
pub const SMALL_RADIUS_PX: f32 = 1.5;

/// One pixel's light from one small emitter: pixel (x, y), the eye distance in front of
/// which a G-buffer surface hides it, and radiance × covered share of the pixel.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Splat {
    /// Pixel column and row (as f32), the hiding distance, 0.
    pub pixel: [f32; 4],
    /// Radiance × coverage (rgb), 0.
    pub light: [f32; 4],
}

/// A small emitting object: its index in `Scene::objects`, radiance, and whether it emits
/// from both faces.
#[derive(Clone, Copy, Debug)]
struct Small {
    object: usize,
    radiance: Vec3,
    two_sided: bool,
    /// Eye distance of the bounding sphere's nearest point.
    near: f32,
}

/// The objects of `scene` that emit one untextured radiance from every triangle.
fn uniform_emitters(scene: &Scene) -> impl Iterator<Item = (usize, Vec3, bool)> + '_ {
    scene.objects.iter().enumerate().filter_map(|(i, o)| {
        if o.face_materials.is_some() {
            return None;
        }
        let m = o.material as usize;
        let mat = &scene.materials[m];
        let textured = scene
            .material_maps
            .get(m)
            .is_some_and(|t| t.emission.is_some());
        (mat.emits() && !textured).then_some((i, mat.emission, mat.two_sided))
    })
}

/// Image position (pixels, (0, 0) the top-left corner) of world point `p` in front of
/// `cam`, as `Camera::direction` maps pixels to rays.
fn to_pixel(cam: &Camera, p: Vec3) -> Vec2 {
    let d = p - cam.position;
    let z = d.dot(cam.forward);
    let t = cam.tan_half_fov();
    let sx = d.dot(cam.right) / (z * t * cam.aspect());
    let sy = d.dot(cam.up) / (z * t);
    Vec2::new(
        (sx + 1.0) * 0.5 * cam.width as f32,
        (1.0 - sy) * 0.5 * cam.height as f32,
    )
}

/// The scene's small emitting objects seen from its camera (see the module header).
fn small_emitters(scene: &Scene) -> Vec<Small> {
    let cam = &scene.camera;
    let focal = 0.5 * cam.height as f32 / cam.tan_half_fov();
    uniform_emitters(scene)
        .filter_map(|(object, radiance, two_sided)| {
            let o = &scene.objects[object];
            let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
            for p in scene.object_vertices(o) {
                lo = lo.min(p);
                hi = hi.max(p);
            }
            let centre = 0.5 * (lo + hi);
            let radius = scene
                .object_vertices(o)
                .map(|p| p.distance(centre))
                .fold(0.0f32, f32::max);
            let z = (centre - cam.position).dot(cam.forward);
            // Wholly in front of the camera, and small there.
            let small =
                z - radius > 1e-3 * z.abs().max(1e-6) && radius / z * focal <= SMALL_RADIUS_PX;
            let near = centre.distance(cam.position) - radius;
            small.then_some(Small {
                object,
                radiance,
                two_sided,
                near,
            })
        })
        .collect()
}

/// The scene objects (indices) that [`splats`] lights: left out of the eye G-buffers.
pub fn small_objects(scene: &Scene) -> Vec<u32> {
    small_emitters(scene)
        .iter()
        .map(|s| s.object as u32)
        .collect()
}

/// `draws` without the instances of `objects` (sorted).
pub fn without(draws: Vec<Draw>, objects: &[u32]) -> Vec<Draw> {
    if objects.is_empty() {
        return draws;
    }
    let mut out = Vec::with_capacity(draws.len());
    for d in draws {
        let mut start = d.instances.start;
        for i in d.instances.clone() {
            if objects.binary_search(&i).is_ok() {
                if start < i {
                    out.push(Draw {
                        vertices: d.vertices.clone(),
                        instances: start..i,
                    });
                }
                start = i + 1;
            }
        }
        if start < d.instances.end {
            out.push(Draw {
                vertices: d.vertices.clone(),
                instances: start..d.instances.end,
            });
        }
    }
    out
}

/// Keeps the part of convex polygon `poly` where `inside` holds, cutting its edges where
/// `cut` (the crossing's parameter along an edge) says.
fn clip(
    poly: &[Vec2],
    inside: impl Fn(Vec2) -> bool,
    cut: impl Fn(Vec2, Vec2) -> Vec2,
) -> Vec<Vec2> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for (k, &a) in poly.iter().enumerate() {
        let b = poly[(k + 1) % poly.len()];
        match (inside(a), inside(b)) {
            (true, true) => out.push(b),
            (true, false) => out.push(cut(a, b)),
            (false, true) => {
                out.push(cut(a, b));
                out.push(b);
            }
            (false, false) => {}
        }
    }
    out
}

/// The area of the part of triangle `tri` (pixels) inside the axis-aligned square
/// [x, x + 1] × [y, y + 1]: Sutherland–Hodgman clipping against its four sides, in the
/// square's own coordinates (a triangle of 1e-4 px² beside pixel 35 would lose its area to
/// rounding in the image's).
pub fn covered_area(tri: [Vec2; 3], x: f32, y: f32) -> f32 {
    let origin = Vec2::new(x, y);
    let mut poly: Vec<Vec2> = tri.iter().map(|p| *p - origin).collect();
    for axis in 0..2 {
        for (bound, keep_above) in [(0.0, true), (1.0, false)] {
            if poly.is_empty() {
                return 0.0;
            }
            let inside = |p: Vec2| (p[axis] >= bound) == keep_above || p[axis] == bound;
            let cut = |a: Vec2, b: Vec2| {
                let t = (bound - a[axis]) / (b[axis] - a[axis]);
                let mut q = a + (b - a) * t;
                q[axis] = bound;
                q
            };
            poly = clip(&poly, inside, cut);
        }
    }
    let mut twice = 0.0;
    for (k, a) in poly.iter().enumerate() {
        let b = poly[(k + 1) % poly.len()];
        twice += a.perp_dot(b);
    }
    0.5 * twice.abs()
}

/// Adds `radiance` × the cover of projected triangle `tri` to the pixels it overlaps
/// (`cover`: per pixel of the image, those inside it).
fn add_cover(
    cam: &Camera,
    tri: [Vec2; 3],
    cover: &mut std::collections::BTreeMap<(u32, u32), f32>,
) {
    let lo = tri[0].min(tri[1]).min(tri[2]).floor().max(Vec2::ZERO);
    let hi = tri[0].max(tri[1]).max(tri[2]).ceil();
    let hi = hi.min(Vec2::new(cam.width as f32, cam.height as f32));
    let (x0, y0, x1, y1) = (lo.x as u32, lo.y as u32, hi.x as u32, hi.y as u32);
    for y in y0..y1 {
        for x in x0..x1 {
            let a = covered_area(tri, x as f32, y as f32);
            if a > 0.0 {
                *cover.entry((x, y)).or_insert(0.0) += a;
            }
        }
    }
}

/// The pixels' cover (share of each pixel, pixel by pixel) by the projection of object `s`:
/// its triangles that face the eye, or where it emits from both faces those of the side
/// that covers more.
fn object_cover(scene: &Scene, s: &Small) -> std::collections::BTreeMap<(u32, u32), f32> {
    let cam = &scene.camera;
    let o = &scene.objects[s.object];
    let placed: Vec<Vec3> = scene.object_vertices(o).collect();
    let mesh = &scene.meshes[o.mesh as usize];
    let mut sides: [std::collections::BTreeMap<(u32, u32), f32>; 2] = Default::default();
    for c in &mesh.indices {
        let c = if o.flipped { [c[0], c[2], c[1]] } else { *c };
        let w = c.map(|i| placed[i as usize]);
        let facing = (w[1] - w[0]).cross(w[2] - w[0]).dot(cam.position - w[0]);
        if facing == 0.0 || (!s.two_sided && facing < 0.0) {
            continue;
        }
        let side = usize::from(facing < 0.0);
        add_cover(cam, w.map(|p| to_pixel(cam, p)), &mut sides[side]);
    }
    let [front, back] = sides;
    let total = |m: &std::collections::BTreeMap<(u32, u32), f32>| m.values().sum::<f32>();
    if total(&back) > total(&front) {
        back
    } else {
        front
    }
}

/// The splats of the scene's small emitters seen from its camera (see the module header);
/// empty where it has none.
pub fn splats(scene: &Scene) -> Vec<Splat> {
    let mut out = Vec::new();
    for s in small_emitters(scene) {
        for ((x, y), a) in object_cover(scene, &s) {
            let light = s.radiance * a.min(1.0);
            out.push(Splat {
                pixel: [x as f32, y as f32, s.near, 0.0],
                light: [light.x, light.y, light.z, 0.0],
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipped_areas_sum_to_the_triangle() {
        let tri = [
            Vec2::new(0.3, 0.2),
            Vec2::new(2.7, 1.1),
            Vec2::new(1.2, 2.9),
        ];
        let area = 0.5 * (tri[1] - tri[0]).perp_dot(tri[2] - tri[0]).abs();
        let mut sum = 0.0;
        for y in 0..3 {
            for x in 0..3 {
                sum += covered_area(tri, x as f32, y as f32);
            }
        }
        assert!((sum - area).abs() < 1e-5 * area, "{sum} vs {area}");
        // Wholly inside one pixel: its own area; outside: none.
        let small = [
            Vec2::new(1.1, 1.1),
            Vec2::new(1.4, 1.2),
            Vec2::new(1.2, 1.6),
        ];
        let a = 0.5 * (small[1] - small[0]).perp_dot(small[2] - small[0]).abs();
        assert!((covered_area(small, 1.0, 1.0) - a).abs() < 1e-7);
        assert_eq!(covered_area(small, 2.0, 1.0), 0.0);
    }

    #[test]
    fn without_splits_merged_instances() {
        let d = |v: std::ops::Range<u32>, i: std::ops::Range<u32>| Draw {
            vertices: v,
            instances: i,
        };
        let draws = vec![d(0..30, 0..4), d(30..60, 4..5)];
        let kept = without(draws, &[1, 4]);
        let got: Vec<_> = kept
            .iter()
            .map(|d| (d.vertices.clone(), d.instances.clone()))
            .collect();
        assert_eq!(got, vec![(0..30, 0..1), (0..30, 2..4)]);
    }
}

#[cfg(test)]
mod scene_tests {
    use super::*;
    use std::collections::HashMap;

    /// A wall, a sphere light 0.02 in radius (under a pixel) and one of 0.5 (not small).
    pub(super) const SCENE: &str = r#"{
        "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 40, "width": 64, "height": 48},
        "materials": {
            "grey": {"diffuse": [0.5, 0.5, 0.5]},
            "bulb": {"diffuse": [0, 0, 0], "emission": [100, 50, 25]},
            "lamp": {"diffuse": [0, 0, 0], "emission": [1, 1, 1]}
        },
        "objects": [
            {"shape": {"type": "quad", "size": [8, 8]}, "material": "grey",
             "transform": {"rotate": [90, 0, 0], "translate": [0, 0, -1]}},
            {"shape": {"type": "sphere", "radius": 0.02, "subdivisions": 4}, "material": "bulb",
             "transform": {"translate": [0.31, 0.17, 0]}},
            {"shape": {"type": "sphere", "radius": 0.5, "subdivisions": 3}, "material": "lamp",
             "transform": {"translate": [-1, 0, 0]}}
        ]
    }"#;

    #[test]
    fn a_sub_pixel_sphere_splats_its_projected_disc() {
        let scene = Scene::from_json(SCENE, "bulb", &HashMap::new()).unwrap();
        assert_eq!(small_objects(&scene), vec![1]);
        let cam = &scene.camera;
        let s = splats(&scene);
        assert!(!s.is_empty() && s.len() <= 4, "{s:?}");
        let centre = glam::Vec3::new(0.31, 0.17, 0.0);
        let total: f32 = s.iter().map(|s| s.light[0] / 100.0).sum();
        // The cover against the sphere's cover by the camera's rays (a 2000² grid over 4×4
        // pixels around it): the icosphere (4 subdivisions) inside it, within 0.5%.
        let p = to_pixel(cam, centre).floor() - 2.0;
        let n = 2000;
        let mut hits = 0u32;
        for i in 0..n * n {
            let u = Vec2::new((i % n) as f32 + 0.5, (i / n) as f32 + 0.5) * (4.0 / n as f32);
            let d = cam.direction(p.x + u.x, p.y + u.y);
            let oc = cam.position - centre;
            // The ray's distance from the centre (not b² − c: 25 − 25 loses r² = 4e-4).
            let miss = oc - d * oc.dot(d);
            hits += u32::from(miss.length_squared() < 0.02 * 0.02);
        }
        let cast = hits as f32 * 16.0 / (n * n) as f32;
        assert!(
            total <= cast * 1.001 && total > 0.995 * cast,
            "{total} vs {cast}"
        );
        // Channels in the emission's proportions; every splat beside the centre's pixel.
        let p = to_pixel(cam, centre);
        for sp in &s {
            assert!((sp.light[1] * 2.0 - sp.light[0]).abs() <= 1e-4 * sp.light[0]);
            assert!((sp.pixel[0] + 0.5 - p.x).abs() < 1.5 && (sp.pixel[1] + 0.5 - p.y).abs() < 1.5);
            let near = centre.distance(cam.position) - 0.02;
            assert!((sp.pixel[2] - near).abs() < 1e-3 * near);
        }
        // Where the camera sees it: the projection agrees with the camera's rays.
        let ray = cam.direction(p.x, p.y);
        let to = (centre - cam.position).normalize();
        assert!(ray.dot(to) > 1.0 - 1e-6);
    }
}
