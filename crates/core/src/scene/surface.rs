//! Textured materials: which textures a material reads ([`MaterialMaps`]) and the material,
//! shading normal and coverage at a point of a triangle, as every CPU method evaluates them.
//! The GPU passes do the same in `shaders/common/texture.wgsl`.

use super::desc::TextureRefs;
use super::Scene;
use crate::bsdf::Material;
use crate::texture::Texture;
use glam::{Vec2, Vec3, Vec4, Vec4Swizzles};
use std::collections::HashMap;
use std::sync::Arc;

/// Default coverage threshold of an alpha-masked material (glTF's `alphaCutoff`).
pub const DEFAULT_ALPHA_CUTOFF: f32 = 0.5;

/// The textures of one material, as indices into `Scene::textures`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MaterialMaps {
    /// RGB multiplies diffuse and transmission.
    pub diffuse: Option<u32>,
    /// RGB multiplies specular.
    pub specular: Option<u32>,
    /// G multiplies roughness.
    pub roughness: Option<u32>,
    /// Tangent-space normal map.
    pub normal: Option<u32>,
    /// Alpha is the coverage; cut out below `alpha_cutoff`.
    pub alpha: Option<u32>,
    pub alpha_cutoff: f32,
    /// RGB multiplies the emitted radiance.
    pub emission: Option<u32>,
}

impl MaterialMaps {
    pub fn is_empty(&self) -> bool {
        *self == MaterialMaps::default()
    }

    /// Resolves the names of a description against the scene's textures.
    pub(crate) fn resolve(
        refs: &TextureRefs,
        index: &HashMap<String, u32>,
    ) -> std::result::Result<MaterialMaps, (String, String)> {
        let find = |field: &str, name: &Option<String>| -> Result<Option<u32>, (String, String)> {
            match name {
                None => Ok(None),
                Some(n) => index.get(n).copied().map(Some).ok_or_else(|| {
                    let mut loaded: Vec<&str> = index.keys().map(String::as_str).collect();
                    loaded.sort_unstable();
                    let loaded = if loaded.is_empty() {
                        "none".to_string()
                    } else {
                        loaded.join(", ")
                    };
                    (
                        field.to_string(),
                        format!("no texture named `{n}` was loaded (loaded: {loaded})"),
                    )
                }),
            }
        };
        let diffuse = find("diffuse_texture", &refs.diffuse)?;
        let mut alpha = find("alpha_texture", &refs.alpha)?;
        let mut alpha_cutoff = 0.0;
        if let Some(c) = refs.alpha_cutoff {
            if !(0.0..=1.0).contains(&c) {
                return Err(("alpha_cutoff".into(), "must be in [0, 1]".into()));
            }
            alpha_cutoff = c;
            alpha = alpha.or(diffuse);
            if alpha.is_none() {
                return Err((
                    "alpha_cutoff".into(),
                    "needs an alpha_texture or a diffuse_texture".into(),
                ));
            }
        } else if alpha.is_some() {
            alpha_cutoff = DEFAULT_ALPHA_CUTOFF;
        }
        Ok(MaterialMaps {
            diffuse,
            specular: find("specular_texture", &refs.specular)?,
            roughness: find("roughness_texture", &refs.roughness)?,
            normal: find("normal_texture", &refs.normal)?,
            alpha,
            alpha_cutoff,
            emission: find("emission_texture", &refs.emission)?,
        })
    }

    /// The names back (for `Scene::material_desc`).
    pub(crate) fn refs(&self, names: &[String]) -> TextureRefs {
        let name = |i: Option<u32>| i.map(|i| names[i as usize].clone());
        TextureRefs {
            diffuse: name(self.diffuse),
            specular: name(self.specular),
            roughness: name(self.roughness),
            normal: name(self.normal),
            alpha: name(self.alpha),
            alpha_cutoff: self.alpha.map(|_| self.alpha_cutoff),
            emission: name(self.emission),
        }
    }
}

/// Unit tangent (xyz, along +u) and handedness (w: the bitangent, along +v, is
/// `w · n × t`) of a triangle from its corners and their UVs; `None` where the UVs are
/// degenerate. Shared by the CPU shading and the GPU vertex data.
pub fn triangle_tangent(p: [Vec3; 3], uv: [Vec2; 3]) -> Option<Vec4> {
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
    let det = d1.x * d2.y - d2.x * d1.y;
    if det.abs() <= 1e-20 || det.is_nan() {
        return None;
    }
    let t = (e1 * d2.y - e2 * d1.y) / det;
    let b = (e2 * d1.x - e1 * d2.x) / det;
    let n = e1.cross(e2);
    let t = t.try_normalize()?;
    let w = if n.cross(t).dot(b) < 0.0 { -1.0 } else { 1.0 };
    Some(t.extend(w))
}

/// The shading normal with a tangent-space normal map texel `texel` (RGB in [0, 1]) applied:
/// tangent `tangent` orthogonalized against `ns`. Shared by CPU shading and the WGSL port.
pub fn perturb_normal(ns: Vec3, tangent: Vec4, texel: Vec3) -> Vec3 {
    let m = texel * 2.0 - Vec3::ONE;
    let t = (tangent.xyz() - ns * ns.dot(tangent.xyz())).normalize_or_zero();
    if t == Vec3::ZERO {
        return ns;
    }
    let b = ns.cross(t) * tangent.w;
    // Texture rows run down (+v), the map's +y points up: the bitangent of +y is -b.
    (t * m.x - b * m.y + ns * m.z).normalize_or_zero()
}

impl Scene {
    /// Texture coordinates at barycentrics (u, v) of triangle `t` (relative to corners 1, 2).
    pub fn uv_at(&self, t: usize, u: f32, v: f32) -> Vec2 {
        let c = self.corner_uvs(t);
        c[0] * (1.0 - u - v) + c[1] * u + c[2] * v
    }

    pub fn texture(&self, i: u32) -> &Texture {
        &self.textures[i as usize]
    }

    /// The textures of triangle `t`'s material.
    pub fn maps_of(&self, t: usize) -> &MaterialMaps {
        &self.material_maps[self.triangle_material(t) as usize]
    }

    /// Triangle `t`'s material at texture coordinates `uv` (level of detail `lod`).
    pub fn material_at(&self, t: usize, uv: Vec2, lod: f32) -> Material {
        let mut m = *self.material_of(t);
        let maps = self.maps_of(t);
        if let Some(i) = maps.diffuse {
            let c = self.texture(i).sample(uv, lod).xyz();
            m.diffuse *= c;
            m.transmission *= c;
        }
        if let Some(i) = maps.specular {
            m.specular *= self.texture(i).sample(uv, lod).xyz();
        }
        if let Some(i) = maps.emission {
            m.emission *= self.texture(i).sample(uv, lod).xyz();
        }
        if let Some(i) = maps.roughness {
            // A map never turns a glossy lobe into a mirror (a delta lobe the scene-level
            // checks, e.g. whether to light-trace caustics, would not know of).
            let glossy = !m.is_mirror();
            m.roughness *= self.texture(i).sample(uv, lod).y;
            if glossy {
                m.roughness = m.roughness.max(crate::bsdf::MIRROR_ROUGHNESS);
            }
        }
        m
    }

    /// Whether the hit at barycentrics (u, v) of triangle `t` is cut out by its material's
    /// alpha mask (coverage below the cutoff, finest level).
    pub fn cut_out(&self, t: usize, u: f32, v: f32) -> bool {
        let maps = self.maps_of(t);
        match maps.alpha {
            Some(i) => self.texture(i).sample(self.uv_at(t, u, v), 0.0).w < maps.alpha_cutoff,
            None => false,
        }
    }

    /// Length of the diagonal of the scene's bounding box (m); 1 for a scene without
    /// vertices.
    pub fn diagonal(&self) -> f32 {
        let (lo, hi) = self.vertex_box();
        if lo.x > hi.x {
            return 1.0;
        }
        (hi - lo).length()
    }

    /// Whether any material has a delta lobe (perfect mirrors, smooth glass).
    pub fn has_delta_materials(&self) -> bool {
        self.materials
            .iter()
            .any(crate::bsdf::Material::has_delta_lobe)
    }

    /// Whether any material is traced through on the CPU by the GPU methods' specular
    /// paths ([`crate::bsdf::Material::is_specular_traced`]: delta lobes, rough glass).
    pub fn has_specular_traced(&self) -> bool {
        self.materials
            .iter()
            .any(crate::bsdf::Material::is_specular_traced)
    }

    /// Whether any material is alpha-masked.
    pub fn has_alpha_masks(&self) -> bool {
        self.material_maps.iter().any(|m| m.alpha.is_some())
    }

    /// Tangent frame of triangle `t` for normal mapping.
    pub fn tangent_of(&self, t: usize) -> Option<Vec4> {
        triangle_tangent(self.triangle(t), self.corner_uvs(t))
    }

    /// The scene's textures keyed by name, for resolving descriptions.
    pub(crate) fn texture_index(&self) -> HashMap<String, u32> {
        self.texture_names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.clone(), i as u32))
            .collect()
    }
}

/// Textures passed with a description, keyed by the names materials use.
pub type TextureMap = HashMap<String, Arc<Texture>>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tangent_follows_u_and_handedness_follows_v() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let t = triangle_tangent(p, [Vec2::ZERO, Vec2::X, Vec2::Y]).unwrap();
        assert!((t - Vec4::new(1.0, 0.0, 0.0, 1.0)).length() < 1e-6);
        // v running the other way flips the handedness.
        let t = triangle_tangent(p, [Vec2::ZERO, Vec2::X, -Vec2::Y]).unwrap();
        assert!((t - Vec4::new(1.0, 0.0, 0.0, -1.0)).length() < 1e-6);
        assert!(triangle_tangent(p, [Vec2::ZERO; 3]).is_none());
    }

    #[test]
    fn flat_normal_map_keeps_the_normal() {
        let ns = Vec3::new(0.0, 0.0, 1.0);
        let tan = Vec4::new(1.0, 0.0, 0.0, 1.0);
        let n = perturb_normal(ns, tan, Vec3::new(0.5, 0.5, 1.0));
        assert!((n - ns).length() < 1e-6);
        // +x in the map tilts towards the tangent; +y towards -v (here -y).
        let n = perturb_normal(ns, tan, Vec3::new(1.0, 0.5, 0.5));
        assert!((n - Vec3::X).length() < 1e-6, "{n}");
        let n = perturb_normal(ns, tan, Vec3::new(0.5, 1.0, 0.5));
        assert!((n + Vec3::Y).length() < 1e-6, "{n}");
    }
}

#[cfg(test)]
mod scene_tests {
    use super::*;
    use crate::trace::{Interaction, SceneBvh};

    /// A quad with a normal map tilting normals 30° towards +u (+x): the CPU hit's shading
    /// normal follows it.
    #[test]
    fn normal_map_tilts_the_hit_normal() {
        let tilt = 30f32.to_radians();
        let texel = [tilt.sin() * 0.5 + 0.5, 0.5, tilt.cos() * 0.5 + 0.5, 1.0];
        let tex = Texture::new(1, 1, &texel).unwrap();
        let json = serde_json::json!({
            "camera": {"position": [0, 2, 0.1], "look_at": [0, 0, 0]},
            "materials": {"m": {"normal_texture": "n"}},
            "objects": [{"shape": {"type": "quad", "size": [2, 2]}, "material": "m"}],
        });
        let textures: TextureMap = [("n".to_string(), Arc::new(tex))].into_iter().collect();
        let scene =
            Scene::from_json_textured(&json.to_string(), "t", &HashMap::new(), &textures).unwrap();
        let bvh = SceneBvh::build(&scene);
        let dir = Vec3::NEG_Y;
        let hit = bvh.intersect(Vec3::new(0.1, 1.0, 0.2), dir, 10.0).unwrap();
        let it = Interaction::new(&scene, &hit, dir);
        let want = Vec3::new(tilt.sin(), tilt.cos(), 0.0);
        assert!((it.frame.n - want).length() < 2e-3, "{}", it.frame.n);
    }

    /// Maps multiply their factors; a black roughness map keeps a glossy lobe glossy.
    #[test]
    fn maps_multiply_and_roughness_stays_glossy() {
        let tex = Texture::new(1, 1, &[0.5, 0.25, 0.0, 1.0]).unwrap();
        let json = serde_json::json!({
            "camera": {"position": [0, 2, 0.1], "look_at": [0, 0, 0]},
            "materials": {"m": {"diffuse": [0.8, 0.8, 0.8], "specular": [1, 1, 1],
                                "roughness": 0.5, "diffuse_texture": "t",
                                "specular_texture": "t", "roughness_texture": "black"}},
            "objects": [{"shape": {"type": "quad", "size": [2, 2]}, "material": "m"}],
        });
        let black = Texture::new(1, 1, &[0.0, 0.0, 0.0, 1.0]).unwrap();
        let textures: TextureMap = [
            ("t".to_string(), Arc::new(tex)),
            ("black".to_string(), Arc::new(black)),
        ]
        .into_iter()
        .collect();
        let scene =
            Scene::from_json_textured(&json.to_string(), "t", &HashMap::new(), &textures).unwrap();
        let m = scene.material_at(0, Vec2::splat(0.5), 0.0);
        assert_eq!(m.diffuse, Vec3::new(0.4, 0.2, 0.0));
        assert_eq!(m.specular, Vec3::new(0.5, 0.25, 0.0));
        assert_eq!(m.roughness, crate::bsdf::MIRROR_ROUGHNESS);
        assert!(!m.is_mirror());
        // The description round-trips with its texture names.
        let desc = scene.material_desc("m").unwrap();
        assert_eq!(desc.roughness_texture.as_deref(), Some("black"));
        assert_eq!(desc.alpha_texture, None);
    }
}
