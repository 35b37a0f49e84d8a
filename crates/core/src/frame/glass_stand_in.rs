//! Rough glass in `bidir`: its rasterized passes and the CPU paths it traces through glass
//! (`bidir::specular_paths`) follow delta lobes only, so it renders Mitsuba's
//! roughdielectric as the smooth glass of the same index and transmittance
//! ([`Material::uber_equivalent`]), on the GPU and on the CPU alike, and says so with a
//! RenderWarning. `path`, `photon` and `gather` render the rough lobes
//! ([`crate::bsdf::rough_dielectric`]); so do `ispm` and `direct`, whose GPU passes see the
//! smooth stand-in (black: no lobe they shade) while their CPU images follow camera paths
//! through the rough lobes (`photon::delta_paths`: `ispm`'s specular image,
//! `direct`'s light met one scattering from the camera) and `ispm`'s photons scatter by them.

use super::options::Method;
use crate::bsdf::Material;
use crate::scene::Scene;

/// Whether `method` renders rough glass by its smooth stand-in.
pub(super) fn stands_in(method: Method) -> bool {
    method == Method::Bidir
}

/// Replaces the rough glass of `scene` by its smooth stand-in where `method` needs it
/// ([`stands_in`]); returns the names of the materials replaced.
pub(super) fn replace(scene: &mut Scene, method: Method) -> Vec<String> {
    if !stands_in(method) {
        return Vec::new();
    }
    let mut names = Vec::new();
    for (m, name) in scene.materials.iter_mut().zip(&scene.material_names) {
        if m.rough_glass {
            *m = Material::uber_equivalent(m);
            names.push(name.clone());
        }
    }
    names
}

/// The RenderWarning naming the materials [`replace`] replaced, if any.
pub(super) fn warning(method: &str, names: &[String]) -> Option<String> {
    (!names.is_empty()).then(|| {
        format!(
            "method `{method}` renders the rough glass (roughdielectric) of materials {} as \
             smooth glass of the same index and transmittance; `path`, `photon`, `gather`, \
             `ispm` and `direct` render its rough reflection and transmission",
            names.join(", ")
        )
    })
}

/// The RenderWarning of `ispm` for thin glass (Mitsuba's thindielectric) under a point or
/// spot light: its GPU bounce maps take those lights' photons' first scatter on the uber
/// stand-in ([`Material::uber_equivalent`]: glass of index 1, straight through without the
/// slab's reflection); every other pass traces the thin slab itself on the CPU.
pub(super) fn thin_warning(scene: &Scene, method: Method) -> Option<String> {
    let local = scene.lights.iter().any(|l| l.is_local());
    let names: Vec<&str> = scene
        .materials
        .iter()
        .zip(&scene.material_names)
        .filter(|(m, _)| m.thin.is_some())
        .map(|(_, n)| n.as_str())
        .collect();
    (method == Method::Ispm && local && !names.is_empty()).then(|| {
        format!(
            "method `ispm` scatters the photons of point and spot lights that first meet the \
             thin glass (thindielectric) of materials {} straight through it without its \
             reflection (its GPU bounce maps); its other passes and every other method trace \
             the thin slab exactly",
            names.join(", ")
        )
    })
}
