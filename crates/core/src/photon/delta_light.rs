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
    if !can_meet_light(scene) {
        let cam = &scene.camera;
        return Ok(Image::new(cam.width, cam.height));
    }
    let settings = CameraSamples {
        max_depth: 1,
        ..*settings
    };
    adaptive_delta_image::<()>(scene, bvh, &settings, progress, |_, _, _| Vec3::ZERO, None)
}

/// Whether a path one delta scattering from the camera can meet any light: an emitting
/// surface, the environment or a sun's disc of directions. Without, [`one_bounce_light`]'s
/// image is exactly black (point and spot lights and parallel suns are met by next-event
/// estimation alone, which it leaves to the GPU), and nothing need be traced.
pub fn can_meet_light(scene: &Scene) -> bool {
    scene.environment.is_some()
        || scene.materials.iter().any(|m| m.emits())
        || scene.lights.iter().any(|l| l.disc_radiance().is_some())
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

    /// Four samples a pixel, seed 3.
    fn four_samples() -> CameraSamples {
        CameraSamples {
            spp: 4,
            seed: 3,
            ..Default::default()
        }
    }

    fn glass(text: &str) -> Scene {
        Scene::from_json(text, "glass", &std::collections::HashMap::new()).expect("scene")
    }

    /// Under a point light alone, nothing a path meets one delta scattering from the camera
    /// emits: the traced image (without the shortcut) is black, and the shortcut returns it
    /// without a ray; the sky or a sun's disc make it trace.
    #[test]
    fn a_point_light_alone_traces_nothing() {
        let settings = four_samples();
        let text = GLASS_UNDER_SKY.replace(
            r#""environment": {"radiance": [0.4, 0.4, 0.4]}"#,
            r#""lights": [{"type": "point", "position": [0, 2, 2], "intensity": [5, 5, 5]}]"#,
        );
        let scene = glass(&text);
        assert!(!can_meet_light(&scene));
        let bvh = SceneBvh::build(&scene);
        let one = CameraSamples {
            max_depth: 1,
            ..settings
        };
        let traced =
            adaptive_delta_image::<()>(&scene, &bvh, &one, &Silent, |_, _, _| Vec3::ZERO, None)
                .unwrap();
        assert!(traced.pixels.iter().all(|&p| p == Vec3::ZERO));
        let img = one_bounce_light(&scene, &bvh, &settings, &Silent).unwrap();
        assert_eq!((img.width, img.height), (24, 24));
        assert!(img.pixels.iter().all(|&p| p == Vec3::ZERO));
        assert!(can_meet_light(&glass(GLASS_UNDER_SKY)));
        let sun = text.replace(
            r#"{"type": "point", "position": [0, 2, 2], "intensity": [5, 5, 5]}"#,
            r#"{"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1],
                "angular_diameter": 2}"#,
        );
        assert!(can_meet_light(&glass(&sun)));
    }

    /// A smooth glass sphere (η 1.5) under a constant sky L = 0.4, seen from outside: one
    /// scattering from the camera, its pixels show the sky reflected by the Fresnel term
    /// alone (the refracted ray meets the sphere's inside: no light), L·F(θ). Through the
    /// central 4×4 pixels θ < 10° and F(θ) is within 0.2% of F(0) = 0.04, so each pixel is
    /// 0.016 to 0.5% (every sample follows both lobes: no noise). Followed further, the
    /// paths would find the sky through the glass too (about L·(1 − F)², 24× more).
    /// Outside the sphere's footprint nothing is traced or added.
    #[test]
    fn glass_shows_the_fresnel_reflection_of_the_sky_alone() {
        let settings = four_samples();
        let scene = glass(GLASS_UNDER_SKY);
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
