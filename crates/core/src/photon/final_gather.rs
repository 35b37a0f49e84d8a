//! Final gathering (Jensen 1996, "Global illumination using photon maps"; Jensen's book,
//! section 9.3.4): the indirect light at a camera path's surface comes from one BSDF-sampled
//! ray per camera sample, whose hit point reads the photon map and takes next-event
//! estimation's direct light; only the caustic photons (light → mirrors/glass → here) are
//! read at the surface itself.
//!
//! Read at the surface the camera sees, a photon-map estimate shows its noise as blotches a
//! few footprints wide, which more camera samples do not average away (every sample of a
//! pixel reads the same footprints). Read one bounce further, each sample reads the map at
//! another point, so the blotches average out with the samples, as a path tracer's noise
//! does; the map's blur (its bias) is seen through one diffuse reflection, which smooths it.

use super::camera_pass::gather_ray;
use super::footprint_map::FootprintMap;
use crate::sampling::Rng;
use crate::scene::Scene;
use crate::trace::direct::{DirectLight, Nee};
use crate::trace::direct_mis::reflection_sample;
use crate::trace::{Interaction, SceneBvh};
use glam::Vec3;

/// What a final gather reads where its rays land.
pub struct FinalGather<'a> {
    pub scene: &'a Scene,
    pub bvh: &'a SceneBvh,
    pub lights: &'a DirectLight,
    /// Every photon that scattered at least once (the direct light is next-event
    /// estimation's).
    pub map: &'a FootprintMap,
    /// Most scatterings a gather ray follows through delta lobes.
    pub max_depth: u32,
}

impl FinalGather<'_> {
    /// Light arriving at `it` after at least one scattering elsewhere, times the BSDF's
    /// non-delta lobes towards `wo`, less what reaches `it` through delta lobes straight from
    /// the light (the caustic photons' share): one BSDF sample's ray, at whose non-delta
    /// hit (directly or through mirrors and glass) the direct light by next-event
    /// estimation and the photon map's radiance are read. Unbiased but for the map's blur.
    pub fn indirect(&self, it: &Interaction, wo: Vec3, rng: &mut Rng) -> Vec3 {
        if it.material.is_purely_specular() {
            return Vec3::ZERO;
        }
        let Some((bs, wi)) = reflection_sample(it, wo, rng) else {
            return Vec3::ZERO;
        };
        let at = |y: &Interaction, wo_y: Vec3, rng: &mut Rng| {
            let direct = self
                .lights
                .estimate(self.scene, self.bvh, y, wo_y, rng, Nee::Alone, None);
            direct + self.map.radiance(y, wo_y)
        };
        bs.weight
            * gather_ray(
                self.scene,
                self.bvh,
                (it.spawn(wi), wi),
                self.max_depth,
                rng,
                at,
            )
    }
}
