//! Which kinds of light the direct-light shaders are compiled for: a scene pays only for
//! the lights it has. `common/direct_shade.wgsl` holds every kind's code behind
//! pipeline-overridable constants; a pipeline compiled with one of them false has none of
//! that code. lavapipe pays for code behind branches that no pixel takes (both sides of a
//! per-lane branch run masked; the inlined loops cost registers), so a scene with one point
//! light paid about twice for the sampled lights, the sun's soft shadows and the
//! environment (docs/bench/lights-gpu.md). The pipelines of each variant are compiled on
//! first use ([`VariantCache`]).

use std::collections::HashMap;
use std::sync::Mutex;

/// The kinds of light a direct-light pipeline handles (the overrides of
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
}

impl DirectVariant {
    /// Every kind of light.
    pub const ALL: DirectVariant = DirectVariant {
        sampled: true,
        directional: true,
        background: true,
    };

    /// The pipeline-overridable constants of this variant.
    pub fn constants(&self) -> [(&'static str, f64); 3] {
        let f = |b: bool| if b { 1.0 } else { 0.0 };
        [
            ("SAMPLED_LIGHTS", f(self.sampled)),
            ("DIRECTIONAL_LIGHTS", f(self.directional)),
            ("BACKGROUND", f(self.background)),
        ]
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
        for (name, value) in DirectVariant::ALL.constants() {
            assert!(
                src.contains(&format!("override {name}: bool = true;")),
                "{name}"
            );
            assert_eq!(value, 1.0);
        }
    }

    #[test]
    fn cache_builds_each_variant_once() {
        let cache = VariantCache::<u32>::default();
        let mut builds = 0;
        let none = DirectVariant {
            sampled: false,
            directional: false,
            background: false,
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
