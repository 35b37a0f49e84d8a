//! GPU rasterization passes, each a struct with its pipeline and layouts: G-buffer, shadow
//! maps (spot, cube), bounce maps, deferred direct light and its edge supersampling,
//! reflective shadow maps, ray bundles, VPLs, composite. A pass never sees the options or
//! the renderer; `frame/` orders them.

pub mod bounce;
pub mod bundles;
pub mod composite;
pub mod direct;
pub mod direct_variant;
pub mod edges;
pub mod exact_models;
pub mod gbuffer;
pub mod instances;
pub mod layers;
pub mod ltc;
pub mod model_energy;
pub mod rsm;
pub mod shadow;
pub mod sky_cone;
pub mod splat;
pub mod subpixel;
pub mod textures;
pub mod vpl;
pub mod wgsl;

use crate::error::Result;
pub(crate) use crate::gpu::layout::{
    buffer_init, storage_entry, view_binding, view_entry, VIEW_SIZE,
};
use crate::gpu::raw::ViewRaw;
use crate::gpu::GpuContext;
use crate::scene::light_views;
use crate::scene::Scene;
use glam::{Mat4, Vec2, Vec3};

pub use instances::{CullUnits, Draw, Geometry};

/// Eye samples per submission (bounds the timestamp queries of one submission).
pub(crate) const SAMPLES_PER_SUBMIT: u32 = 256;

/// Sub-pixel sample positions in [0, 1)²: a stratified grid when `spp` is a square, else
/// the Halton (2, 3) sequence. Their mean over the pixel is a box filter, like the path
/// tracer's uniform jitter.
pub fn sample_positions(spp: u32) -> Vec<Vec2> {
    let n = (spp as f64).sqrt().round() as u32;
    if n * n == spp {
        return (0..spp)
            .map(|i| Vec2::new((i % n) as f32 + 0.5, (i / n) as f32 + 0.5) / n as f32)
            .collect();
    }
    let halton = |mut i: u32, b: u32| {
        let (mut f, mut r) = (1.0f32, 0.0f32);
        while i > 0 {
            f /= b as f32;
            r += f * (i % b) as f32;
            i /= b;
        }
        r
    };
    (1..=spp)
        .map(|i| Vec2::new(halton(i, 2), halton(i, 3)))
        .collect()
}

/// The camera's world -> clip transform with the image shifted so that the pixel centre
/// sees image position `pixel + jitter`.
pub(crate) fn camera_view(scene: &Scene, jitter: Vec2, weight: f32) -> ViewRaw {
    let cam = &scene.camera;
    let (lo, hi) = light_views::bounds(scene);
    let far = (lo - cam.position)
        .abs()
        .max((hi - cam.position).abs())
        .length()
        * 1.01
        + 1e-3;
    let proj = light_views::perspective(
        cam.fov_y.to_radians(),
        cam.aspect(),
        near(cam.position, cam.forward, (lo, hi), far),
        far,
    );
    let shift = Vec3::new(
        2.0 * (0.5 - jitter.x) / cam.width as f32,
        -2.0 * (0.5 - jitter.y) / cam.height as f32,
        0.0,
    );
    let view = light_views::look_to(cam.position, cam.forward, cam.up);
    ViewRaw::new(
        Mat4::from_translation(shift) * proj * view,
        cam.position,
        weight,
    )
}

/// The eye views' near plane: just before the scene's bounding box when all of the box is in
/// front of the camera (nothing nearer can be seen), else `far` · 1e-5. Depth32Float with a
/// standard projection resolves Δz ≈ z² · 6e-8 / near at distance z: at `far` · 1e-5 a surface
/// 0.5 units in front of another 1100 units away (Mitsuba's Cornell box: its luminaire under
/// the ceiling, seen from 800 units outside the box) z-fought with it, and the luminaire
/// vanished from whole frames of some sub-pixel offsets (the `direct` light 22% dark at 64×64
/// over 16 progressive passes, 8% dark in one frame at 128×128; issue 42). Just before the box,
/// Δz ≈ 1e-4 there.
///
/// The plane is at a view *depth* (distance along `forward`), so it is the box's least depth:
/// the least over its corners of `(corner − eye) · forward` (a linear function's minimum over a
/// box is at a corner). The Euclidean distance to the box is larger off the axis and clipped
/// the nearest part of a floor seen obliquely (a floor lit by a point light: `direct` lost the
/// image's near rows, 0.94 of `path`).
fn near(eye: Vec3, forward: Vec3, (lo, hi): (Vec3, Vec3), far: f32) -> f32 {
    if lo.x > hi.x {
        return far * 1e-5;
    }
    let depth = |x: f32, y: f32, z: f32| (Vec3::new(x, y, z) - eye).dot(forward);
    let least = [lo.x, hi.x]
        .into_iter()
        .flat_map(|x| [lo.y, hi.y].into_iter().map(move |y| (x, y)))
        .flat_map(|(x, y)| [lo.z, hi.z].into_iter().map(move |z| depth(x, y, z)))
        .fold(f32::INFINITY, f32::min);
    // max/min, not clamp: no panic on a NaN `far`.
    (0.99 * least).max(far * 1e-5).min(far * 0.5)
}

/// The camera's world -> clip transform for culling the eye passes: a sample's jitter
/// shifts the image by under a pixel (|Δndc| < 1 / width), so the centre view narrowed by
/// w / (w + 2) (h / (h + 2)) holds every jittered sample's frustum.
pub fn eye_cull_view(scene: &Scene) -> Mat4 {
    let centre = Mat4::from_cols_array_2d(&camera_view(scene, Vec2::splat(0.5), 1.0).view_proj);
    let (w, h) = (scene.camera.width as f32, scene.camera.height as f32);
    Mat4::from_scale(Vec3::new(w / (w + 2.0), h / (h + 2.0), 1.0)) * centre
}

/// A render pass that writes depth alone (no colour target) into `depth`, starting from
/// `load` and keeping the result or not (`store`): shadow maps, ray bundles, the edge mask.
pub(crate) fn depth_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    depth: &wgpu::TextureView,
    (load, store): (wgpu::LoadOp<f32>, wgpu::StoreOp),
    timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations { load, store }),
            stencil_ops: None,
        }),
        timestamp_writes: timestamps,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// Decodes `oct_encode` of `types.wgsl`.
pub(crate) fn oct_decode(e: Vec2) -> Vec3 {
    let mut n = Vec3::new(e.x, e.y, 1.0 - e.x.abs() - e.y.abs());
    let t = (-n.z).max(0.0);
    n.x += if n.x >= 0.0 { -t } else { t };
    n.y += if n.y >= 0.0 { -t } else { t };
    n.normalize_or_zero()
}

/// Samples per submission: up to [`SAMPLES_PER_SUBMIT`], fewer for large images so that
/// one submission stays short (about 2¹⁸ pixel samples, about 0.1 s on
/// lavapipe) and cancellation, checked between submissions, stays prompt.
pub(crate) fn samples_per_submit(w: u32, h: u32) -> u32 {
    let pixels = (w as u64 * h as u64).max(1);
    ((1u64 << 18) / pixels).clamp(1, SAMPLES_PER_SUBMIT as u64) as u32
}

/// Fails with `OutOfMemory` when the scene's instanced GPU geometry (unique meshes plus
/// one record per object) would not fit, and with a GPU error when its buffers exceed the
/// adapter's limits; before either is built.
pub(crate) fn check_scene_buffers(ctx: &GpuContext, scene: &Scene) -> Result<()> {
    instances::check_buffers(ctx, scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sample_positions_average_to_the_pixel_centre() {
        for spp in [1, 4, 16, 7, 100, 33] {
            let p = sample_positions(spp);
            assert_eq!(p.len(), spp as usize);
            assert!(p
                .iter()
                .all(|s| s.cmpge(Vec2::ZERO).all() && s.cmplt(Vec2::ONE).all()));
            let mean = p.iter().copied().sum::<Vec2>() / spp as f32;
            assert!(
                (mean - Vec2::splat(0.5)).abs().max_element() < 0.5 / (spp as f32).sqrt() + 1e-6,
                "{spp}: {mean}"
            );
        }
    }

    /// The jittered camera maps the point seen through image position `pixel + jitter` to
    /// the centre of `pixel`.
    #[test]
    fn camera_view_matches_camera_rays() {
        let scene = crate::scene::builtin::load("cornell").expect("built-in scene");
        let cam = scene.camera.with_size(64, 48);
        let scene = Scene {
            camera: cam,
            ..scene
        };
        let jitter = Vec2::new(0.2, 0.9);
        let m = Mat4::from_cols_array_2d(&camera_view(&scene, jitter, 1.0).view_proj);
        for (x, y) in [(0u32, 0u32), (10, 40), (63, 47)] {
            // 4 units out: inside the box (the near plane sits just before it, 2.4 away).
            let p = cam.position + cam.direction(x as f32 + jitter.x, y as f32 + jitter.y) * 4.0;
            let c = m * p.extend(1.0);
            let ndc = c.truncate() / c.w;
            let px = Vec2::new((ndc.x + 1.0) * 0.5 * 64.0, (1.0 - ndc.y) * 0.5 * 48.0);
            assert!(
                (px - Vec2::new(x as f32 + 0.5, y as f32 + 0.5))
                    .abs()
                    .max_element()
                    < 1e-3,
                "{px}"
            );
            assert!((0.0..=1.0).contains(&ndc.z));
        }
    }

    /// Outside the scene's box the near plane sits just before it, so that Depth32Float
    /// tells apart two surfaces 0.5 units apart 1100 units away (Mitsuba's Cornell box: its
    /// luminaire under the ceiling; at far · 1e-5 their depths were the same float); inside
    /// it stays at far · 1e-5.
    #[test]
    fn near_plane_resolves_a_luminaire_under_its_ceiling() {
        let bounds = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(556.0, 549.0, 560.0));
        let eye = Vec3::new(278.0, 273.0, -800.0);
        let far = 2000.0;
        let n = near(eye, Vec3::Z, bounds, far);
        assert!((n - 792.0).abs() < 1.0, "{n}");
        assert_eq!(near(Vec3::splat(100.0), Vec3::Z, bounds, far), far * 1e-5);
        let proj = light_views::perspective(0.7, 1.0, n, far);
        let depth = |z: f32| {
            let c = proj * glam::Vec4::new(0.0, 0.0, -z, 1.0);
            c.z / c.w
        };
        assert!(depth(1100.0) - depth(1099.5) > 1e-4);
        let old = light_views::perspective(0.7, 1.0, far * 1e-5, far);
        let old_depth = |z: f32| {
            let c = old * glam::Vec4::new(0.0, 0.0, -z, 1.0);
            c.z / c.w
        };
        // At far · 1e-5 the two depths are a float's spacing apart at most.
        assert!((old_depth(1100.0) - old_depth(1099.5)).abs() <= 2.0 * f32::EPSILON);
    }

    /// No point of the scene's box lies nearer than the near plane, for eyes all around it
    /// and looking every way: the box's corners (where the least depth is) project into
    /// [0, 1] depth or behind the far plane, never in front of the near plane. Before, the
    /// plane sat at the Euclidean distance to the box and clipped an obliquely seen floor.
    #[test]
    fn near_plane_clips_nothing_of_the_box() {
        let mut rng = crate::sampling::Rng::new(7, 8, 9);
        let bounds = (Vec3::new(-2.0, -1.0, -2.0), Vec3::new(2.0, -1.0, 2.0));
        // The floor seen from (0, 2.2, 3.4): its near corners are 3.17 deep, 3.49 away.
        let eye = Vec3::new(0.0, 2.2, 3.4);
        let forward = Vec3::new(0.0, -3.2, -3.6).normalize();
        let n = near(eye, forward, bounds, 100.0);
        assert!(n <= 3.17 && n > 3.0, "{n}");
        let mut placed = 0;
        for _ in 0..2000 {
            let eye = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 20.0 - 10.0;
            let forward = crate::sampling::uniform_sphere(rng.next_2d());
            let (lo, hi) = (Vec3::new(-1.0, -2.0, -0.5), Vec3::new(1.5, 0.5, 3.0));
            let n = near(eye, forward, (lo, hi), 50.0);
            if n == 50.0 * 1e-5 {
                continue; // part of the box beside or behind the eye: the fallback plane
            }
            placed += 1;
            for k in 0..8 {
                let c = Vec3::new(
                    if k & 1 == 0 { lo.x } else { hi.x },
                    if k & 2 == 0 { lo.y } else { hi.y },
                    if k & 4 == 0 { lo.z } else { hi.z },
                );
                let d = (c - eye).dot(forward);
                assert!(d >= n, "corner depth {d} < near {n}");
            }
        }
        assert!(placed > 200, "{placed} eyes with the box wholly in front");
    }

    #[test]
    fn octahedral_decode_inverts_encode() {
        let mut rng = crate::sampling::Rng::new(1, 2, 3);
        for _ in 0..1000 {
            let n = crate::sampling::uniform_sphere(rng.next_2d());
            // The WGSL encoder, transcribed.
            let p = Vec2::new(n.x, n.y) / (n.x.abs() + n.y.abs() + n.z.abs());
            let e = if n.z >= 0.0 {
                p
            } else {
                (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs()))
                    * Vec2::new(
                        if p.x >= 0.0 { 1.0 } else { -1.0 },
                        if p.y >= 0.0 { 1.0 } else { -1.0 },
                    )
            };
            assert!((oct_decode(e) - n).length() < 1e-5);
        }
    }
}
