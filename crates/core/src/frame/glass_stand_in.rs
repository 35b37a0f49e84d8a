//! Rough glass in the GPU methods (`direct`, `ispm`, `bidir`): their rasterized passes and
//! the CPU paths they trace through glass (`photon::delta_paths`, `bidir::specular_paths`)
//! follow delta lobes only, so they render Mitsuba's roughdielectric as the smooth glass of
//! the same index and transmittance ([`Material::uber_equivalent`]), on the GPU and on the
//! CPU alike, and say so with a RenderWarning. `path`, `photon` and `gather` render the
//! rough lobes ([`crate::bsdf::rough_dielectric`]).

use crate::bsdf::Material;
use crate::scene::Scene;

/// Replaces the rough glass of `scene` by its smooth stand-in when `gpu` (the method is a
/// GPU one); returns the names of the materials replaced.
pub(super) fn replace(scene: &mut Scene, gpu: bool) -> Vec<String> {
    if !gpu {
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
             smooth glass of the same index and transmittance; `path`, `photon` and `gather` \
             render its rough reflection and transmission",
            names.join(", ")
        )
    })
}
