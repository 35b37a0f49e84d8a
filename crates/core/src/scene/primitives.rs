//! Tessellated primitive shapes, in their local frames. Normals point outwards.

use super::desc::ShapeDesc;
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::f32::consts::TAU;

/// An indexed triangle mesh with per-vertex normals (counter-clockwise = front).
#[derive(Clone, Debug, Default)]
pub struct TriMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub indices: Vec<[u32; 3]>,
}

impl TriMesh {
    fn push_vertex(&mut self, p: Vec3, n: Vec3) -> u32 {
        self.positions.push(p);
        self.normals.push(n);
        (self.positions.len() - 1) as u32
    }

    /// A flat quad from four corners in counter-clockwise order seen from the front.
    fn push_quad(&mut self, c: [Vec3; 4]) {
        let n = (c[1] - c[0]).cross(c[2] - c[0]).normalize();
        let i = c.map(|p| self.push_vertex(p, n));
        self.indices.push([i[0], i[1], i[2]]);
        self.indices.push([i[0], i[2], i[3]]);
    }
}

pub fn quad(size: [f32; 2]) -> TriMesh {
    let (x, z) = (size[0] * 0.5, size[1] * 0.5);
    let mut m = TriMesh::default();
    m.push_quad([
        Vec3::new(-x, 0.0, -z),
        Vec3::new(-x, 0.0, z),
        Vec3::new(x, 0.0, z),
        Vec3::new(x, 0.0, -z),
    ]);
    m
}

pub fn cuboid(size: Vec3) -> TriMesh {
    let h = size * 0.5;
    let mut m = TriMesh::default();
    let c = |x: f32, y: f32, z: f32| Vec3::new(x * h.x, y * h.y, z * h.z);
    m.push_quad([
        c(-1., -1., 1.),
        c(1., -1., 1.),
        c(1., 1., 1.),
        c(-1., 1., 1.),
    ]); // +z
    m.push_quad([
        c(1., -1., -1.),
        c(-1., -1., -1.),
        c(-1., 1., -1.),
        c(1., 1., -1.),
    ]); // -z
    m.push_quad([
        c(1., -1., 1.),
        c(1., -1., -1.),
        c(1., 1., -1.),
        c(1., 1., 1.),
    ]); // +x
    m.push_quad([
        c(-1., -1., -1.),
        c(-1., -1., 1.),
        c(-1., 1., 1.),
        c(-1., 1., -1.),
    ]); // -x
    m.push_quad([
        c(-1., 1., 1.),
        c(1., 1., 1.),
        c(1., 1., -1.),
        c(-1., 1., -1.),
    ]); // +y
    m.push_quad([
        c(-1., -1., -1.),
        c(1., -1., -1.),
        c(1., -1., 1.),
        c(-1., -1., 1.),
    ]); // -y
    m
}

/// Geodesic sphere: an icosahedron subdivided `subdivisions` times (20·4^s triangles).
pub fn sphere(radius: f32, subdivisions: u32) -> TriMesh {
    let t = (1.0 + 5f32.sqrt()) * 0.5;
    let mut verts: Vec<Vec3> = [
        [-1., t, 0.],
        [1., t, 0.],
        [-1., -t, 0.],
        [1., -t, 0.],
        [0., -1., t],
        [0., 1., t],
        [0., -1., -t],
        [0., 1., -t],
        [t, 0., -1.],
        [t, 0., 1.],
        [-t, 0., -1.],
        [-t, 0., 1.],
    ]
    .iter()
    .map(|v| Vec3::from_array(*v).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, verts: &mut Vec<Vec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                verts.push(((verts[a as usize] + verts[b as usize]) * 0.5).normalize());
                (verts.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let ab = midpoint(a, b, &mut verts);
            let bc = midpoint(b, c, &mut verts);
            let ca = midpoint(c, a, &mut verts);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    TriMesh {
        positions: verts.iter().map(|v| *v * radius).collect(),
        normals: verts,
        indices: faces,
    }
}

/// Side wall of a cylinder of `radius` from y0 to y1, normals outward (or inward).
fn push_wall(m: &mut TriMesh, radius: f32, y0: f32, y1: f32, segments: u32, inward: bool) {
    let base = m.positions.len() as u32;
    for i in 0..=segments {
        let a = TAU * i as f32 / segments as f32;
        let n = Vec3::new(a.cos(), 0.0, -a.sin());
        let n_out = if inward { -n } else { n };
        m.push_vertex(n * radius + Vec3::Y * y0, n_out);
        m.push_vertex(n * radius + Vec3::Y * y1, n_out);
    }
    for i in 0..segments {
        let (b0, t0, b1, t1) = (
            base + 2 * i,
            base + 2 * i + 1,
            base + 2 * i + 2,
            base + 2 * i + 3,
        );
        if inward {
            m.indices.push([b0, t0, t1]);
            m.indices.push([b0, t1, b1]);
        } else {
            m.indices.push([b0, t1, t0]);
            m.indices.push([b0, b1, t1]);
        }
    }
}

/// Annulus (or disc when `r0` = 0) at height y facing +y or -y.
fn push_annulus(m: &mut TriMesh, r0: f32, r1: f32, y: f32, segments: u32, up: bool) {
    let n = if up { Vec3::Y } else { -Vec3::Y };
    let base = m.positions.len() as u32;
    for i in 0..=segments {
        let a = TAU * i as f32 / segments as f32;
        let d = Vec3::new(a.cos(), 0.0, -a.sin());
        m.push_vertex(d * r0 + Vec3::Y * y, n);
        m.push_vertex(d * r1 + Vec3::Y * y, n);
    }
    for i in 0..segments {
        let (i0, o0, i1, o1) = (
            base + 2 * i,
            base + 2 * i + 1,
            base + 2 * i + 2,
            base + 2 * i + 3,
        );
        // A disc (r0 = 0) needs only the outer triangle of each segment.
        if up {
            m.indices.push([i0, o0, o1]);
            if r0 > 0.0 {
                m.indices.push([i0, o1, i1]);
            }
        } else {
            m.indices.push([i0, o1, o0]);
            if r0 > 0.0 {
                m.indices.push([i0, i1, o1]);
            }
        }
    }
}

pub fn cylinder(radius: f32, height: f32, segments: u32, caps: bool) -> TriMesh {
    let mut m = TriMesh::default();
    push_wall(&mut m, radius, 0.0, height, segments, false);
    if caps {
        push_annulus(&mut m, 0.0, radius, height, segments, true);
        push_annulus(&mut m, 0.0, radius, 0.0, segments, false);
    }
    m
}

pub fn ring(inner: f32, outer: f32, height: f32, segments: u32) -> TriMesh {
    let mut m = TriMesh::default();
    push_wall(&mut m, outer, 0.0, height, segments, false);
    push_wall(&mut m, inner, 0.0, height, segments, true);
    push_annulus(&mut m, inner, outer, height, segments, true);
    push_annulus(&mut m, inner, outer, 0.0, segments, false);
    m
}

/// Texture coordinates per triangle corner of a primitive's mesh, v running down the image:
/// a quad maps the whole texture once (u along x, v along z); each box face likewise; a
/// sphere longitude/latitude (v = 0 at the top); cylinder and ring walls angle × height,
/// their caps planar over the outer diameter.
pub fn uvs(shape: &ShapeDesc, m: &TriMesh) -> Vec<[Vec2; 3]> {
    let angular = |p: Vec3| 0.5 + p.z.atan2(p.x) / TAU;
    m.indices
        .iter()
        .map(|tri| {
            let p = tri.map(|i| m.positions[i as usize]);
            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            let mut seam = false;
            let mut c = match *shape {
                ShapeDesc::Quad { size } => {
                    p.map(|q| Vec2::new(q.x / size[0] + 0.5, q.z / size[1] + 0.5))
                }
                ShapeDesc::Box { size } => {
                    let s = Vec3::from(size);
                    let a = n.abs();
                    p.map(|q| {
                        let q = q / s;
                        if a.x >= a.y && a.x >= a.z {
                            Vec2::new(0.5 - q.z * n.x.signum(), 0.5 - q.y)
                        } else if a.y >= a.z {
                            Vec2::new(q.x + 0.5, 0.5 + q.z * n.y.signum())
                        } else {
                            Vec2::new(0.5 + q.x * n.z.signum(), 0.5 - q.y)
                        }
                    })
                }
                ShapeDesc::Sphere { radius, .. } => {
                    seam = true;
                    p.map(|q| {
                        let y = (q.y / radius).clamp(-1.0, 1.0);
                        Vec2::new(angular(q), y.acos() / std::f32::consts::PI)
                    })
                }
                ShapeDesc::Cylinder { height, .. } | ShapeDesc::Ring { height, .. } => {
                    let r = p
                        .iter()
                        .map(|q| Vec2::new(q.x, q.z).length())
                        .fold(0.0f32, f32::max)
                        .max(1e-12);
                    if n.y.abs() > 0.9 {
                        p.map(|q| Vec2::new(q.x / (2.0 * r) + 0.5, q.z / (2.0 * r) + 0.5))
                    } else {
                        seam = true;
                        p.map(|q| Vec2::new(angular(q), 1.0 - q.y / height))
                    }
                }
                ShapeDesc::Mesh { .. } | ShapeDesc::Instance { .. } => [Vec2::ZERO; 3],
            };
            // Across the seam of angular coordinates, keep the triangle on one side.
            // A pole's longitude is arbitrary: take the mean of the other corners'.
            let pole = |q: Vec3| Vec2::new(q.x, q.z).length() < 1e-6 * q.length();
            let poles = p.map(|q| seam && pole(q));
            let (lo, hi) = c
                .iter()
                .zip(poles)
                .filter(|(_, is_pole)| !is_pole)
                .fold((f32::MAX, f32::MIN), |(lo, hi), (v, _)| {
                    (lo.min(v.x), hi.max(v.x))
                });
            if seam && hi - lo > 0.5 {
                for v in &mut c {
                    if v.x < 0.5 {
                        v.x += 1.0;
                    }
                }
            }
            if poles.iter().any(|p| *p) {
                let others: Vec<f32> = (0..3).filter(|&i| !poles[i]).map(|i| c[i].x).collect();
                let mean = others.iter().sum::<f32>() / others.len().max(1) as f32;
                for i in 0..3 {
                    if poles[i] {
                        c[i].x = mean;
                    }
                }
            }
            c
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Signed volume by the divergence theorem: positive iff faces wind outward.
    fn volume(m: &TriMesh) -> f32 {
        m.indices
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn closed_shapes_wind_outward_with_the_right_volume() {
        assert!((volume(&cuboid(Vec3::new(1.0, 2.0, 3.0))) - 6.0).abs() < 1e-4);
        let s = sphere(1.0, 4);
        assert_eq!(s.indices.len(), 20 * 256);
        let v = volume(&s);
        assert!(
            v > 0.99 * 4.0 / 3.0 * std::f32::consts::PI && v < 4.0 / 3.0 * std::f32::consts::PI
        );
        let c = volume(&cylinder(1.0, 2.0, 256, true));
        assert!((c - 2.0 * std::f32::consts::PI).abs() < 0.01);
        let r = volume(&ring(1.0, 1.5, 1.0, 256));
        assert!((r - std::f32::consts::PI * (2.25 - 1.0)).abs() < 0.01);
    }

    #[test]
    fn vertex_normals_agree_with_winding() {
        for m in [
            cuboid(Vec3::ONE),
            sphere(2.0, 2),
            cylinder(1.0, 1.0, 16, true),
            ring(0.5, 1.0, 1.0, 16),
            quad([1.0, 1.0]),
        ] {
            for t in &m.indices {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                let ng = (b - a).cross(c - a);
                for i in t {
                    assert!(
                        ng.dot(m.normals[*i as usize]) > 0.0,
                        "{:?} {:?}",
                        [a, b, c],
                        m.normals[*i as usize]
                    );
                }
            }
        }
    }
}

#[cfg(test)]
mod uv_tests {
    use super::*;

    /// A quad maps the whole texture once; a box face too; sphere triangles never straddle
    /// the seam (no triangle spans more than half the texture in u).
    #[test]
    fn primitive_uvs() {
        let shape = ShapeDesc::Quad { size: [2.0, 4.0] };
        let m = quad([2.0, 4.0]);
        let uv = uvs(&shape, &m);
        let all: Vec<Vec2> = uv.iter().flatten().copied().collect();
        let lo = all.iter().fold(Vec2::splat(9.0), |a, b| a.min(*b));
        let hi = all.iter().fold(Vec2::splat(-9.0), |a, b| a.max(*b));
        assert_eq!((lo, hi), (Vec2::ZERO, Vec2::ONE));
        let shape = ShapeDesc::Box {
            size: [1.0, 2.0, 3.0],
        };
        for tri in uvs(&shape, &cuboid(Vec3::new(1.0, 2.0, 3.0))) {
            assert!(tri
                .iter()
                .all(|v| v.cmpge(Vec2::ZERO).all() && v.cmple(Vec2::ONE).all()));
        }
        let shape = ShapeDesc::Sphere {
            radius: 1.0,
            subdivisions: 3,
        };
        for tri in uvs(&shape, &sphere(1.0, 3)) {
            let (a, b) = tri
                .iter()
                .fold((9.0f32, -9.0f32), |(a, b), v| (a.min(v.x), b.max(v.x)));
            assert!(b - a <= 0.5, "{tri:?}");
        }
    }
}
