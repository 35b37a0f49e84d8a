//! Mirrors and glass seen by the camera in method `ispm`. Rasterized shading of the eye
//! G-buffer evaluates only the non-delta lobes of the first surface, so perfect reflection
//! and refraction are traced backwards on the CPU, as the paper suggests (section 4:
//! "backwards recursive ray tracing on the CPU, with recursive global illumination
//! approximated by ... a traditional photon map gather"): next-event estimation for direct
//! light and a k-nearest-neighbour gather over the frame's stored photons (which exclude
//! the bounce-map hits, i.e. direct light) wherever the specular path lands.

use crate::error::Result;
use crate::image::Image;
use crate::photon::estimate::{GatherCache, PhotonMap};
use crate::photon::{Neighbour, Photon};
use crate::render::camera_pass::{delta_image, has_delta_lobe};
use crate::render::delta_paths::{adaptive_delta_image, shade_landings, trace_landings, Landings};
use crate::render::{Progress, Settings, SpecularSampling};
use crate::scene::Scene;
use crate::trace::path::direct_light;
use crate::trace::Interaction;
use crate::trace::SceneBvh;
use glam::Vec3;

/// Radiance reaching the camera through the delta lobes of the first surface seen,
/// keeping the camera side of the adaptive sampling (its landings:
/// `render::delta_paths::Landings`) in `landings` for the next frame. They are traced
/// only when `landings` holds none, or holds those of another seed, `spp` or image size;
/// the caller drops them when the camera, the geometry or the materials change, so a
/// frame whose lights alone changed only shades them (next-event estimation and the
/// photon gathers). Also returns the camera samples traced (0 when the landings were
/// reused).
pub fn specular_paths(
    scene: &Scene,
    bvh: &SceneBvh,
    settings: &Settings,
    photons: &[Photon],
    landings: &mut Option<Landings>,
    progress: &dyn Progress,
) -> Result<(Image, u64)> {
    if !scene.materials.iter().any(has_delta_lobe) {
        let cam = &scene.camera;
        return Ok((Image::new(cam.width, cam.height), 0));
    }
    let map = PhotonMap::try_build(photons.to_vec(), progress)?;
    let gather = crate::render::photon_map_gather(scene, settings);
    match settings.specular_sampling {
        SpecularSampling::Adaptive => {
            let gather = |it: &Interaction, wo: Vec3, cache: &mut GatherCache| {
                map.radiance_cached(it, wo, &gather, cache)
            };
            let cam = &scene.camera;
            let current = landings.as_ref().is_some_and(|l| {
                (l.seed, l.spp, l.size()) == (settings.seed, settings.spp, (cam.width, cam.height))
            });
            let (landings, traced) = match landings.take() {
                Some(l) if current => (landings.insert(l), 0),
                _ => {
                    let l = landings.insert(trace_landings(scene, bvh, settings, progress)?);
                    let n = l.samples();
                    (l, n)
                }
            };
            let image = shade_landings(
                scene,
                landings,
                progress,
                |it, wo| direct_light(scene, bvh, it, wo),
                Some(&gather),
            )?;
            Ok((image, traced))
        }
        SpecularSampling::Full => {
            let image = delta_image(
                scene,
                bvh,
                settings,
                progress,
                |it, wo, scratch: &mut Vec<Neighbour>| {
                    direct_light(scene, bvh, it, wo) + map.radiance(it, wo, &gather, scratch)
                },
            )?;
            let cam = &scene.camera;
            Ok((image, (cam.width * cam.height * settings.spp.max(1)) as u64))
        }
    }
}

/// Radiance reaching the camera through the delta lobes of the first surface seen, with
/// next-event estimation of the scene's lights only where the path lands (method `bidir`,
/// which keeps no photon map): the indirect light behind mirrors and glass is missing.
pub fn specular_paths_direct(
    scene: &Scene,
    bvh: &SceneBvh,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<Image> {
    match settings.specular_sampling {
        SpecularSampling::Adaptive => adaptive_delta_image::<()>(
            scene,
            bvh,
            settings,
            progress,
            |it, wo| direct_light(scene, bvh, it, wo),
            None,
        ),
        SpecularSampling::Full => {
            delta_image(scene, bvh, settings, progress, |it, wo, _: &mut ()| {
                direct_light(scene, bvh, it, wo)
            })
        }
    }
}
