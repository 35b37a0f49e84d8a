//! Mitsuba's exact material models in the deferred direct light (issue 42): one
//! [`ModelMaterialRaw`] per scene material, bound beside the G-buffer (group 1, binding 5 of
//! the direct passes; `shaders/common/exact_models.wgsl`), which holds each sample's material
//! index + 1 in its emission target's `w`.
//!
//! A record is the exact model's where [`shades_exactly`] says so; elsewhere it is zeroed
//! (flags 0), and the direct light shades the uber parameters of the G-buffer as before.
//!
//! A diffuse texture does not stand in the way: the G-buffer (and an RSM, a VPL record)
//! holds the uber stand-in's diffuse albedo times the texel, and the record the untextured
//! stand-in's ([`ModelMaterialRaw::stand_in_diffuse`]), whose ratio is the texel
//! ([`textured_model`]; `model_textured` in WGSL).

use crate::bsdf::Material;
use crate::gpu::raw::{model_flags, ModelMaterialRaw};
use crate::scene::{MaterialMaps, Scene};
use bytemuck::Zeroable;
use glam::Vec3;

/// Whether the direct light shades material `m` (maps `maps`) by its exact model: one of
/// Mitsuba's models the uber BSDF does not render (a coating, a conductor of complex index,
/// Beckmann's distribution), opaque, with no specular or roughness texture (the record
/// holds one value per material; the G-buffer's textured values are the uber stand-in's).
/// Diffuse, normal, alpha and emission maps do not stand in the way (a diffuse texel is
/// recovered per sample: [`textured_model`]).
pub fn shades_exactly(m: &Material, maps: &MaterialMaps) -> bool {
    let textured = maps.specular.is_some() || maps.roughness.is_some();
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
            let maps = maps.get(i).unwrap_or(&none);
            if shades_exactly(m, maps) {
                let mut raw = m.to_model_raw();
                if maps.diffuse.is_some() {
                    raw.flags |= model_flags::TEX_DIFFUSE;
                    raw.stand_in_diffuse = m.uber_equivalent().diffuse.into();
                }
                raw
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

/// The texel a diffuse map applied to a sample whose uber stand-in has diffuse albedo
/// `sample_diffuse`, where `stand_in` is the untextured stand-in's: their ratio per channel
/// (0 where the stand-in's is 0).
fn texel(sample_diffuse: Vec3, stand_in: Vec3) -> Vec3 {
    Vec3::select(
        stand_in.cmpgt(Vec3::ZERO),
        sample_diffuse / stand_in.max(Vec3::splat(1e-30)),
        Vec3::ZERO,
    )
}

/// Material `m` (a scene material shaded exactly, maps `maps`) at a sample whose uber
/// stand-in has diffuse albedo `sample_diffuse` (a G-buffer's): with a diffuse map, its ρ
/// times the texel that sample holds (`model_textured` in `models.wgsl`), else `m`.
pub fn textured_model(m: &Material, maps: &MaterialMaps, sample_diffuse: Vec3) -> Material {
    let mut out = *m;
    if maps.diffuse.is_some() {
        out.diffuse = m.diffuse * texel(sample_diffuse, m.uber_equivalent().diffuse);
    }
    out
}

/// The uber stand-in a `bidir` VPL record carries for material `met` (as a ray met it,
/// textures applied) whose exact model is record `model` ([`model_of`]: index + 1):
/// `met`'s own ([`Material::uber_equivalent`]) but that a diffuse texture multiplies the
/// untextured stand-in's diffuse albedo, as on the G-buffer and the RSMs, so that the
/// shader gives the texel back ([`textured_model`]).
pub fn record_stand_in(scene: &Scene, model: u32, met: &Material) -> Material {
    let i = model as usize;
    if i == 0 || i > scene.materials.len() {
        return met.uber_equivalent();
    }
    let none = MaterialMaps::default();
    let maps = scene.material_maps.get(i - 1).unwrap_or(&none);
    stand_in_of(&scene.materials[i - 1], maps, met)
}

/// [`record_stand_in`] of `met`, material `base` (maps `maps`) as a ray met it.
fn stand_in_of(base: &Material, maps: &MaterialMaps, met: &Material) -> Material {
    let mut uber = met.uber_equivalent();
    if maps.diffuse.is_some() {
        uber.diffuse = base.uber_equivalent().diffuse * texel(met.diffuse, base.diffuse);
    }
    uber
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

#[cfg(test)]
mod textured_tests {
    use super::*;
    use crate::bsdf::{Coating, Distribution};

    /// A nonlinear rough plastic of diffuse factor 1 (the importer's for a bitmap
    /// `diffuse_reflectance`): its stand-in's albedo is clamped to 1, which the texel's
    /// recovery must not mind (the G-buffer multiplies the clamped albedo).
    fn plastic() -> Material {
        Material {
            diffuse: Vec3::ONE,
            specular: Vec3::ONE,
            roughness: 0.3,
            coating: Some(Coating::new(1.49, true, 0.09, Distribution::Ggx)),
            ..Material::default()
        }
    }

    #[test]
    fn diffuse_maps_are_shaded_exactly_with_the_texel_recovered() {
        let m = plastic();
        let maps = MaterialMaps {
            diffuse: Some(0),
            ..MaterialMaps::default()
        };
        assert!(shades_exactly(&m, &maps));
        let raw = records_of(&[m], &[maps])[0];
        assert_ne!(raw.flags & model_flags::TEX_DIFFUSE, 0);
        let stand_in = m.uber_equivalent().diffuse;
        assert_eq!(Vec3::from(raw.stand_in_diffuse), stand_in);
        assert_eq!(records_of(&[m], &[])[0].flags & model_flags::TEX_DIFFUSE, 0);
        for texel in [Vec3::new(0.9, 0.2, 0.05), Vec3::new(0.0, 0.5, 1.0)] {
            // The G-buffer's albedo: the stand-in's times the texel (`textured_material`).
            let exact = textured_model(&m, &maps, stand_in * texel);
            assert!((exact.diffuse - m.diffuse * texel).abs().max_element() < 1e-6);
            // The CPU's VPL records hold the same as the G-buffer.
            let met = Material {
                diffuse: m.diffuse * texel,
                ..m
            };
            let rec = stand_in_of(&m, &maps, &met);
            assert!((rec.diffuse - stand_in * texel).abs().max_element() < 1e-6);
            assert_eq!(rec.specular, met.uber_equivalent().specular);
            // Not the textured material's own stand-in (a nonlinear base is not linear).
            assert!(
                (met.uber_equivalent().diffuse - rec.diffuse)
                    .abs()
                    .max_element()
                    > 0.01
            );
            let plain = stand_in_of(&m, &MaterialMaps::default(), &met);
            assert_eq!(plain, met.uber_equivalent());
        }
        let rough_map = MaterialMaps {
            roughness: Some(0),
            ..maps
        };
        assert!(!shades_exactly(&m, &rough_map));
    }
}
