//! A ray's hit turned into a shading point.

use super::Hit;
use crate::bsdf::Material;
use crate::sampling::Frame;
use crate::scene::{surface, Scene};
use glam::{Vec2, Vec3};

/// Geometry and material at a ray hit. The material is the triangle's with its textures
/// looked up at the hit (finest level), black where the ray meets a one-sided material's
/// back ([`Material::seen_from`]); the shading normal includes its normal map.
#[derive(Clone, Copy, Debug)]
pub struct Interaction {
    pub position: Vec3,
    /// Geometric normal (from the winding; outward for closed meshes).
    pub ng: Vec3,
    /// Shading frame (interpolated vertex normal, same side as `ng`).
    pub frame: Frame,
    pub material: Material,
    pub triangle: u32,
    /// Texture coordinates of the hit.
    pub uv: Vec2,
}

impl Interaction {
    pub fn new(scene: &Scene, hit: &Hit, dir: Vec3) -> Self {
        let (position, [ng, ns, front], uv) = Self::surface(scene, hit, dir);
        Interaction {
            position,
            ng,
            frame: Frame::new(ns),
            // Point samples read the finest level (as the bounce maps do); only the eye
            // passes filter by screen footprint.
            material: scene
                .material_at(hit.triangle as usize, uv, 0.0)
                .seen_from(front, dir),
            triangle: hit.triangle,
            uv,
        }
    }

    /// The geometric and shading normals at a hit (those of [`Interaction::new`]) and its
    /// texture coordinates, without the material: for tests that need only the surface's
    /// orientation.
    pub fn normals(scene: &Scene, hit: &Hit, dir: Vec3) -> (Vec3, Vec3, Vec2) {
        let (_, [ng, ns, _], uv) = Self::surface(scene, hit, dir);
        (ng, ns, uv)
    }

    /// The position, the geometric, shading and front normals and the texture coordinates
    /// of a hit. The front normal tells a one-sided material's front as Mitsuba does: the
    /// interpolated vertex normal (before it is turned to `ng`'s side), or `ng` where the
    /// mesh has none.
    fn surface(scene: &Scene, hit: &Hit, dir: Vec3) -> (Vec3, [Vec3; 3], Vec2) {
        let t = hit.triangle as usize;
        let ([p0, p1, p2], [n0, n1, n2]) = scene.corners(t);
        let ng = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        let w = 1.0 - hit.u - hit.v;
        let mut ns = (n0 * w + n1 * hit.u + n2 * hit.v).normalize_or_zero();
        if ns == Vec3::ZERO || !ns.is_finite() {
            ns = ng;
        }
        let front = ns;
        if ns.dot(ng) < 0.0 {
            ns = -ns;
        }
        let uv = scene.uv_at(t, hit.u, hit.v);
        if let Some(i) = scene.maps_of(t).normal {
            if let Some(tangent) = scene.tangent_at(t, hit.u, hit.v) {
                // ns is on the winding's side here, as the tangent frame.
                let texel = scene.texture(i).sample(uv, 0.0).truncate();
                let n = surface::perturb_normal(ns, tangent, texel);
                if n != Vec3::ZERO && n.is_finite() {
                    ns = n;
                }
            }
        }
        // Shading normals must not disagree with the geometry about which side the ray
        // came from, or light leaks; fall back to the geometric normal there.
        if dir.dot(ns) * dir.dot(ng) <= 0.0 {
            ns = ng;
        }
        (p0 * w + p1 * hit.u + p2 * hit.v, [ng, ns, front], uv)
    }

    /// Ray origin for leaving the surface towards `dir` without re-hitting it.
    #[inline]
    pub fn spawn(&self, dir: Vec3) -> Vec3 {
        let eps = 1e-4 * (1.0 + self.position.abs().max_element());
        self.position + self.ng * eps * dir.dot(self.ng).signum()
    }
}
