//! Shading normals of an object: the shape's own, flat (face normals), smooth (area-weighted
//! over vertices that share a position), or smooth up to a crease angle (Blender's
//! auto-smooth). Chosen per object by the scene format's `smooth` field.

use super::TriMesh;
use glam::Vec3;
use std::collections::HashMap;

/// How an object's shading normals are made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Smoothing {
    /// The shape's own normals; flat on triangles that have none (a mesh file without
    /// normals, or vertices whose normal is zero).
    Auto,
    /// Face normals everywhere: every triangle is shaded flat.
    Flat,
    /// One normal per position, averaged over every triangle that touches it.
    Smooth,
    /// Smooth across edges where the faces meet at less than this angle (radians), sharp
    /// across steeper ones.
    Crease(f32),
}

impl Smoothing {
    /// From the scene format: `false`, `true`, or a crease angle in degrees.
    pub fn from_angle_degrees(deg: f32) -> Smoothing {
        if deg >= 180.0 {
            Smoothing::Smooth
        } else {
            Smoothing::Crease(deg.to_radians())
        }
    }
}

/// The mesh with shading normals made as `mode` asks. Vertices are split where one position
/// needs several normals (flat faces, creases), so the triangle count is unchanged.
pub fn shade(mesh: &TriMesh, mode: Smoothing) -> TriMesh {
    match mode {
        Smoothing::Auto => auto(mesh),
        Smoothing::Flat => flat(mesh, |_| true),
        Smoothing::Smooth => smooth(mesh),
        Smoothing::Crease(angle) => crease(mesh, angle.cos()),
    }
}

/// Area-weighted face normal (length = twice the area).
fn face_normal(m: &TriMesh, t: [u32; 3]) -> Vec3 {
    let [a, b, c] = t.map(|i| m.positions[i as usize]);
    (b - a).cross(c - a)
}

fn auto(m: &TriMesh) -> TriMesh {
    if m.normals.len() != m.positions.len() {
        return flat(m, |_| true);
    }
    let missing = |t: [u32; 3]| {
        t.iter()
            .any(|&i| m.normals[i as usize].length_squared() < 1e-12)
    };
    if !m.indices.iter().any(|&t| missing(t)) {
        return m.clone();
    }
    flat(m, missing)
}

/// Splits the triangles `pick` selects into their own vertices with the face normal; the
/// others keep theirs.
fn flat(m: &TriMesh, pick: impl Fn([u32; 3]) -> bool) -> TriMesh {
    let keep_normals = m.normals.len() == m.positions.len();
    let mut out = TriMesh {
        positions: m.positions.clone(),
        normals: if keep_normals {
            m.normals.clone()
        } else {
            vec![Vec3::ZERO; m.positions.len()]
        },
        indices: Vec::with_capacity(m.indices.len()),
    };
    for &t in &m.indices {
        if !pick(t) {
            out.indices.push(t);
            continue;
        }
        let n = face_normal(m, t).normalize_or_zero();
        let base = out.positions.len() as u32;
        for i in t {
            out.positions.push(m.positions[i as usize]);
            out.normals.push(n);
        }
        out.indices.push([base, base + 1, base + 2]);
    }
    compact(out)
}

/// Drops vertices no triangle uses (left behind by splitting).
fn compact(m: TriMesh) -> TriMesh {
    let mut remap = vec![u32::MAX; m.positions.len()];
    let mut out = TriMesh {
        positions: Vec::with_capacity(m.positions.len()),
        normals: Vec::with_capacity(m.positions.len()),
        indices: Vec::with_capacity(m.indices.len()),
    };
    for t in &m.indices {
        out.indices.push(t.map(|i| {
            let r = &mut remap[i as usize];
            if *r == u32::MAX {
                *r = out.positions.len() as u32;
                out.positions.push(m.positions[i as usize]);
                out.normals.push(m.normals[i as usize]);
            }
            *r
        }));
    }
    out
}

/// Group id per vertex: vertices at bit-identical positions share one (files split vertices
/// at UV seams and normals; smoothing must see through that).
fn weld(m: &TriMesh) -> (Vec<u32>, usize) {
    let mut ids: HashMap<[u32; 3], u32> = HashMap::with_capacity(m.positions.len());
    let group = m
        .positions
        .iter()
        .map(|p| {
            let key = p.to_array().map(|x| (x + 0.0).to_bits()); // +0.0 merges -0.0 and 0.0
            let next = ids.len() as u32;
            *ids.entry(key).or_insert(next)
        })
        .collect();
    (group, ids.len())
}

fn smooth(m: &TriMesh) -> TriMesh {
    let (group, groups) = weld(m);
    let mut acc = vec![Vec3::ZERO; groups];
    for &t in &m.indices {
        let n = face_normal(m, t);
        for i in t {
            acc[group[i as usize] as usize] += n;
        }
    }
    TriMesh {
        positions: m.positions.clone(),
        normals: group
            .iter()
            .map(|&g| acc[g as usize].normalize_or_zero())
            .collect(),
        indices: m.indices.clone(),
    }
}

/// Per corner: the sum of the area-weighted normals of the faces around its position whose
/// unit normal is within the crease angle of this face's. Corners of one vertex with equal
/// normals share an output vertex.
fn crease(m: &TriMesh, cos_max: f32) -> TriMesh {
    let (group, groups) = weld(m);
    let normals: Vec<Vec3> = m.indices.iter().map(|&t| face_normal(m, t)).collect();
    let unit: Vec<Vec3> = normals.iter().map(|n| n.normalize_or_zero()).collect();
    // Faces around each position, in compressed rows.
    let mut start = vec![0u32; groups + 1];
    for t in &m.indices {
        for &i in t {
            start[group[i as usize] as usize + 1] += 1;
        }
    }
    for g in 0..groups {
        start[g + 1] += start[g];
    }
    let mut fill = start.clone();
    let mut faces = vec![0u32; start[groups] as usize];
    for (f, t) in m.indices.iter().enumerate() {
        for &i in t {
            let g = group[i as usize] as usize;
            faces[fill[g] as usize] = f as u32;
            fill[g] += 1;
        }
    }
    let mut out = TriMesh {
        positions: Vec::with_capacity(m.positions.len()),
        normals: Vec::with_capacity(m.positions.len()),
        indices: Vec::with_capacity(m.indices.len()),
    };
    let mut corner_vertex: HashMap<(u32, [u32; 3]), u32> = HashMap::new();
    for (f, t) in m.indices.iter().enumerate() {
        out.indices.push(t.map(|i| {
            let g = group[i as usize] as usize;
            let n = faces[start[g] as usize..start[g + 1] as usize]
                .iter()
                .filter(|&&h| unit[h as usize].dot(unit[f]) >= cos_max)
                .map(|&h| normals[h as usize])
                .sum::<Vec3>()
                .normalize_or_zero();
            let n = if n == Vec3::ZERO { unit[f] } else { n };
            *corner_vertex
                .entry((i, n.to_array().map(f32::to_bits)))
                .or_insert_with(|| {
                    out.positions.push(m.positions[i as usize]);
                    out.normals.push(n);
                    (out.positions.len() - 1) as u32
                })
        }));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::primitives;

    fn distinct_normals(m: &TriMesh) -> usize {
        let mut v: Vec<[u32; 3]> = m
            .normals
            .iter()
            .map(|n| n.to_array().map(|x| ((x * 1e4).round() + 0.0).to_bits())) // -0 is 0
            .collect();
        v.sort_unstable();
        v.dedup();
        v.len()
    }

    /// A cube with its 8 corners shared (as a file without normals stores it).
    fn welded_cube() -> TriMesh {
        let m = primitives::cuboid(Vec3::ONE);
        let (group, n) = weld(&m);
        let mut pos = vec![Vec3::ZERO; n];
        for (i, &g) in group.iter().enumerate() {
            pos[g as usize] = m.positions[i];
        }
        TriMesh {
            positions: pos,
            normals: Vec::new(),
            indices: m
                .indices
                .iter()
                .map(|t| t.map(|i| group[i as usize]))
                .collect(),
        }
    }

    #[test]
    fn cube_without_normals_is_flat_by_default() {
        let cube = welded_cube();
        assert_eq!(cube.positions.len(), 8);
        let m = shade(&cube, Smoothing::Auto);
        assert_eq!(m.indices.len(), 12);
        assert_eq!(distinct_normals(&m), 6);
        for t in &m.indices {
            let ng = face_normal(&m, *t).normalize();
            for i in t {
                assert!(m.normals[*i as usize].dot(ng) > 0.9999);
            }
        }
    }

    #[test]
    fn smooth_cube_has_one_normal_per_corner() {
        let m = shade(&welded_cube(), Smoothing::Smooth);
        assert_eq!(m.positions.len(), 8);
        assert_eq!(distinct_normals(&m), 8);
        // Area weighting over the corner's three faces (one or two triangles each): the
        // normal leans into the diagonal, never along an axis.
        for n in &m.normals {
            assert!(n.abs().min_element() > 0.3, "{n}");
        }
    }

    #[test]
    fn crease_angle_splits_the_cube_but_not_a_sphere() {
        let cube = shade(&welded_cube(), Smoothing::from_angle_degrees(30.0));
        assert_eq!(distinct_normals(&cube), 6);
        assert_eq!(cube.positions.len(), 24);
        let mut sphere = primitives::sphere(1.0, 3);
        sphere.normals.clear();
        let s = shade(&sphere, Smoothing::from_angle_degrees(30.0));
        assert_eq!(s.positions.len(), sphere.positions.len());
        // Smooth normals of a geodesic sphere point away from the centre (within 1°).
        for (p, n) in s.positions.iter().zip(&s.normals) {
            assert!(p.normalize().dot(*n) > 1f32.to_radians().cos());
        }
    }

    #[test]
    fn file_normals_are_kept_and_zero_normals_are_filled_flat() {
        let mut m = primitives::sphere(1.0, 2);
        let kept = shade(&m, Smoothing::Auto);
        assert_eq!(kept.normals, m.normals);
        m.normals[0] = Vec3::ZERO;
        let fixed = shade(&m, Smoothing::Auto);
        assert!(fixed.normals.iter().all(|n| n.length() > 0.99));
        assert_eq!(fixed.indices.len(), m.indices.len());
    }
}
