//! The light met one delta scattering from the camera: what Mitsuba's `direct` integrator
//! counts beyond the non-delta lobes of the first surface seen (its BSDF sample, drawn at
//! the first hit only, finds an emitter, the sky or a sun's disc through a mirror, a smooth
//! coating or smooth glass, Fresnel-weighted), and the whole light of rough glass seen
//! first (its BSDF sample through the rough reflection or transmission lobe). Method
//! `direct` shades the first surface's non-delta lobes on the GPU; this image is the rest.
//!
//! The specular image's sampling ([`adaptive_delta_image`]: pixels no delta triangle
//! projects onto stay black without a ray, the glass's reflection and refraction are both
//! followed with their Fresnel weights) with the paths cut after one scattering, and no
//! light estimated where they land: the light they meet there alone (emission, the sky and
//! the suns' discs where they leave the scene). Rough glass is followed through the lobe its
//! sampling picks (BSDF sampling alone: unbiased, noisier than Mitsuba's light samples on a
//! small emitter seen in it).

use super::camera_pass::CameraSamples;
use super::delta_paths::adaptive_delta_image;
use crate::cancel::Progress;
use crate::error::Result;
use crate::image::Image;
use crate::scene::Scene;
use crate::trace::SceneBvh;
use glam::Vec3;

/// The light reaching the camera one delta (or rough-glass) scattering from the first
/// surface seen, `settings.spp` samples per pixel where it can be non-zero (its
/// `max_depth` is ignored: one scattering); black without mirrors or glass.
pub fn one_bounce_light(
    scene: &Scene,
    bvh: &SceneBvh,
    settings: &CameraSamples,
    progress: &dyn Progress,
) -> Result<Image> {
    let settings = CameraSamples {
        max_depth: 1,
        ..*settings
    };
    adaptive_delta_image::<()>(scene, bvh, &settings, progress, |_, _, _| Vec3::ZERO, None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cancel::Silent;

    /// One glass sphere (η 1.5) under a constant sky, seen from 3 m away.
    const GLASS_UNDER_SKY: &str = r#"{
        "objects": [{"material": "glass",
                     "shape": {"type": "sphere", "radius": 0.8, "subdivisions": 5}}],
        "materials": {"glass": {"diffuse": [0, 0, 0], "transmission": [1, 1, 1], "ior": 1.5}},
        "environment": {"radiance": [0.4, 0.4, 0.4]},
        "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 40, "width": 24,
                   "height": 24}
    }"#;

    /// A smooth glass sphere (η 1.5) under a constant sky L = 0.4, seen from outside: one
    /// scattering from the camera, its pixels show the sky reflected by the Fresnel term
    /// alone (the refracted ray meets the sphere's inside: no light), L·F(θ). Through the
    /// central 4×4 pixels θ < 10° and F(θ) is within 0.2% of F(0) = 0.04, so each pixel is
    /// 0.016 to 0.5% (every sample follows both lobes: no noise). Followed further, the
    /// paths would find the sky through the glass too (about L·(1 − F)², 24× more).
    /// Outside the sphere's footprint nothing is traced or added.
    #[test]
    fn glass_shows_the_fresnel_reflection_of_the_sky_alone() {
        let settings = CameraSamples {
            spp: 4,
            seed: 3,
            ..Default::default()
        };
        let no_files = std::collections::HashMap::new();
        let scene = Scene::from_json(GLASS_UNDER_SKY, "glass", &no_files).expect("scene");
        let bvh = SceneBvh::build(&scene);
        let img = one_bounce_light(&scene, &bvh, &settings, &Silent).unwrap();
        let want = 0.4 * 0.04;
        for y in 10..14 {
            for x in 10..14 {
                let v = img.pixels[y * 24 + x];
                let e = (v - Vec3::splat(want)).abs().max_element();
                assert!(e < 0.005 * want, "pixel ({x}, {y}): {v} vs {want}");
            }
        }
        assert_eq!(img.pixels[0], Vec3::ZERO);
    }
}
