//! Which kinds of light and material the direct-light shaders are compiled for: a scene
//! pays only for what it has. `common/direct_shade.wgsl` holds every kind's code behind
//! pipeline-overridable constants; a pipeline compiled with one of them false has none of
//! that code. lavapipe pays for code behind branches that no pixel takes (both sides of a
//! per-lane branch run masked; the inlined loops cost registers), so a scene with one point
//! light paid about twice for the sampled lights, the sun's soft shadows and the
//! environment (docs/bench/lights-gpu.md). The pipelines of each variant are compiled on
//! first use and kept for the device ([`VariantCache`]: 20–360 ms a pipeline on lavapipe,
//! once).
//!
//! A feature of the direct shading plugs in by four lines, so that scenes without it pay
//! nothing for it:
//! 1. an `override NAME: bool = true;` in `direct_shade.wgsl` (true: the default, every
//!    pass that does not specialize compiles everything), and `if NAME { … }` (or
//!    `NAME && …` in a condition) around the feature's code;
//! 2. a field of [`DirectVariant`] (true in [`DirectVariant::ALL`]);
//! 3. its entry in [`DirectVariant::constants`] (the tests check that every override of
//!    the shader has one, and each entry an override);
//! 4. where the frame decides it from the scene (`GpuScene::direct_variant`, or
//!    [`MaterialKinds`] for a property of the materials): true whenever any pixel may
//!    need the code, since a kind left out is never evaluated.

use std::collections::HashMap;
use std::sync::Mutex;

use crate::gpu::raw::{MaterialRaw, ModelMaterialRaw};

/// The kinds of light and material a direct-light pipeline handles (the overrides of
/// `direct_shade.wgsl`). A variant must cover the scene it shades: a kind left out is
/// never evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DirectVariant {
    /// Points drawn on the emitters or directions drawn from the sky (`SAMPLED_LIGHTS`).
    pub sampled: bool,
    /// Directional lights (`DIRECTIONAL_LIGHTS`).
    pub directional: bool,
    /// The environment behind uncovered samples (`BACKGROUND`).
    pub background: bool,
    /// Emitting surfaces: the G-buffer's emission read (`EMISSION`).
    pub emission: bool,
    /// Specular lobes or Fresnel-weighted diffuse lobes (`GLOSSY`): without, Lambert's
    /// lobe alone.
    pub glossy: bool,
    /// The polygon groups' glossy lobe by linearly transformed cosines (`LTC_LIGHTS`): some
    /// polygon group and some glossy material.
    pub ltc: bool,
    /// Round emitters (spheres) among the polygon groups (`ROUND_LIGHTS`).
    pub round: bool,
}

impl DirectVariant {
    /// Every kind of light and material.
    pub const ALL: DirectVariant = DirectVariant {
        sampled: true,
        directional: true,
        background: true,
        emission: true,
        glossy: true,
        ltc: true,
        round: true,
    };

    /// The pipeline-overridable constants of this variant.
    pub fn constants(&self) -> [(&'static str, f64); 7] {
        let f = |b: bool| if b { 1.0 } else { 0.0 };
        [
            ("SAMPLED_LIGHTS", f(self.sampled)),
            ("DIRECTIONAL_LIGHTS", f(self.directional)),
            ("BACKGROUND", f(self.background)),
            ("EMISSION", f(self.emission)),
            ("GLOSSY", f(self.glossy)),
            ("LTC_LIGHTS", f(self.ltc)),
            ("ROUND_LIGHTS", f(self.round)),
        ]
    }
}

/// What the scene's materials need of the direct shading (their GPU records, the uber
/// parameters: textures only scale a specular colour or an emission that the record has).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaterialKinds {
    /// Some material emits.
    pub emission: bool,
    /// Some material has a specular colour or a Fresnel flag.
    pub glossy: bool,
}

impl MaterialKinds {
    /// The kinds of `materials` with their exact-model records `models`
    /// (`raster::exact_models`): a material shaded by its exact model needs the emission
    /// read (the G-buffer's `emission.w` holds its index) and the glossy code (its model's
    /// lobes).
    pub fn of(materials: &[MaterialRaw], models: &[ModelMaterialRaw]) -> MaterialKinds {
        let any = |v: [f32; 3]| v.iter().any(|&c| c != 0.0);
        let exact = models.iter().any(|r| r.flags != 0);
        MaterialKinds {
            emission: exact || materials.iter().any(|m| any(m.emission)),
            glossy: exact || materials.iter().any(|m| any(m.specular) || m.fresnel != 0),
        }
    }
}

/// Whether any of the lights is directional (kind 2).
pub fn any_directional(lights: &[crate::gpu::raw::LightRaw]) -> bool {
    lights.iter().any(|l| l.kind == 2)
}

/// Pipelines per variant, each compiled when first asked for.
pub struct VariantCache<T: Clone> {
    built: Mutex<HashMap<DirectVariant, T>>,
}

impl<T: Clone> Default for VariantCache<T> {
    fn default() -> Self {
        VariantCache {
            built: Mutex::new(HashMap::new()),
        }
    }
}

impl<T: Clone> VariantCache<T> {
    /// The pipelines of `variant`, built by `build` the first time.
    pub fn get(&self, variant: DirectVariant, build: impl FnOnce(DirectVariant) -> T) -> T {
        let mut built = self.built.lock().unwrap_or_else(|e| e.into_inner());
        built
            .entry(variant)
            .or_insert_with(|| build(variant))
            .clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constants_name_every_override_of_the_shader() {
        let src = super::super::wgsl::DIRECT_SHADE;
        let names: Vec<_> = DirectVariant::ALL.constants().map(|(n, _)| n).to_vec();
        for (name, value) in DirectVariant::ALL.constants() {
            assert!(
                src.contains(&format!("override {name}: bool = true;")),
                "{name}"
            );
            assert_eq!(value, 1.0);
        }
        // And every override of the shaders that the variants compile has its constant.
        for src in super::super::wgsl::DIRECT_SHADING {
            for line in src.lines().filter(|l| l.starts_with("override ")) {
                let name = line["override ".len()..].split(':').next().unwrap_or("");
                assert!(names.contains(&name), "{name} has no DirectVariant field");
            }
        }
    }

    #[test]
    fn material_kinds_see_emission_specular_and_fresnel() {
        let lambert = MaterialRaw {
            diffuse: [0.5; 3],
            ..bytemuck::Zeroable::zeroed()
        };
        let none = MaterialKinds::of(&[lambert], &[bytemuck::Zeroable::zeroed()]);
        assert!(!none.emission && !none.glossy);
        let mut fresnel = lambert;
        fresnel.fresnel = 1;
        let mut shiny = lambert;
        shiny.specular = [0.0, 0.0, 0.04];
        let mut lamp = lambert;
        lamp.emission = [0.0, 2.0, 0.0];
        for (m, emission, glossy) in [
            (fresnel, false, true),
            (shiny, false, true),
            (lamp, true, false),
        ] {
            assert_eq!(
                MaterialKinds::of(&[lambert, m], &[bytemuck::Zeroable::zeroed()]),
                MaterialKinds { emission, glossy }
            );
        }
        // A material shaded by its exact model: its index is in the emission read, its
        // lobes in the glossy code.
        let mut exact: ModelMaterialRaw = bytemuck::Zeroable::zeroed();
        exact.flags = 1;
        assert_eq!(
            MaterialKinds::of(&[lambert], &[exact]),
            MaterialKinds {
                emission: true,
                glossy: true
            }
        );
    }

    #[test]
    fn cache_builds_each_variant_once() {
        let cache = VariantCache::<u32>::default();
        let mut builds = 0;
        let none = DirectVariant {
            sampled: false,
            directional: false,
            background: false,
            emission: false,
            glossy: false,
            ltc: false,
            round: false,
        };
        for v in [DirectVariant::ALL, none, DirectVariant::ALL] {
            cache.get(v, |_| {
                builds += 1;
                builds
            });
        }
        assert_eq!(builds, 2);
        assert_eq!(cache.get(none, |_| 99), 2);
    }
}
