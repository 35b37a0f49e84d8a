//! The scene on the GPU as instances: each unique mesh's triangles once, in the mesh's own
//! frame (one non-indexed vertex buffer holds them all, mesh after mesh), and one record per
//! object ([`InstanceRaw`]) that places its mesh. The passes that rasterize the scene draw
//! a range of one mesh's vertices for a run of instances ([`Draw`]); [`CullUnits`] picks
//! them per view (per instance, then per cluster of a large mesh). Moving an object
//! rewrites its instance record only. GPU memory is proportional to the unique triangles
//! plus the objects; the flat world-space view of the scene is never built for drawing.

use crate::error::Result;
use crate::gpu::raw::{InstanceRaw, VertexRaw};
use crate::gpu::GpuContext;
use crate::scene::surface::triangle_tangent;
use crate::scene::{Scene, SceneObject};
use bytemuck::Zeroable;
use glam::{Mat4, Vec3, Vec4};
use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;

/// Triangles per culling cluster of a mesh: small enough that a cluster of a large mesh
/// usually lies in one cube face, large enough that a mesh has few clusters.
const CLUSTER_TRIANGLES: u32 = 1024;

/// One instanced draw: vertices `vertices` (three per triangle, of one mesh) for each of
/// the instances `instances` (object indices).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Draw {
    pub vertices: Range<u32>,
    pub instances: Range<u32>,
}

impl Draw {
    /// Triangles this draw rasterizes.
    pub fn triangles(&self) -> u64 {
        (self.vertices.len() / 3) as u64 * self.instances.len() as u64
    }
}

/// Triangles rasterized by `draws`.
pub fn triangles_drawn(draws: &[Draw]) -> u64 {
    draws.iter().map(Draw::triangles).sum()
}

/// Appends a draw of `vertices` for instance `i`, merged into the last draw where it
/// continues it (the same vertices for the next instance, or the next vertices of the same
/// single instance).
fn push(draws: &mut Vec<Draw>, vertices: Range<u32>, i: u32) {
    if let Some(last) = draws.last_mut() {
        if last.vertices == vertices && last.instances.end == i {
            last.instances.end += 1;
            return;
        }
        if last.instances == (i..i + 1) && last.vertices.end == vertices.start {
            last.vertices.end = vertices.end;
            return;
        }
    }
    draws.push(Draw {
        vertices,
        instances: i..i + 1,
    });
}

/// A run of a mesh's triangles and their box in the mesh's frame.
#[derive(Clone, Debug)]
struct Cluster {
    vertices: Range<u32>,
    lo: Vec3,
    hi: Vec3,
}

/// A mesh as the GPU draws it: a scene mesh and, for objects that take their materials
/// from the mesh's file, the file's per-face material offsets (the vertices carry them).
#[derive(Clone, Debug)]
pub struct GpuMesh {
    /// Index into [`Scene::meshes`].
    source: u32,
    faces: Option<Arc<Vec<u32>>>,
    /// Its vertices in the vertex buffer (three per triangle).
    pub vertices: Range<u32>,
    clusters: Vec<Cluster>,
    lo: Vec3,
    hi: Vec3,
}

/// Where a box lies against a view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Clip {
    Outside,
    Partly,
    Inside,
}

/// Where the box `lo..hi` lies against the view of clip matrix `m` (box frame -> clip,
/// depth 0..1): outside only when all eight corners lie outside one clip plane (so every
/// point of the box is clipped away), inside when all eight lie inside every plane (the
/// view volume is convex).
pub fn clip_box(m: &Mat4, lo: Vec3, hi: Vec3) -> Clip {
    let corners: [Vec4; 8] = std::array::from_fn(|i| {
        let c = Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        *m * c.extend(1.0)
    });
    let planes: [fn(&Vec4) -> bool; 6] = [
        |c| c.x < -c.w,
        |c| c.x > c.w,
        |c| c.y < -c.w,
        |c| c.y > c.w,
        |c| c.z < 0.0,
        |c| c.z > c.w,
    ];
    let mut inside = true;
    for out in planes {
        let n = corners.iter().filter(|c| out(c)).count();
        if n == 8 {
            return Clip::Outside;
        }
        inside &= n == 0;
    }
    if inside {
        Clip::Inside
    } else {
        Clip::Partly
    }
}

/// The culling data of a scene's instanced geometry: each GPU mesh's clusters and every
/// object's mesh and transform. The meshes are fixed for a scene; [`CullUnits::moved`]
/// re-reads the transforms (O(objects)).
pub struct CullUnits {
    meshes: Arc<Vec<GpuMesh>>,
    /// Per object: its GPU mesh and object -> world.
    objects: Vec<(u32, Mat4)>,
}

/// The key of an object's GPU mesh: its scene mesh and its file's face materials (by
/// identity: objects that load the same file share them).
fn mesh_key(o: &SceneObject) -> (u32, usize) {
    let faces = o
        .face_materials
        .as_ref()
        .map_or(0, |f| Arc::as_ptr(f) as usize);
    (o.mesh, faces)
}

impl CullUnits {
    pub fn of(scene: &Scene) -> Self {
        let mut index: HashMap<(u32, usize), u32> = HashMap::new();
        let mut meshes: Vec<GpuMesh> = Vec::new();
        let mut next = 0u32;
        let objects = scene
            .objects
            .iter()
            .map(|o| {
                let m = *index.entry(mesh_key(o)).or_insert_with(|| {
                    let mesh = gpu_mesh(scene, o, next);
                    next = mesh.vertices.end;
                    meshes.push(mesh);
                    meshes.len() as u32 - 1
                });
                (m, o.transform)
            })
            .collect();
        CullUnits {
            meshes: Arc::new(meshes),
            objects,
        }
    }

    /// Re-reads the objects' transforms after some moved.
    pub fn moved(&mut self, scene: &Scene) {
        for (o, (_, m)) in scene.objects.iter().zip(&mut self.objects) {
            *m = o.transform;
        }
    }

    /// The GPU meshes (vertex ranges) in vertex-buffer order.
    pub fn meshes(&self) -> &[GpuMesh] {
        &self.meshes
    }

    /// Vertices of all GPU meshes together.
    pub fn vertex_count(&self) -> u32 {
        self.meshes.last().map_or(0, |m| m.vertices.end)
    }

    /// Every object's whole mesh, no culling (runs of objects sharing a mesh in one draw).
    pub fn all(&self) -> Vec<Draw> {
        let mut draws = Vec::new();
        for (i, (m, _)) in self.objects.iter().enumerate() {
            push(
                &mut draws,
                self.meshes[*m as usize].vertices.clone(),
                i as u32,
            );
        }
        draws
    }

    /// Per layer (world -> clip matrices `layers`), the draws that reach into its view: an
    /// object whose placed mesh box lies outside is skipped, one inside drawn whole, one
    /// partly inside drawn cluster by cluster (those whose placed box reaches in). A point
    /// light's six cube faces each see a part of the scene: on `dense-cornell` (three 82k
    /// triangle spheres below the light) a triangle is drawn into about 1.75 faces, not six.
    pub fn draws(&self, layers: &[Mat4]) -> Vec<Vec<Draw>> {
        layers.iter().map(|m| self.draws_in(m)).collect()
    }

    fn draws_in(&self, view: &Mat4) -> Vec<Draw> {
        let mut draws = Vec::new();
        for (i, (mesh, model)) in self.objects.iter().enumerate() {
            let g = &self.meshes[*mesh as usize];
            let m = *view * *model;
            match clip_box(&m, g.lo, g.hi) {
                Clip::Outside => {}
                Clip::Partly if g.clusters.len() > 1 => {
                    for c in &g.clusters {
                        if clip_box(&m, c.lo, c.hi) != Clip::Outside {
                            push(&mut draws, c.vertices.clone(), i as u32);
                        }
                    }
                }
                _ => push(&mut draws, g.vertices.clone(), i as u32),
            }
        }
        draws
    }
}

/// Object `o`'s GPU mesh, its vertices from `first` on: clusters of
/// [`CLUSTER_TRIANGLES`] triangles in the mesh's order and their boxes.
fn gpu_mesh(scene: &Scene, o: &SceneObject, first: u32) -> GpuMesh {
    let mesh = &scene.meshes[o.mesh as usize];
    let n = mesh.indices.len() as u32;
    let clusters: Vec<Cluster> = (0..n.div_ceil(CLUSTER_TRIANGLES))
        .map(|c| {
            let t = c * CLUSTER_TRIANGLES..((c + 1) * CLUSTER_TRIANGLES).min(n);
            let (lo, hi) = mesh.indices[t.start as usize..t.end as usize]
                .iter()
                .flatten()
                .map(|&v| mesh.positions[v as usize])
                .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p), hi.max(p))
                });
            Cluster {
                vertices: first + 3 * t.start..first + 3 * t.end,
                lo,
                hi,
            }
        })
        .collect();
    let (lo, hi) = clusters
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), c| {
            (lo.min(c.lo), hi.max(c.hi))
        });
    GpuMesh {
        source: o.mesh,
        faces: o.face_materials.clone(),
        vertices: first..first + 3 * n,
        clusters,
        lo,
        hi,
    }
}

/// GPU mesh `g`'s vertices in its mesh's frame: per triangle corner its position, shading
/// normal, texture coordinates and tangent (the mesh's per-corner tangents, else the
/// triangle's own frame at each corner), and per triangle its geometric normal (from the
/// winding) and per-face material offset (0 without). Placement (and a mirrored object's
/// flipped handedness) is the instance's, in the vertex stage.
fn mesh_vertices(scene: &Scene, g: &GpuMesh, out: &mut Vec<VertexRaw>) {
    let mesh = &scene.meshes[g.source as usize];
    let uvs = &scene.mesh_uvs[g.source as usize];
    for (t, tri) in mesh.indices.iter().enumerate() {
        let p = tri.map(|i| mesh.positions[i as usize]);
        let ng = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let stored = scene
            .mesh_tangents
            .get(g.source as usize)
            .and_then(Option::as_ref);
        let tangents = match stored {
            Some(corners) => corners[t],
            None => [triangle_tangent(p, uvs[t]).unwrap_or(Vec4::ZERO); 3],
        };
        let material = g.faces.as_ref().map_or(0, |f| f[t]);
        for (c, tangent) in tangents.into_iter().enumerate() {
            out.push(VertexRaw {
                position: p[c].into(),
                normal: mesh.normals[tri[c] as usize].into(),
                geometric_normal: ng.into(),
                material,
                uv: uvs[t][c].into(),
                tangent: tangent.into(),
            });
        }
    }
}

/// Object `o`'s instance record.
pub fn instance_of(o: &SceneObject) -> InstanceRaw {
    let n = o.normal_matrix;
    let flip = if o.flipped { -1.0 } else { 1.0 };
    InstanceRaw {
        model: o.transform.to_cols_array_2d(),
        normal: [
            n.x_axis.extend(flip).into(),
            n.y_axis.extend(0.0).into(),
            n.z_axis.extend(0.0).into(),
        ],
        material: o.material,
        _pad: [0; 3],
    }
}

/// The scene's instanced geometry on the GPU: the unique meshes' vertices
/// ([`VertexRaw`], buffer slot 0) and one [`InstanceRaw`] per object (slot 1).
pub struct Geometry {
    pub vertices: wgpu::Buffer,
    pub instances: wgpu::Buffer,
    /// Every object's whole mesh (the passes that draw all of the scene).
    pub all: Vec<Draw>,
}

/// Bytes of the instanced geometry's buffers: (vertices, instances).
pub fn buffer_bytes(cull: &CullUnits) -> (u64, u64) {
    (
        cull.vertex_count() as u64 * std::mem::size_of::<VertexRaw>() as u64,
        cull.objects.len() as u64 * std::mem::size_of::<InstanceRaw>() as u64,
    )
}

impl Geometry {
    /// Uploads the scene's meshes, as `cull` lays them out, and its instances.
    pub fn upload(ctx: &GpuContext, scene: &Scene, cull: &CullUnits) -> Self {
        let mut verts = Vec::with_capacity(cull.vertex_count() as usize);
        for g in cull.meshes.iter() {
            mesh_vertices(scene, g, &mut verts);
        }
        let instances: Vec<InstanceRaw> = scene.objects.iter().map(instance_of).collect();
        let usage = wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST;
        // wgpu refuses empty vertex buffers: one zero record stands in.
        let verts = if verts.is_empty() {
            vec![VertexRaw::zeroed(); 3]
        } else {
            verts
        };
        let records = if instances.is_empty() {
            vec![InstanceRaw::zeroed()]
        } else {
            instances
        };
        Geometry {
            vertices: super::buffer_init(ctx, "mesh vertices", bytemuck::cast_slice(&verts), usage),
            instances: super::buffer_init(ctx, "instances", bytemuck::cast_slice(&records), usage),
            all: cull.all(),
        }
    }

    /// Rewrites object `o`'s instance record (after it moved).
    pub fn write_instance(&self, ctx: &GpuContext, scene: &Scene, o: usize) {
        let raw = instance_of(&scene.objects[o]);
        crate::gpu::write_buffer(
            &ctx.queue,
            "instances",
            &self.instances,
            (o * std::mem::size_of::<InstanceRaw>()) as u64,
            bytemuck::bytes_of(&raw),
        );
    }

    /// Binds the buffers to `pass` and records `draws` (all of the scene with `None`).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, draws: Option<&[Draw]>) {
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_vertex_buffer(1, self.instances.slice(..));
        for d in draws.unwrap_or(&self.all) {
            pass.draw(d.vertices.clone(), d.instances.clone());
        }
    }
}

/// Fails with `OutOfMemory` when the instanced geometry's buffers (the unique meshes'
/// vertices, one record per object) would not fit, and with a GPU error when a buffer
/// exceeds the adapter's limits; before either is built.
pub fn check_buffers(ctx: &GpuContext, scene: &Scene) -> Result<()> {
    let mut seen = std::collections::HashSet::new();
    let triangles: u64 = scene
        .objects
        .iter()
        .filter(|o| seen.insert(mesh_key(o)))
        .map(|o| scene.meshes[o.mesh as usize].indices.len() as u64)
        .sum();
    let vertices = triangles * 3 * std::mem::size_of::<VertexRaw>() as u64;
    let instances = scene.objects.len() as u64 * std::mem::size_of::<InstanceRaw>() as u64;
    crate::memory::check(
        || {
            format!(
                "the scene's GPU geometry ({} objects, {} unique triangles)",
                scene.objects.len(),
                triangles
            )
        },
        // The CPU copy of the vertices while uploading, and the culling data per object.
        vertices * 2 + instances * 2,
    )?;
    ctx.check_buffer("the scene's unique meshes' vertices", vertices)?;
    ctx.check_buffer("the scene's instance records", instances)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::light_views::{look_to, perspective};

    /// Which flat triangles `draws` rasterize (object by object, its mesh's triangles).
    fn drawn(scene: &Scene, cull: &CullUnits, draws: &[Draw]) -> Vec<bool> {
        let mut seen = vec![false; scene.triangle_count()];
        for d in draws {
            for i in d.instances.clone() {
                let (mesh, _) = cull.objects[i as usize];
                let g = &cull.meshes[mesh as usize];
                assert!(g.vertices.start <= d.vertices.start && d.vertices.end <= g.vertices.end);
                let first = scene.objects[i as usize].triangles.start;
                let t = |v: u32| (first + (v - g.vertices.start) / 3) as usize;
                for s in &mut seen[t(d.vertices.start)..t(d.vertices.end)] {
                    assert!(!*s, "a triangle drawn twice");
                    *s = true;
                }
            }
        }
        seen
    }

    /// Culling is conservative and per instance: on the 100-sphere grid seen from a camera
    /// that sees part of it, every triangle with a corner strictly inside the view volume
    /// is drawn (once), whole spheres out of view are not, and the draws merge runs of
    /// spheres. Unculled, every triangle is drawn once, in one draw per run of objects
    /// sharing a mesh.
    #[test]
    fn culled_draws_hold_every_triangle_in_view() {
        let mut scene = crate::scene::bench::sphere_copies(100, false);
        let cull = CullUnits::of(&scene);
        // The spheres are one mesh; the box's walls are others.
        assert!(cull.meshes.len() < 10, "{}", cull.meshes.len());
        let all = cull.all();
        assert!(drawn(&scene, &cull, &all).iter().all(|&s| s));
        assert_eq!(triangles_drawn(&all), scene.triangle_count() as u64);
        assert!(all.len() < 10, "{} draws", all.len());

        let view = perspective(0.3, 1.0, 0.01, 20.0)
            * look_to(Vec3::new(0.9, 1.0, 1.5), Vec3::new(0.0, 0.0, -1.0), Vec3::Y);
        for moved in [false, true] {
            let cull = if moved {
                // Move the first sphere into the middle of the view: the draws follow it.
                let o = scene.objects.len() - 100;
                let update = crate::scene::SceneUpdate::Transform {
                    object: o,
                    transform: Mat4::from_translation(Vec3::new(0.9, 1.0, 1.0))
                        * Mat4::from_scale(Vec3::splat(0.5)),
                };
                scene.apply(&update).expect("move");
                let mut c = CullUnits::of(&crate::scene::bench::sphere_copies(100, false));
                c.moved(&scene);
                c
            } else {
                CullUnits::of(&scene)
            };
            let draws = cull.draws(&[view]).pop().expect("one view");
            let seen = drawn(&scene, &cull, &draws);
            let inside = |p: Vec3| {
                let c = view * p.extend(1.0);
                c.w > 0.0 && c.x.abs() < c.w && c.y.abs() < c.w && c.z > 0.0 && c.z < c.w
            };
            let mut visible = 0;
            for (t, s) in seen.iter().enumerate() {
                if scene.triangle(t).into_iter().any(inside) {
                    visible += 1;
                    assert!(s, "triangle {t} in view, not drawn (moved: {moved})");
                }
            }
            let n = triangles_drawn(&draws);
            assert!(n < scene.triangle_count() as u64 / 3, "{n} drawn");
            assert!(visible > 1000, "{visible} visible");
            if moved {
                let o = &scene.objects[scene.objects.len() - 100];
                assert!(seen[o.triangles.start as usize..o.triangles.end as usize]
                    .iter()
                    .any(|&s| s));
            }
            eprintln!(
                "moved {moved}: {n} of {} triangles drawn in {} draws, {visible} in view",
                scene.triangle_count(),
                draws.len()
            );
        }
    }

    /// A box is inside exactly when all its points are: against random boxes, `Inside`
    /// boxes have every sampled point inside the view volume, `Outside` ones none, and all
    /// three outcomes occur.
    #[test]
    fn clip_box_classifies_boxes() {
        let m = perspective(1.05, 1.3, 0.01, 10.0) * look_to(Vec3::ZERO, Vec3::X, Vec3::Y);
        let inside = |p: Vec3| {
            let c = m * p.extend(1.0);
            c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w && c.z >= 0.0 && c.z <= c.w
        };
        let mut rng = crate::sampling::Rng::new(5, 0, 0);
        let mut counts = [0; 3];
        let mut r3 = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        for _ in 0..3000 {
            let a = r3() * 8.0 - Vec3::new(0.0, 4.0, 4.0);
            let b = a + r3() * 1.5;
            let clip = clip_box(&m, a, b);
            counts[clip as usize] += 1;
            for _ in 0..32 {
                let p = a + (b - a) * r3();
                match clip {
                    Clip::Outside => assert!(!inside(p), "{a} {b} holds {p}"),
                    Clip::Inside => assert!(inside(p), "{a} {b}: {p} outside"),
                    Clip::Partly => {}
                }
            }
        }
        assert!(counts.iter().all(|&c| c > 100), "{counts:?}");
    }
}
