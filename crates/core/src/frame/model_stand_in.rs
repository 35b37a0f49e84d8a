//! The RenderWarning of the GPU methods (`direct`, `ispm`, `bidir`) for Mitsuba's material
//! models (coatings, conductors of complex index, Beckmann's distribution). Their direct
//! light and `ispm`'s photon estimates and rasterized first bounce shade the exact models
//! (`raster::exact_models`, a diffuse texture's texel included) unless a specular or
//! roughness texture varies the BSDF's parameters, and so do `bidir`'s pixels, VPLs and
//! ray bundles' hits (`bidir_models.wgsl`); those
//! are shaded as the uber stand-in ([`crate::bsdf::Material::uber_equivalent`]), and said
//! so.

use super::Method;
use crate::raster::exact_models::shades_exactly;
use crate::scene::{MaterialMaps, Scene};

/// The warning for `method` on `scene`, if any of its materials is approximated.
pub(super) fn warning(scene: &Scene, method: Method) -> Option<String> {
    if !method.uses_gpu() {
        return None;
    }
    let none = MaterialMaps::default();
    let mut textured = Vec::new();
    for (i, (m, name)) in scene
        .materials
        .iter()
        .zip(&scene.material_names)
        .enumerate()
    {
        // Rough glass is `glass_stand_in`'s: `bidir` replaces it (and says so), `ispm` and
        // `direct` render its lobes (their CPU images; `ispm`'s photons).
        // Thin glass likewise (`glass_stand_in::thin_warning`).
        if m.uber_equivalent() == *m || m.rough_glass || m.thin.is_some() {
            continue;
        }
        if !shades_exactly(m, scene.material_maps.get(i).unwrap_or(&none)) {
            textured.push(name.as_str());
        }
    }
    if textured.is_empty() {
        return None;
    }
    Some(format!(
        "method `{}` shades the Mitsuba models of materials {} (a specular or roughness texture \
         varies their BSDF's parameters) as uber stand-ins (Schlick's Fresnel for coatings and conductors, GGX for \
         Beckmann; docs/scene-format.md); `path`, `photon` and `gather` render them exactly",
        method.name(),
        textured.join(", ")
    ))
}
