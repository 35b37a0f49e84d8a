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

use crate::sampling::{cosine_hemisphere, Rng};
use crate::scene::Scene;
use crate::trace::{Interaction, SceneBvh};

/// Pixels a side of the grid whose first hits β is measured at.
const GRID: u32 = 24;

/// Cosine-distributed directions per grid point.
const DIRECTIONS: u32 = 4;

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
