//! Closest-hit and any-hit ray queries over all scene triangles, via obvhs's compressed
//! wide BVH (CWBVH, built with PLOC).

use crate::error::Result;
use crate::memory;
use crate::scene::Scene;
use glam::{Affine3A, Vec3, Vec3A};
pub use obvhs::ploc::PlocSearchDistance;
use obvhs::{
    aabb::Aabb, bvh2::reinsertion::ReinsertionOptimizer, bvh2::Bvh2,
    cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh, cwbvh::CwBvh, ploc::PlocBuilder, ray::Ray,
    triangle::Triangle, BvhBuildParams,
};
use std::collections::HashMap;
use std::sync::Arc;

/// Peak memory of a BVH build per triangle (bytes): the obvhs triangles, the PLOC build's
/// boxes, Morton codes and binary nodes (kept for refits), the compressed wide BVH and the
/// Möller–Trumbore copies. Measured 325 bytes (peak RSS growth building 1.3M triangles,
/// `Scene.build_bvh`); with headroom.
const BUILD_BYTES_PER_TRIANGLE: u64 = 512;

/// A closest hit: distance, triangle index (into the scene) and barycentrics of v1 and v2.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    pub triangle: u32,
    pub u: f32,
    pub v: f32,
}

/// Triangle pre-processed for Möller–Trumbore.
#[derive(Clone, Copy, Debug)]
pub(super) struct Tri {
    pub(super) v0: Vec3A,
    pub(super) e1: Vec3A,
    pub(super) e2: Vec3A,
}

impl Tri {
    /// (t, u, v) of a hit within (tmin, tmax), barycentrics relative to v1 and v2.
    #[inline(always)]
    fn intersect(&self, ray: &Ray) -> Option<(f32, f32, f32)> {
        let p = ray.direction.cross(self.e2);
        let det = self.e1.dot(p);
        if det.abs() < 1e-12 {
            return None;
        }
        let inv = 1.0 / det;
        let s = ray.origin - self.v0;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(self.e1);
        let v = ray.direction.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = self.e2.dot(q) * inv;
        (t > ray.tmin && t < ray.tmax).then_some((t, u, v))
    }
}

/// An obvhs ray for the open segment (0, tmax).
///
/// obvhs picks the traversal octant with `d < 0` (false for -0.0) but inverts -0.0 to a
/// huge *negative* value, and the mismatch makes rays such as (-1, -0, -0) miss everything.
/// Adding +0.0 turns every -0.0 into +0.0 (IEEE 754) and leaves all other values alone.
#[inline]
fn make_ray(origin: Vec3, dir: Vec3, tmax: f32) -> Ray {
    Ray::new(origin.into(), (dir + Vec3::ZERO).into(), 0.0, tmax)
}

/// One mesh's triangles in BVH order, and the BVH: a compressed wide BVH for queries,
/// converted from the binary tree that PLOC builds, which is kept so that a moved mesh can
/// be refitted ([`MeshBvh::refit`]) instead of built anew. The bottom level of [`SceneBvh`].
pub struct MeshBvh {
    bvh: CwBvh,
    tris: Vec<Tri>,
    /// Mesh triangle index of each BVH-ordered triangle.
    ids: Vec<u32>,
    pub(super) bvh2: Bvh2,
    pub(super) triangles: Vec<Triangle>,
}

/// The any-hit test of alpha-masked materials: a hit where the mask's coverage is below the
/// cutoff is skipped, as the GPU passes discard those fragments.
struct AlphaTest {
    /// Per material: index into `masks`, or `u32::MAX` when opaque.
    per_material: Vec<u32>,
    /// Coverage texture and cutoff per masked material.
    masks: Vec<(std::sync::Arc<crate::texture::Texture>, f32)>,
    /// Per object (instance): material, the file's per-face materials, its mesh's texture
    /// coordinates (shared), and whether it is mirrored.
    objects: Vec<ObjectAlpha>,
}

/// An object's material, the file's per-face materials, its mesh's texture coordinates and
/// whether it is mirrored.
type ObjectAlpha = (u32, Option<Arc<Vec<u32>>>, Arc<Vec<[glam::Vec2; 3]>>, bool);

impl AlphaTest {
    fn new(scene: &Scene) -> Option<AlphaTest> {
        if !scene.has_alpha_masks() {
            return None;
        }
        let mut masks = Vec::new();
        let per_material: Vec<u32> = scene
            .material_maps
            .iter()
            .map(|m| match m.alpha {
                Some(t) => {
                    masks.push((scene.textures[t as usize].clone(), m.alpha_cutoff));
                    (masks.len() - 1) as u32
                }
                None => u32::MAX,
            })
            .collect();
        Some(AlphaTest {
            per_material,
            masks,
            objects: scene
                .objects
                .iter()
                .map(|o| {
                    (
                        o.material,
                        o.face_materials.clone(),
                        scene.mesh_uvs[o.mesh as usize].clone(),
                        o.flipped,
                    )
                })
                .collect(),
        })
    }

    /// Whether the hit at barycentrics (u, v) (mesh corner order) of mesh triangle `t` of
    /// object `object` is cut out; the texture coordinates are interpolated in the flat
    /// corner order, as [`Scene::uv_at`] does.
    #[inline]
    fn cut(&self, object: u32, t: u32, u: f32, v: f32) -> bool {
        let (base, faces, uvs, flipped) = &self.objects[object as usize];
        let material = faces.as_ref().map_or(*base, |f| base + f[t as usize]);
        let m = self.per_material[material as usize];
        if m == u32::MAX {
            return false;
        }
        let (tex, cutoff) = &self.masks[m as usize];
        let c = uvs[t as usize];
        let (c, u, v) = if *flipped {
            ([c[0], c[2], c[1]], v, u)
        } else {
            (c, u, v)
        };
        let uv = c[0] * (1.0 - u - v) + c[1] * u + c[2] * v;
        tex.sample(uv, 0.0).w < *cutoff
    }
}

/// How [`SceneBvh`] builds its tree: obvhs's PLOC (search distance, the depth below which it
/// searches one neighbour only) and reinsertion (the share of nodes reinserted), plus
/// whether coincident triangles are told apart first. The defaults were chosen by build
/// time against trace time, `docs/bench/bvh-build.md`.
#[derive(Clone, Copy, Debug)]
pub struct BuildSettings {
    pub search: PlocSearchDistance,
    pub search_depth_threshold: usize,
    pub reinsertion: f32,
    /// PLOC pairs two nodes only when each is the other's cheapest neighbour, and breaks ties
    /// toward the right: a run of identical boxes (copies of one mesh at one place) merges
    /// one pair per pass into a chain as deep as the copies, quadratic in them (242 copies of
    /// a 20k-triangle sphere: 33 s). With this set, coincident triangles' boxes are moved apart for the
    /// build (`separated_boxes`) so that the copies pair up into a balanced subtree; the
    /// leaves get their exact boxes back (and the tree is refitted) before it is used.
    pub separate_coincident: bool,
}

impl BuildSettings {
    pub const DEFAULT: BuildSettings = BuildSettings {
        search: PlocSearchDistance::Medium,
        search_depth_threshold: 3,
        reinsertion: 0.05,
        separate_coincident: true,
    };
}

/// A fast hasher for the boxes' bit patterns (multiply–rotate per word).
#[derive(Default)]
struct BoxHasher(u64);

impl std::hash::Hasher for BoxHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for w in bytes.chunks(4) {
            let mut word = [0u8; 4];
            word[..w.len()].copy_from_slice(w);
            self.write_u32(u32::from_le_bytes(word));
        }
    }
    fn write_u32(&mut self, v: u32) {
        self.0 = (self.0 ^ v as u64)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .rotate_left(26);
    }
}

/// The bit pattern of a triangle's vertices: equal for coincident triangles.
fn vertex_bits(t: &Triangle) -> [u32; 9] {
    let (a, b, c) = (t.v0.to_array(), t.v1.to_array(), t.v2.to_array());
    [a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]].map(f32::to_bits)
}

/// Each triangle's box, with the boxes of coincident triangles (bitwise equal vertices) moved
/// apart for the build: the k-th of m copies is shifted along the diagonal by k/m of half
/// its extent, so that PLOC pairs neighbouring copies into a balanced subtree instead of
/// absorbing them one per pass. `None` when no two triangles are coincident.
fn separated_boxes(triangles: &[Triangle]) -> Option<Vec<Aabb>> {
    use std::hash::Hasher;
    // Fast path (most scenes): sorted 64-bit hashes of the triangles all differ.
    let mut hashes: Vec<u64> = triangles
        .iter()
        .map(|t| {
            let mut h = BoxHasher::default();
            vertex_bits(t).iter().for_each(|w| h.write_u32(*w));
            h.finish()
        })
        .collect();
    hashes.sort_unstable();
    if hashes.windows(2).all(|w| w[0] != w[1]) {
        return None;
    }
    drop(hashes);
    // Per distinct triangle: (copies, copies seen so far).
    let mut seen: HashMap<[u32; 9], (u32, u32), std::hash::BuildHasherDefault<BoxHasher>> =
        HashMap::with_capacity_and_hasher(triangles.len(), Default::default());
    for t in triangles {
        seen.entry(vertex_bits(t)).or_insert((0, 0)).0 += 1;
    }
    let moved = triangles
        .iter()
        .map(|t| {
            let b = t.aabb();
            let Some(e) = seen.get_mut(&vertex_bits(t)).filter(|e| e.0 > 1) else {
                return b;
            };
            let rank = e.1;
            e.1 += 1;
            // Degenerate (point or segment) triangles still get a distinct shift.
            let extent = (b.max - b.min)
                .max_element()
                .max(b.max.abs().max_element() * 1e-5)
                .max(1e-20);
            let shift = Vec3A::splat(extent * 0.5 * rank as f32 / e.0 as f32);
            Aabb {
                min: b.min + shift,
                max: b.max + shift,
            }
        })
        .collect();
    Some(moved)
}

/// The scene's flat triangles in world space (one mesh of every object's copy): for the
/// flat-BVH benchmarks.
pub fn flat_triangles(scene: &Scene) -> Vec<Triangle> {
    (0..scene.triangle_count())
        .map(|t| {
            let [a, b, c] = scene.triangle(t);
            Triangle {
                v0: a.into(),
                v1: b.into(),
                v2: c.into(),
            }
        })
        .collect()
}

impl MeshBvh {
    /// The build of obvhs's `build_cwbvh_from_tris` (medium quality, no spatial splits),
    /// keeping the binary tree, with coincident triangles told apart
    /// ([`BuildSettings::DEFAULT`]).
    pub fn from_triangles(triangles: &[Triangle]) -> Self {
        Self::from_triangles_with(triangles, &BuildSettings::DEFAULT)
    }

    /// [`MeshBvh::from_triangles`] with explicit build settings (for the build benchmark).
    pub fn from_triangles_with(triangles: &[Triangle], settings: &BuildSettings) -> Self {
        let p = BvhBuildParams::medium_build();
        let indices = (0..triangles.len() as u32).collect();
        let separated = if settings.separate_coincident {
            separated_boxes(triangles)
        } else {
            None
        };
        let mut bvh2 = if let Some(boxes) = &separated {
            PlocBuilder::with_capacity(triangles.len()).build(
                settings.search,
                boxes,
                indices,
                p.sort_precision,
                settings.search_depth_threshold,
            )
        } else {
            PlocBuilder::with_capacity(triangles.len()).build(
                settings.search,
                triangles,
                indices,
                p.sort_precision,
                settings.search_depth_threshold,
            )
        };
        ReinsertionOptimizer::default().run(&mut bvh2, settings.reinsertion, None);
        if separated.is_some() {
            // Back to the triangles' own boxes, so that refits and queries see tight bounds.
            for node in bvh2.nodes.iter_mut().filter(|n| n.is_leaf()) {
                let t = bvh2.primitive_indices[node.first_index as usize];
                node.set_aabb(triangles[t as usize].aabb());
            }
            bvh2.refit_all();
        }
        Self::from_bvh2(bvh2, triangles.to_vec())
    }

    fn from_bvh2(bvh2: Bvh2, triangles: Vec<Triangle>) -> Self {
        let p = BvhBuildParams::medium_build();
        let bvh = bvh2_to_cwbvh(&bvh2, p.max_prims_per_leaf.clamp(1, 3), true, false);
        let ids: Vec<u32> = bvh.primitive_indices.clone();
        let tris = ids
            .iter()
            .map(|&i| {
                let t = &triangles[i as usize];
                Tri {
                    v0: t.v0,
                    e1: t.v1 - t.v0,
                    e2: t.v2 - t.v0,
                }
            })
            .collect();
        MeshBvh {
            bvh,
            tris,
            ids,
            bvh2,
            triangles,
        }
    }

    /// Updates the tree after triangles `moved` (indices into the mesh) changed to
    /// `triangles`: their leaf boxes, then every parent (the topology stays, so quality drops
    /// as they travel), then the wide BVH again.
    pub fn refit(self, triangles: &[Triangle], moved: &[std::ops::Range<usize>]) -> Self {
        let MeshBvh {
            mut bvh2,
            triangles: mut mine,
            ..
        } = self;
        bvh2.init_primitives_to_nodes_if_uninit();
        for range in moved {
            for t in range.clone() {
                let node = bvh2.primitives_to_nodes[t] as usize;
                bvh2.nodes[node].set_aabb(obvhs::Boundable::aabb(&triangles[t]));
                mine[t] = triangles[t];
            }
        }
        bvh2.refit_all();
        Self::from_bvh2(bvh2, mine)
    }

    /// The box around every triangle (empty without any).
    fn bounds(&self) -> Aabb {
        self.bvh2.nodes.first().map_or(Aabb::empty(), |n| *n.aabb())
    }

    /// Closest hit of `ray` whose (mesh triangle, u, v) `keep` accepts: (mesh triangle, t, u,
    /// v).
    #[inline]
    fn closest(
        &self,
        ray: Ray,
        keep: impl Fn(u32, f32, f32) -> bool,
    ) -> Option<(u32, f32, f32, f32)> {
        let mut best = None;
        let mut hit = obvhs::ray::RayHit::none();
        self.bvh
            .ray_traverse(ray, &mut hit, |r, id| match self.tris[id].intersect(r) {
                Some((t, u, v)) if keep(self.ids[id], u, v) => {
                    best = Some((self.ids[id], t, u, v));
                    t
                }
                _ => f32::INFINITY,
            });
        // The traversal only reports hits closer than the running tmax, so the last one
        // recorded is the closest.
        best
    }

    /// Distance of some hit of `ray` that `keep` accepts (infinity: none).
    #[inline]
    fn any(&self, ray: Ray, keep: impl Fn(u32, f32, f32) -> bool) -> f32 {
        let mut found = f32::INFINITY;
        self.bvh
            .ray_traverse_miss(ray, |r, id| match self.tris[id].intersect(r) {
                Some((t, u, v)) if keep(self.ids[id], u, v) => {
                    found = t;
                    t
                }
                _ => f32::INFINITY,
            });
        found
    }

    /// Closest hit along `origin + t·dir`, t in (0, tmax): (mesh triangle, t, u, v).
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<(u32, f32, f32, f32)> {
        self.closest(make_ray(origin, dir, tmax), |_, _, _| true)
    }

    /// True when anything blocks the open segment (0, tmax) of the ray.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        self.any(make_ray(origin, dir, tmax), |_, _, _| true) < f32::INFINITY
    }
}

/// Scenes of at most this many placed triangles (and no alpha masks) are traced as one
/// world-space mesh, as before instancing: on such scenes the top level and the ray's
/// transform into each instance's frame cost more than they save (`path` on the 30-triangle
/// Cornell box of `docs/bench/path-vs-mitsuba.md`; section 6 of `docs/bench/instancing.md`).
/// Moving an object refits the baked mesh, O(triangles) over at most this many.
pub const BAKE_TRIANGLES: usize = 4096;

/// Whether `scene` is traced as one baked world-space mesh ([`BAKE_TRIANGLES`]).
fn bakes(scene: &Scene) -> bool {
    scene.triangle_count() <= BAKE_TRIANGLES && !scene.has_alpha_masks()
}

/// Every placed triangle of `scene` in world space and flat order (corners as the flat view
/// stores them, bitwise), without building the flat view.
fn world_triangles(scene: &Scene) -> Vec<Triangle> {
    let mut out = vec![Triangle::default(); scene.triangle_count()];
    scene.for_each_triangle(
        |_| false,
        |t, [a, b, c]| {
            out[t] = Triangle {
                v0: a.into(),
                v1: b.into(),
                v2: c.into(),
            }
        },
    );
    out
}

/// Bytes per instance of a [`SceneBvh`] build: the instance record, its box, and the top
/// level's PLOC and wide nodes (a few per instance), with headroom.
const BUILD_BYTES_PER_INSTANCE: u64 = 512;

/// One object placed in the top level: its mesh's BVH, the world -> mesh transform, and
/// where its triangles start in the scene's flat numbering.
#[derive(Clone, Copy, Debug)]
pub(super) struct Instance {
    pub(super) to_local: Affine3A,
    pub(super) mesh: u32,
    pub(super) first_triangle: u32,
    /// The flat arrays store a mirrored object's triangles with corners 1 and 2 swapped, so
    /// its barycentrics swap too.
    pub(super) flipped: bool,
}

/// A mesh placed as it is (world space), its triangles numbered from 0.
const IDENTITY_INSTANCE: Instance = Instance {
    to_local: Affine3A::IDENTITY,
    mesh: 0,
    first_triangle: 0,
    flipped: false,
};

/// The two-level BVH of a scene: one [`MeshBvh`] per unique mesh (in its local frame, built
/// once and shared, [`Scene::meshes`]) and a top level over the objects (instances). Moving
/// objects ([`SceneBvh::refit`]) rebuilds the top level only: O(instances), never the
/// triangles. Hits name the scene's flat triangle index, with barycentrics in its corner
/// order, so that the flat view and the instances agree.
pub struct SceneBvh {
    pub(super) meshes: Vec<Arc<MeshBvh>>,
    pub(super) instances: Vec<Instance>,
    /// The top level over instance boxes (BVH order -> instance in `order`).
    top: CwBvh,
    order: Vec<u32>,
    /// Alpha masks of the scene's materials (none: every hit counts).
    alpha: Option<AlphaTest>,
    /// One world-space mesh of the whole scene in flat triangle order ([`BAKE_TRIANGLES`]):
    /// rays go to it directly.
    baked: bool,
}

fn mesh_triangles(mesh: &crate::scene::TriMesh) -> Vec<Triangle> {
    mesh.indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| Vec3A::from(mesh.positions[i as usize]));
            Triangle {
                v0: a,
                v1: b,
                v2: c,
            }
        })
        .collect()
}

/// Each object of `scene` as an instance of its mesh.
fn scene_instances(scene: &Scene) -> Vec<Instance> {
    scene
        .objects
        .iter()
        .map(|o| Instance {
            to_local: Affine3A::from_mat4(o.transform).inverse(),
            mesh: o.mesh,
            first_triangle: o.triangles.start,
            flipped: o.flipped,
        })
        .collect()
}

/// Instance boxes with equal ones moved apart as [`separated_boxes`] does for triangles
/// (`None` when all differ).
fn separated_instance_boxes(boxes: &[Aabb]) -> Option<Vec<Aabb>> {
    let as_triangle = |b: &Aabb| Triangle {
        v0: b.min,
        v1: b.max,
        v2: b.min,
    };
    let tris: Vec<Triangle> = boxes.iter().map(as_triangle).collect();
    separated_boxes(&tris)
}

/// The box of `b` placed by `xf` (its eight corners transformed).
fn placed_box(b: &Aabb, xf: &Affine3A) -> Aabb {
    if !b.valid() {
        return *b;
    }
    let mut out = Aabb::empty();
    for i in 0..8 {
        let c = Vec3A::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        );
        out.extend(xf.transform_point3a(c));
    }
    out
}

/// The top level over `instances`: (wide BVH, instance of each BVH-ordered leaf).
fn build_top(meshes: &[Arc<MeshBvh>], instances: &[Instance]) -> (CwBvh, Vec<u32>) {
    let top = bvh2_to_cwbvh(&top_bvh2(meshes, instances), 1, true, false);
    let order = top.primitive_indices.clone();
    (top, order)
}

/// The binary tree over the boxes of `instances` that [`build_top`] converts (the GPU
/// traverses it as it is, `trace::bvh_flat`).
pub(super) fn top_bvh2(meshes: &[Arc<MeshBvh>], instances: &[Instance]) -> Bvh2 {
    let boxes: Vec<Aabb> = instances
        .iter()
        .map(|i| placed_box(&meshes[i.mesh as usize].bounds(), &i.to_local.inverse()))
        .collect();
    let p = BvhBuildParams::medium_build();
    // Coincident instances (equal boxes) would chain as coincident triangles do: told apart
    // for the build, then given their exact boxes back.
    let separated = separated_instance_boxes(&boxes);
    let mut bvh2 = PlocBuilder::with_capacity(boxes.len()).build(
        BuildSettings::DEFAULT.search,
        separated.as_deref().unwrap_or(&boxes),
        (0..boxes.len() as u32).collect(),
        p.sort_precision,
        BuildSettings::DEFAULT.search_depth_threshold,
    );
    ReinsertionOptimizer::default().run(&mut bvh2, BuildSettings::DEFAULT.reinsertion, None);
    if separated.is_some() {
        for node in bvh2.nodes.iter_mut().filter(|n| n.is_leaf()) {
            let i = bvh2.primitive_indices[node.first_index as usize];
            node.set_aabb(boxes[i as usize]);
        }
        bvh2.refit_all();
    }
    bvh2
}

impl SceneBvh {
    /// Builds the BVH of every unique mesh of `scene` and the top level over its objects.
    pub fn build(scene: &Scene) -> Self {
        Self::build_with(scene, &BuildSettings::DEFAULT)
    }

    /// [`SceneBvh::build`] with explicit build settings for the meshes (for the build
    /// benchmark).
    pub fn build_with(scene: &Scene, settings: &BuildSettings) -> Self {
        if bakes(scene) {
            // Small: its flat view costs little, and the surface interactions then read
            // corners from it instead of placing them per hit.
            let _ = scene.flat();
            return Self::baked(MeshBvh::from_triangles_with(
                &world_triangles(scene),
                settings,
            ));
        }
        let meshes = scene
            .meshes
            .iter()
            .map(|m| Arc::new(MeshBvh::from_triangles_with(&mesh_triangles(m), settings)))
            .collect();
        Self::from_parts(meshes, scene_instances(scene), AlphaTest::new(scene))
    }

    fn from_parts(
        meshes: Vec<Arc<MeshBvh>>,
        instances: Vec<Instance>,
        alpha: Option<AlphaTest>,
    ) -> Self {
        let (top, order) = build_top(&meshes, &instances);
        SceneBvh {
            meshes,
            instances,
            top,
            order,
            alpha,
            baked: false,
        }
    }

    /// The scene baked into `mesh` (world space, flat order): one identity instance.
    fn baked(mesh: MeshBvh) -> Self {
        let mut b = Self::from_parts(vec![Arc::new(mesh)], vec![IDENTITY_INSTANCE], None);
        b.baked = true;
        b
    }

    /// Whether any hit may be cut out by an alpha mask (the GPU traversal has no masks).
    pub fn has_alpha_masks(&self) -> bool {
        self.alpha.is_some()
    }

    /// Re-reads the alpha masks of the scene's materials (after a material update).
    pub fn update_alpha(&mut self, scene: &Scene) {
        if self.baked != bakes(scene) {
            // Masks appeared in a baked scene (or went from a small one): built again.
            *self = Self::build(scene);
            return;
        }
        self.alpha = AlphaTest::new(scene);
    }

    /// [`SceneBvh::build`] after checking that the build fits in memory: the unique
    /// triangles and the instances.
    pub fn try_build(scene: &Scene) -> Result<Self> {
        memory::check(
            || {
                format!(
                    "the BVH over {} unique triangles and {} instances",
                    scene.unique_triangle_count(),
                    scene.objects.len()
                )
            },
            Self::estimate_bytes(scene.unique_triangle_count(), scene.objects.len()),
        )?;
        Ok(Self::build(scene))
    }

    /// Peak bytes of a build over `triangles` unique triangles placed by `instances` objects.
    pub fn estimate_bytes(triangles: usize, instances: usize) -> u64 {
        (triangles as u64)
            .saturating_mul(BUILD_BYTES_PER_TRIANGLE)
            .saturating_add((instances as u64).saturating_mul(BUILD_BYTES_PER_INSTANCE))
    }

    /// One mesh of `triangles` in world space (no scene): for tests and benchmarks.
    pub fn from_triangles(triangles: &[Triangle]) -> Self {
        Self::from_triangles_with(triangles, &BuildSettings::DEFAULT)
    }

    /// [`SceneBvh::from_triangles`] with explicit build settings.
    pub fn from_triangles_with(triangles: &[Triangle], settings: &BuildSettings) -> Self {
        Self::baked(MeshBvh::from_triangles_with(triangles, settings))
    }

    /// Updates the BVH after objects moved (their new transforms are read from `scene`):
    /// the top level only, O(instances); the meshes' BVHs are kept. `moved` (flat triangle
    /// ranges) is not needed by the two-level BVH and kept for the callers.
    pub fn refit(self, scene: &Scene, moved: &[std::ops::Range<usize>]) -> Self {
        if self.baked && bakes(scene) {
            let tris = world_triangles(scene);
            let mesh = self.meshes.into_iter().next().map(Arc::try_unwrap);
            return Self::baked(match mesh {
                Some(Ok(mesh)) => mesh.refit(&tris, moved),
                _ => MeshBvh::from_triangles(&tris),
            });
        }
        if self.baked || bakes(scene) {
            return Self::build(scene);
        }
        Self::from_parts(self.meshes, scene_instances(scene), AlphaTest::new(scene))
    }

    /// [`SceneBvh::refit`] without re-reading the alpha masks (for the update benchmark).
    pub fn update_instances(&mut self, scene: &Scene) {
        if self.baked || bakes(scene) {
            *self = Self::build(scene);
            return;
        }
        self.instances = scene_instances(scene);
        let (top, order) = build_top(&self.meshes, &self.instances);
        self.top = top;
        self.order = order;
    }

    /// Unique meshes and instances in the BVH.
    pub fn counts(&self) -> (usize, usize) {
        (self.meshes.len(), self.instances.len())
    }

    /// The ray in instance `i`'s mesh frame (same parameter t: the direction is not
    /// renormalised).
    #[inline(always)]
    fn local_ray(&self, i: &Instance, origin: Vec3A, dir: Vec3A, tmax: f32) -> Ray {
        make_ray(
            i.to_local.transform_point3a(origin).into(),
            i.to_local.transform_vector3a(dir).into(),
            tmax,
        )
    }

    /// Whether the hit (u, v) (mesh corner order) on mesh triangle `t` of instance
    /// `which` is cut out by an alpha mask.
    #[inline]
    fn cut_out(&self, which: u32, t: u32, u: f32, v: f32) -> bool {
        self.alpha.as_ref().is_some_and(|a| a.cut(which, t, u, v))
    }

    /// Closest hit along `origin + t·dir`, t in (0, tmax).
    #[inline]
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        let ray = make_ray(origin, dir, tmax);
        if self.baked {
            return self.meshes[0]
                .closest(ray, |_, _, _| true)
                .map(|(triangle, t, u, v)| Hit { t, triangle, u, v });
        }
        let (o, d) = (Vec3A::from(origin), Vec3A::from(dir));
        let mut best: Option<(u32, u32, f32, f32, f32)> = None;
        let mut hit = obvhs::ray::RayHit::none();
        self.top.ray_traverse(ray, &mut hit, |r, k| {
            let which = self.order[k];
            let i = &self.instances[which as usize];
            let local = self.local_ray(i, o, d, r.tmax);
            match self.meshes[i.mesh as usize]
                .closest(local, |t, u, v| !self.cut_out(which, t, u, v))
            {
                Some((t_mesh, t, u, v)) => {
                    best = Some((which, t_mesh, t, u, v));
                    t
                }
                None => f32::INFINITY,
            }
        });
        best.map(|(which, t_mesh, t, u, v)| {
            let i = &self.instances[which as usize];
            let (u, v) = if i.flipped { (v, u) } else { (u, v) };
            Hit {
                t,
                triangle: i.first_triangle + t_mesh,
                u,
                v,
            }
        })
    }

    /// True when anything blocks the open segment (0, tmax) of the ray.
    #[inline]
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        let ray = make_ray(origin, dir, tmax);
        if self.baked {
            return self.meshes[0].any(ray, |_, _, _| true) < f32::INFINITY;
        }
        let (o, d) = (Vec3A::from(origin), Vec3A::from(dir));
        !self.top.ray_traverse_miss(ray, |r, k| {
            let which = self.order[k];
            let i = &self.instances[which as usize];
            let local = self.local_ray(i, o, d, r.tmax);
            self.meshes[i.mesh as usize].any(local, |t, u, v| !self.cut_out(which, t, u, v))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{uniform_sphere, Rng};

    /// After an object moved, the refitted BVH finds what a new one finds (same triangle and
    /// distance for every ray).
    #[test]
    fn refit_matches_rebuild() {
        let mut scene = crate::scene::builtin::load("cornell-glass").unwrap();
        let bvh = SceneBvh::build(&scene);
        let object = scene.objects.len() - 1;
        let o = &scene.objects[object];
        let moved = o.triangles.start as usize..o.triangles.end as usize;
        let transform = glam::Mat4::from_translation(Vec3::new(0.3, 0.1, -0.2)) * o.transform;
        scene
            .apply(&crate::scene::SceneUpdate::Transform { object, transform })
            .unwrap();
        let refit = bvh.refit(&scene, std::slice::from_ref(&moved));
        let fresh = SceneBvh::build(&scene);
        let mut rng = Rng::new(7, 0, 0);
        let mut hits = 0;
        for _ in 0..20_000 {
            let o = Vec3::new(
                rng.next_f32() * 2.0 - 1.0,
                rng.next_f32() * 2.0,
                rng.next_f32() * 2.0 - 1.0,
            );
            let d = uniform_sphere(rng.next_2d());
            let (a, b) = (refit.intersect(o, d, 1e30), fresh.intersect(o, d, 1e30));
            assert_eq!(a.map(|h| (h.triangle, h.t)), b.map(|h| (h.triangle, h.t)));
            assert_eq!(refit.occluded(o, d, 0.5), fresh.occluded(o, d, 0.5));
            hits += a.is_some() as u32;
        }
        assert!(hits > 10_000);
    }

    /// Depth of the binary tree (a leaf alone: 1).
    fn depth(bvh: &Bvh2) -> usize {
        let mut deepest = 0;
        let mut stack = vec![(0usize, 1usize)];
        while let Some((n, d)) = stack.pop() {
            deepest = deepest.max(d);
            let node = &bvh.nodes[n];
            if !node.is_leaf() {
                stack.push((node.first_index as usize, d + 1));
                stack.push((node.first_index as usize + 1, d + 1));
            }
        }
        deepest
    }

    /// 300 coincident copies of 40 random triangles: PLOC alone pairs one copy per pass and
    /// builds a chain (depth ≥ the copies, the quadratic build of the 242-sphere scene);
    /// with coincident triangles told apart the tree is logarithmic (≤ 4·log2 n), its leaves
    /// have their exact boxes, and every query finds what brute force finds (the closest
    /// distance; any hit exactly below and none just above it).
    #[test]
    fn coincident_copies_build_a_shallow_exact_tree() {
        let mut rng = Rng::new(3, 0, 0);
        let mut p = || Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
        let mesh: Vec<Triangle> = (0..40)
            .map(|_| {
                let c = p();
                Triangle {
                    v0: c,
                    v1: c + p() * 0.3,
                    v2: c + p() * 0.3,
                }
            })
            .collect();
        let copies = 300;
        let tris: Vec<Triangle> = (0..copies).flat_map(|_| mesh.iter().copied()).collect();
        let plain = MeshBvh::from_triangles_with(
            &tris,
            &BuildSettings {
                separate_coincident: false,
                ..BuildSettings::DEFAULT
            },
        );
        let bvh = MeshBvh::from_triangles(&tris);
        let log2 = (tris.len() as f64).log2().ceil() as usize;
        assert!(depth(&plain.bvh2) >= copies, "{}", depth(&plain.bvh2));
        assert!(
            depth(&bvh.bvh2) <= 4 * log2,
            "depth {} for {} triangles",
            depth(&bvh.bvh2),
            tris.len()
        );
        for node in bvh.bvh2.nodes.iter().filter(|n| n.is_leaf()) {
            let t = bvh.bvh2.primitive_indices[node.first_index as usize] as usize;
            assert_eq!(node.aabb(), &tris[t].aabb());
        }
        let mut rng = Rng::new(4, 0, 0);
        let mut hits = 0;
        for _ in 0..2000 {
            let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 3.0 - 1.5;
            let d = uniform_sphere(rng.next_2d());
            let ray = Ray::new(o.into(), d.into(), 0.0, f32::INFINITY);
            let brute = mesh
                .iter()
                .filter_map(|t| {
                    Tri {
                        v0: t.v0,
                        e1: t.v1 - t.v0,
                        e2: t.v2 - t.v0,
                    }
                    .intersect(&ray)
                    .map(|h| h.0)
                })
                .min_by(f32::total_cmp);
            let got = bvh.intersect(o, d, f32::INFINITY).map(|h| h.1);
            assert_eq!(brute, got);
            if let Some(t) = brute {
                hits += 1;
                assert!(bvh.occluded(o, d, t * 1.001));
                assert!(!bvh.occluded(o, d, t * 0.999));
            }
        }
        assert!(hits > 30, "{hits}"); // 61 with this seed: the check is not vacuous
    }

    /// The BVH finds exactly what a brute-force loop over all triangles finds.
    #[test]
    fn matches_brute_force() {
        let scene = crate::scene::builtin::load("cornell-glass").unwrap();
        let bvh = SceneBvh::build(&scene);
        let tris: Vec<Tri> = (0..scene.flat().triangles.len())
            .map(|t| {
                let [a, b, c] = scene.triangle(t);
                Tri {
                    v0: a.into(),
                    e1: (b - a).into(),
                    e2: (c - a).into(),
                }
            })
            .collect();
        let mut rng = Rng::new(1, 0, 0);
        for _ in 0..2000 {
            let o = Vec3::new(
                rng.next_f32() * 2.0 - 1.0,
                rng.next_f32() * 2.0,
                rng.next_f32() * 2.0 - 1.0,
            );
            let d = uniform_sphere(rng.next_2d());
            let ray = Ray::new(o.into(), d.into(), 0.0, f32::INFINITY);
            let brute = tris
                .iter()
                .enumerate()
                .filter_map(|(i, t)| t.intersect(&ray).map(|h| (i, h.0)))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            let got = bvh.intersect(o, d, f32::INFINITY);
            match (brute, got) {
                (None, None) => {}
                (Some((_, tb)), Some(h)) => assert!((tb - h.t).abs() < 1e-5, "{tb} vs {}", h.t),
                (b, g) => panic!("brute {b:?} vs bvh {g:?}"),
            }
            if let Some((_, t)) = brute {
                assert!(bvh.occluded(o, d, t * 1.001));
                assert!(!bvh.occluded(o, d, t * 0.999));
            }
        }
    }
}

#[cfg(test)]
mod axis_tests {
    use super::*;

    /// Rays along the coordinate axes (direction components exactly zero) must hit the
    /// walls of a closed box from every origin, including origins on a slab plane.
    #[test]
    fn axis_aligned_rays_hit_closed_box() {
        let mut json: serde_json::Value =
            serde_json::from_str(crate::scene::builtin::json("cornell").unwrap()).unwrap();
        // Close the front so every direction hits something.
        json["objects"]
            .as_array_mut()
            .unwrap()
            .push(serde_json::json!({
                "shape": {"type": "quad", "size": [2, 2]},
                "transform": {"rotate": [-90, 0, 0], "translate": [0, 1, 1]},
                "material": "white"
            }));
        let scene = crate::Scene::from_json(&json.to_string(), "t", &Default::default()).unwrap();
        let bvh = SceneBvh::build(&scene);
        let dirs = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        let mut misses = Vec::new();
        for ox in [-0.9f32, -0.35, 0.0, 0.35, 0.6, 0.9] {
            for oy in [0.01f32, 0.3, 0.6, 1.0, 1.2, 1.9] {
                for oz in [-0.9f32, -0.35, 0.0, 0.3, 0.9] {
                    let o = Vec3::new(ox, oy, oz);
                    for d in dirs {
                        if bvh.intersect(o, d, f32::INFINITY).is_none() {
                            misses.push((o, d));
                        }
                    }
                }
            }
        }
        assert!(
            misses.is_empty(),
            "{} misses, e.g. {:?}",
            misses.len(),
            &misses[..misses.len().min(5)]
        );
    }
}

/// Seconds (median of `runs`) to update the scene's BVH after its last object moved by a few
/// centimetres: a full rebuild ([`SceneBvh::build`]) against [`SceneBvh::refit`]. For the
/// frame benchmark.
pub fn rebuild_vs_refit(scene: &Scene, runs: usize) -> (f64, f64) {
    use std::time::Instant;
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let mut scene = scene.clone();
    let Some(object) = scene.objects.len().checked_sub(1) else {
        return (0.0, 0.0);
    };
    let start = scene.objects[object].transform;
    let moved = {
        let o = &scene.objects[object];
        o.triangles.start as usize..o.triangles.end as usize
    };
    let mut bvh = Some(SceneBvh::build(&scene));
    let (mut rebuild, mut refit) = (Vec::new(), Vec::new());
    for i in 0..runs {
        let transform =
            glam::Mat4::from_translation(Vec3::new(0.01 * (i + 1) as f32, 0.0, 0.0)) * start;
        scene
            .apply(&crate::scene::SceneUpdate::Transform { object, transform })
            .expect("a translation is a valid transform");
        let t = Instant::now();
        let _ = SceneBvh::build(&scene);
        rebuild.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        bvh = bvh.map(|b| b.refit(&scene, std::slice::from_ref(&moved)));
        refit.push(t.elapsed().as_secs_f64());
    }
    (median(rebuild), median(refit))
}
