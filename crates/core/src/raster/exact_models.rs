//! Mitsuba's exact material models in the deferred direct light (issue 42): one
//! [`ModelMaterialRaw`] per scene material, bound beside the G-buffer (group 1, binding 5 of
//! the direct passes; `shaders/common/exact_models.wgsl`), which holds each sample's material
//! index + 1 in its emission target's `w`.
//!
//! A record is the exact model's where [`shades_exactly`] says so; elsewhere it is zeroed
//! (flags 0), and the direct light shades the uber parameters of the G-buffer as before.

use crate::bsdf::Material;
use crate::gpu::raw::ModelMaterialRaw;
use crate::scene::{MaterialMaps, Scene};
use bytemuck::Zeroable;

/// Whether the direct light shades material `m` (maps `maps`) by its exact model: one of
/// Mitsuba's models the uber BSDF does not render (a coating, a conductor of complex index,
/// Beckmann's distribution), opaque, with no texture varying its BSDF's parameters (the
/// record holds one value per material; the G-buffer's textured values are the uber
/// stand-in's). Normal, alpha and emission maps do not stand in the way.
pub fn shades_exactly(m: &Material, maps: &MaterialMaps) -> bool {
    let textured = maps.diffuse.is_some() || maps.specular.is_some() || maps.roughness.is_some();
    m.uber_equivalent() != *m && !m.rough_glass && m.transmission == glam::Vec3::ZERO && !textured
}

/// The records of `scene`'s materials, in order ([`records_of`]).
pub fn records(scene: &Scene) -> Vec<ModelMaterialRaw> {
    records_of(&scene.materials, &scene.material_maps)
}

/// The records of `materials` (maps `maps`, by index): [`Material::to_model_raw`] where
/// [`shades_exactly`], zeroed elsewhere (at least one record: a storage buffer is never
/// empty).
pub fn records_of(materials: &[Material], maps: &[MaterialMaps]) -> Vec<ModelMaterialRaw> {
    let none = MaterialMaps::default();
    let mut out: Vec<ModelMaterialRaw> = materials
        .iter()
        .enumerate()
        .map(|(i, m)| {
            if shades_exactly(m, maps.get(i).unwrap_or(&none)) {
                m.to_model_raw()
            } else {
                ModelMaterialRaw::zeroed()
            }
        })
        .collect();
    if out.is_empty() {
        out.push(ModelMaterialRaw::zeroed());
    }
    out
}

/// The record index + 1 of the material of `scene`'s `triangle` where it is shaded exactly
/// ([`shades_exactly`]), 0 where its uber parameters are shaded: `bidir`'s VPL records
/// carry it ([`material_word`]; `shaders/bidir_models.wgsl`). `met` is the material as a
/// ray met it (`trace::Interaction::material`): a one-sided material's black back
/// ([`Material::seen_from`]) is shaded by its (zero) uber parameters.
pub fn model_of(scene: &Scene, triangle: u32, met: &Material) -> u32 {
    let i = scene.triangle_material(triangle as usize) as usize;
    let none = MaterialMaps::default();
    let maps = scene.material_maps.get(i).unwrap_or(&none);
    if i < scene.materials.len() && shades_exactly(met, maps) {
        i as u32 + 1
    } else {
        0
    }
}

/// A `bidir` VPL record's material word ([`crate::raster::vpl::VplRaw::fresnel`]): the
/// uber parameters' Fresnel flag in bit 0, the exact model's record index + 1 ([`model_of`])
/// above it.
pub fn material_word(fresnel: bool, model: u32) -> u32 {
    fresnel as u32 | (model << 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::{Conductor, Distribution};
    use glam::Vec3;

    fn plain() -> Material {
        Material {
            diffuse: Vec3::splat(0.5),
            ..Material::default()
        }
    }

    #[test]
    fn uber_materials_keep_a_zeroed_record() {
        let m = plain();
        assert!(!shades_exactly(&m, &MaterialMaps::default()));
        assert_eq!(records_of(&[m], &[])[0].flags, 0);
        assert_eq!(records_of(&[], &[]).len(), 1);
    }

    #[test]
    fn mitsuba_models_are_shaded_exactly_unless_textured() {
        let beckmann = Material {
            specular: Vec3::ONE,
            roughness: 0.4,
            distribution: Distribution::Beckmann,
            ..plain()
        };
        let gold = Material {
            diffuse: Vec3::ZERO,
            specular: Vec3::ONE,
            roughness: 0.3,
            conductor: Some(Conductor::new(
                Vec3::new(0.14, 0.42, 1.4),
                Vec3::new(3.9, 2.4, 1.9),
            )),
            ..Material::default()
        };
        for m in [beckmann, gold] {
            assert!(shades_exactly(&m, &MaterialMaps::default()));
            assert_eq!(records_of(&[m], &[])[0].flags, m.to_model_raw().flags);
            let textured = MaterialMaps {
                roughness: Some(0),
                ..MaterialMaps::default()
            };
            assert!(!shades_exactly(&m, &textured));
            let normal_mapped = MaterialMaps {
                normal: Some(0),
                ..MaterialMaps::default()
            };
            assert!(shades_exactly(&m, &normal_mapped));
        }
    }
}
