//! The coefficient β of the sky's control variate in the lighting pass (`bidir.wgsl`,
//! issue 44 item 4). Each pixel's sky light through the bundles is
//! β·C + (1/n)·Σ f_i·(V_i − β) (C the diffuse lobe's unshadowed sky light in closed form,
//! f_i a bundle's unshadowed sample of it, V_i whether the bundle sees the sky): unbiased for
//! any β drawn independently of the bundles' directions, and of least variance where β is the
//! share of the sky the point sees. β = 1 (before) is exact in the open, but in a closed room
//! lit through a window or glass (V ≈ 0 everywhere) the pixel's estimate is C minus 16
//! bundles' estimate of C: ±100% noise shared by every pixel of a normal, so the frame mean
//! of `glass_room`-like glazed rooms lit by the sky alone moved from −0.13 to 2.4 of `path`
//! with the seed.
//!
//! β is the sky-weighted visible share Σ L(ω)·V(ω) / Σ L(ω) over cosine-distributed
//! directions at the camera's first non-specular hits of a fixed grid of pixels, traced in
//! the CPU BVH (glass and mirrors block, as in the bundles), from a fixed random stream: one
//! number a frame, independent of the frame's bundles.
//!
//! β depends on the camera, the geometry, the materials (which surfaces are specular) and
//! the sky alone, so [`SkyShare`] keeps it in `bidir`'s state from frame to frame (about
//! 2,900 CPU rays saved each frame): the renderer forgets it when the camera, the geometry
//! or the materials change (`Renderer::sync_gpu`, with the direct light's traced specular
//! image), and drops the whole state when the environment changes or the image is resized.

use crate::frame::context::FrameCtx;
use crate::sampling::{cosine_hemisphere, Rng};
use crate::scene::Scene;
use crate::trace::{Interaction, SceneBvh};

/// Pixels a side of the grid whose first hits β is measured at.
const GRID: u32 = 24;

/// Cosine-distributed directions per grid point.
const DIRECTIONS: u32 = 4;

/// β as last computed, kept while the camera, the geometry, the materials and the
/// environment stay (see the module).
#[derive(Debug, Default)]
pub(super) struct SkyShare {
    kept: Option<f32>,
}

impl SkyShare {
    /// The camera, the geometry or the materials changed: β is computed again.
    pub(super) fn invalidate(&mut self) {
        self.kept = None;
    }

    /// The frame's β: the kept one, else computed (stage "sky share") and kept.
    pub(super) fn get(&mut self, fc: &mut FrameCtx, bvh: &SceneBvh) -> f32 {
        if let Some(beta) = self.kept {
            return beta;
        }
        let beta = fc.timed("sky share", |fc| coefficient(fc.scene, bvh));
        self.kept = Some(beta);
        beta
    }
}

/// β (see the module's documentation): 1 without an environment or where no grid pixel
/// sees a diffusely shaded surface.
pub(super) fn coefficient(scene: &Scene, bvh: &SceneBvh) -> f32 {
    let Some(env) = scene.environment.as_deref() else {
        return 1.0;
    };
    let cam = &scene.camera;
    let (mut seen, mut all) = (0.0f32, 0.0f32);
    for k in 0..GRID * GRID {
        let mut rng = Rng::new(0x5c_0e, 0xb37a, k as u64);
        let j = rng.next_2d();
        let x = ((k % GRID) as f32 + j.x) / GRID as f32 * cam.width as f32;
        let y = ((k / GRID) as f32 + j.y) / GRID as f32 * cam.height as f32;
        let dir = cam.direction(x, y);
        let Some(hit) = bvh.intersect(cam.position, dir, f32::INFINITY) else {
            continue;
        };
        let it = Interaction::new(scene, &hit, dir);
        if it.material.is_purely_specular() {
            continue;
        }
        // The shading frame on the camera's side.
        let n = if it.frame.n.dot(dir) > 0.0 {
            -it.frame.n
        } else {
            it.frame.n
        };
        let frame = crate::sampling::Frame::new(n);
        for _ in 0..DIRECTIONS {
            let wi = frame.to_world(cosine_hemisphere(rng.next_2d()));
            let l = env.radiance(wi).max_element();
            all += l;
            if bvh.intersect(it.spawn(wi), wi, f32::INFINITY).is_none() {
                seen += l;
            }
        }
    }
    if all > 0.0 {
        (seen / all).clamp(0.0, 1.0)
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::coefficient;
    use crate::frame::{FrameDesc, RenderOptions, Renderer};
    use crate::scene::{EnvImage, Environment, Lighting, Scene, SceneUpdate};
    use crate::trace::SceneBvh;
    use glam::{Mat4, Vec3};
    use serde_json::json;
    use std::sync::Arc;

    /// A ground plate with a box and a wall under a sun and a constant sky: the wall and
    /// the box hide part of the sky from the ground, so 0 < β < 1.
    fn scene() -> Scene {
        let json = r#"{
            "camera": {"position": [0, 2.2, 4], "look_at": [0, 0.4, 0], "fov": 40},
            "lights": [{"type": "directional", "direction": [-0.5, -1, -0.3],
                        "irradiance": [3, 2.8, 2.5]}],
            "environment": {"radiance": [0.3, 0.4, 0.6]},
            "materials": {"ground": {"diffuse": [0.6, 0.55, 0.5]},
                          "red": {"diffuse": [0.7, 0.2, 0.15]},
                          "wall": {"diffuse": [0.8, 0.8, 0.8]}},
            "objects": [
                {"shape": {"type": "quad", "size": [4, 4]}, "material": "ground"},
                {"shape": {"type": "box", "size": [0.8, 0.8, 0.8]}, "material": "red",
                 "transform": {"translate": [0.3, 0.4, 0], "rotate": [0, 30, 0]}},
                {"shape": {"type": "quad", "size": [3, 1.5]}, "material": "wall",
                 "transform": {"translate": [0, 0.75, -1.2], "rotate": [90, 0, 0]}}
            ]
        }"#;
        Scene::from_json(json, "sky share", &Default::default()).expect("scene")
    }

    fn options() -> RenderOptions {
        crate::options!(Bidir, spp: 1, width: 16, height: 16, bundles: 4, vpls_per_light: 8)
    }

    /// One frame of `r`: whether it computed β (its stage "sky share") and the β it used.
    fn frame(r: &mut Renderer) -> (bool, f32) {
        let out = r
            .render(&FrameDesc::default(), &crate::Silent)
            .expect("frame");
        let computed = out.stats.stages.iter().any(|(n, _)| n == "sky share");
        let state = r.gpu.as_ref().and_then(|g| g.bidir.as_ref());
        let beta = state.and_then(|b| b.sky_share.kept);
        (computed, beta.expect("β kept after a frame"))
    }

    /// β of a new renderer's first frame of `scene`.
    fn fresh(scene: &Scene) -> f32 {
        let mut r = Renderer::new(scene, &options()).expect("renderer");
        let (computed, beta) = frame(&mut r);
        assert!(computed);
        beta
    }

    /// β computed anew from `r`'s scene with a BVH built anew.
    fn recomputed(r: &Renderer) -> f32 {
        let bvh = SceneBvh::try_build(r.scene()).expect("bvh");
        coefficient(r.scene(), &bvh)
    }

    /// A sky bright along the horizon (the rows about the middle of the image), dim
    /// above: the wall and the box hide more of it than of a constant sky.
    fn horizon_sky() -> Arc<Environment> {
        let (w, h) = (16u32, 8u32);
        let texels = (0..w * h)
            .map(|i| match i / w {
                3 | 4 => Vec3::splat(10.0),
                _ => Vec3::splat(0.1),
            })
            .collect();
        let image = EnvImage {
            width: w,
            height: h,
            texels,
        };
        Arc::new(Environment::image(image, 1.0, 0.0))
    }

    /// β is computed on the first frame and kept over still frames and light changes; a
    /// change of the camera, the sky, the geometry or the materials computes it again, and
    /// gives what a new renderer (or β computed anew) gives.
    #[test]
    fn kept_until_the_camera_geometry_materials_or_sky_change() {
        let mut r = Renderer::new(&scene(), &options()).expect("renderer");
        let (computed, b0) = frame(&mut r);
        assert!(computed);
        assert_eq!(b0, recomputed(&r));
        assert!(
            0.05 < b0 && b0 < 0.95,
            "β {b0}: the test needs a partly hidden sky"
        );

        // A still frame, then one where only the sun moved: kept.
        assert_eq!(frame(&mut r), (false, b0));
        let sun = json!({"type": "directional", "direction": [0.4, -1, -0.2],
                         "irradiance": [3, 2.8, 2.5]});
        let light = serde_json::from_value(sun).expect("light");
        r.update(&SceneUpdate::Light { index: 0, light })
            .expect("update");
        assert_eq!(frame(&mut r), (false, b0));

        // The camera moved close to the foot of the wall.
        let camera = json!({"position": [-0.9, 0.8, 0.8], "look_at": [0, 0.2, -1.2], "fov": 40});
        let camera = serde_json::from_value(camera).expect("camera");
        r.update(&SceneUpdate::Camera(camera)).expect("update");
        let (computed, b1) = frame(&mut r);
        assert!(computed);
        assert_eq!(b1, fresh(r.scene()));
        assert!(
            (b1 - b0).abs() > 0.02,
            "β {b0} → {b1}: the move must matter"
        );

        // Another sky.
        let lighting = Lighting {
            environment: Some(horizon_sky()),
            lights: Vec::new(),
            add: false,
        };
        r.set_lighting(&lighting).expect("lighting");
        let (computed, b2) = frame(&mut r);
        assert!(computed);
        assert_eq!(b2, fresh(r.scene()));
        assert!((b2 - b1).abs() > 0.02, "β {b1} → {b2}: the sky must matter");

        // The wall moved away.
        let transform = Mat4::from_translation(Vec3::new(0.0, 0.75, -3.0))
            * Mat4::from_rotation_x(90f32.to_radians());
        r.update(&SceneUpdate::Transform {
            object: 2,
            transform,
        })
        .expect("update");
        let (computed, b3) = frame(&mut r);
        assert!(computed);
        assert_eq!(b3, recomputed(&r));
        assert!(
            (b3 - b2).abs() > 0.02,
            "β {b2} → {b3}: the wall must matter"
        );

        // The wall a mirror: it no longer counts as a diffuse hit, and still blocks.
        let mirror = json!({"diffuse": [0, 0, 0], "specular": [1, 1, 1], "roughness": 0});
        let material = Box::new(serde_json::from_value(mirror).expect("material"));
        let name = "wall".to_string();
        r.update(&SceneUpdate::Material { name, material })
            .expect("update");
        let (computed, b4) = frame(&mut r);
        assert!(computed);
        assert_eq!(b4, recomputed(&r));
        assert_eq!(frame(&mut r), (false, b4));
    }
}
