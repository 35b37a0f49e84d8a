//! The light of paths with a delta (mirror, glass) scattering that the rasterized passes
//! cannot draw (issue 29): `bidir`'s GPU strategies connect the camera's first surface x1,
//! or the bundle hit x2 after it, to the lights and to light-subpath vertices by shadow-map
//! visibility, which no delta lobe passes. The rest is split so that every path is counted
//! once, as `path` splits it between its path tracer and its light tracer:
//!
//! - the GPU: paths whose first two vertices from the camera (x1, and x2 or the light)
//!   scatter by non-delta lobes, except those whose first scattering after a point or spot
//!   light is a delta lobe (the light subpaths of those lights leave an RSM vertex's delta
//!   lobe untraced, [`super::subpaths`]; the lighting pass gives the delta lobes no
//!   roughness clamp, so a mirror reflects nothing there);
//! - [`caustics`]: the light tracer of `path` (`trace::light_tracer`) from the point and
//!   spot lights, which connects to the camera every non-delta vertex after a first delta
//!   bounce (L S … D E, the caustics seen directly among them); and its delta chains from
//!   the emitters and suns (`chain_only`, issue 44): L S+ D E, the surfaces the camera sees
//!   lit through glass or by a mirror alone (the longer paths through glass are the VPLs'
//!   of [`super::emitted`], whose subpaths go on through delta lobes);
//! - [`delta_camera_paths`]: camera paths through a delta lobe at x1 (mirrors and glass
//!   seen by the camera, E S+ D …: beyond the next-event estimation of
//!   `specular_paths_direct` where they land) or at x2 (E D S+ …: light reaching a surface
//!   seen by the camera through a mirror or glass), continued by the path tracer, less the
//!   emitters and suns met from x2 through delta lobes alone (the delta chains'). Before,
//!   these camera paths were the only estimator of an emitter's light through glass (the
//!   floor under `glass_room`'s slab: fireflies, median 0.28 of `path`).
//!
//! Left out: a parallel sun's light through glass seen through glass (L S+ D S+ E), which
//! `path` leaves out too.

use crate::cancel::{Progress, StageProgress};
use crate::error::Result;
use crate::image::Image;
use crate::sampling::Rng;
use crate::scene::sources::{Source, Sources};
use crate::scene::Scene;
use crate::trace::direct::DirectLight;
use crate::trace::light_tracer::{self, LightTraceSettings};
use crate::trace::light_vertex::Connection;
use crate::trace::path::{self, PathSettings, Strategy};
use crate::trace::{Interaction, SceneBvh};
use glam::Vec3;
use rayon::prelude::*;

/// Fewest light paths a frame traces for [`caustics`] (one per pixel beyond that, as
/// `path` at 1 spp): at 32×32 one per pixel would leave about 30 paths a frame on
/// `caustic-ring`'s mirror ring. Paths whose first bounce is not a delta lobe end after one
/// ray. At 48² (2304 pixels) 2^18 instead of 2^16 paths take the first frame's relMSE
/// against `path` from 0.030 to 0.017 on `mirror-shadow` and from 0.075 to 0.036 on
/// `caustic-ring` (`benches/measure/bidir_scenes`) for about 0.06 s more a frame.
pub(super) const MIN_LIGHT_PATHS: u64 = 1 << 18;

/// The sources of [`caustics`]: the point and spot lights (those whose light subpaths the
/// GPU leaves to it).
fn local_lights(scene: &Scene) -> Sources {
    Sources::filtered(scene, |s| match s {
        Source::Light(i) => scene.lights[i].is_local(),
        _ => false,
    })
}

/// The sources of the delta-chain light tracer: the emitters and the directional lights,
/// the sources of [`super::emitted`]'s VPLs but the sky (a sky is large: the camera paths
/// through glass find it by themselves, as `path`'s do).
fn chain_sources(scene: &Scene) -> Sources {
    Sources::filtered(scene, |s| match s {
        Source::Light(i) => !scene.lights[i].is_local(),
        Source::Emitters => true,
        Source::Environment => false,
    })
}

/// The light tracer's image of `paths` light paths from the point and spot lights, up to
/// `max_depth` scatterings, plus that of `paths` delta chains from the emitters and suns
/// ([`chain_sources`], `chain_only`: L S+ D E, the surfaces seen by the camera and lit
/// through glass or by a mirror alone; their longer paths are the VPLs' of
/// [`super::emitted`], whose subpaths go on through delta lobes). Zero without delta
/// materials.
pub(super) fn caustics(
    scene: &Scene,
    bvh: &SceneBvh,
    paths: u64,
    seed: u64,
    max_depth: u32,
    progress: &dyn Progress,
) -> Result<Image> {
    let mut image = Image::new(scene.camera.width, scene.camera.height);
    if !scene.has_delta_materials() || max_depth < 2 {
        return Ok(image);
    }
    let runs = [
        (local_lights(scene), false, 0xca05_71c5),
        (chain_sources(scene), true, 0xca05_71c6),
    ];
    let runs: Vec<_> = runs.into_iter().filter(|r| !r.0.is_empty()).collect();
    let chunks = paths.div_ceil(light_tracer::CHUNK) * runs.len() as u64;
    let stage = StageProgress::new(progress, "caustic light paths", chunks);
    for (sources, chain_only, stream) in runs {
        let settings = LightTraceSettings {
            max_depth,
            rr_depth: 3,
            chain_only,
        };
        let part = light_tracer::image(
            scene,
            bvh,
            &sources,
            (paths, seed, stream),
            &settings,
            &stage,
        );
        for (p, q) in image.pixels.iter_mut().zip(&part.pixels) {
            *p += *q;
        }
    }
    stage.finish()?;
    Ok(image)
}

/// The camera paths through a delta lobe at the first or the second vertex, `spp` jittered
/// samples a pixel, up to `max_depth` scatterings: see the module's documentation.
pub(super) fn delta_camera_paths(
    scene: &Scene,
    bvh: &SceneBvh,
    spp: u32,
    seed: u64,
    max_depth: u32,
    progress: &dyn Progress,
) -> Result<Image> {
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let mut image = Image::new(w, h);
    if !scene.has_delta_materials() || max_depth < 2 {
        return Ok(image);
    }
    let lights = DirectLight::of(scene);
    let stage = StageProgress::new(progress, "delta camera paths", h as u64);
    let spp = spp.max(1);
    image
        .pixels
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                if stage.stopped() {
                    return;
                }
                let pixel = y as u64 * w as u64 + x as u64;
                let mut sum = Vec3::ZERO;
                for s in 0..spp {
                    let mut rng = Rng::new(seed, 0xde17_a000 ^ pixel, s as u64);
                    let j = rng.next_2d();
                    let dir = cam.direction(x as f32 + j.x, y as f32 + j.y);
                    sum += sample(scene, bvh, &lights, cam.position, dir, max_depth, &mut rng);
                }
                *px = sum / spp as f32;
            }
            stage.advance(1);
        });
    stage.finish()?;
    Ok(image)
}

/// One camera sample of [`delta_camera_paths`]: from the camera ray's first surface x1,
/// (a) its delta lobes are followed to each non-delta vertex z they reach, whose
/// non-delta scattering is continued by the path tracer (the next-event estimation at z is
/// `specular_paths_direct`'s); (b) its non-delta lobes are sampled once, and where they
/// meet a delta lobe at x2, the path goes on through it by the path tracer (next-event
/// estimation included, and the emitters, sky and suns' discs it meets).
fn sample(
    scene: &Scene,
    bvh: &SceneBvh,
    lights: &DirectLight,
    origin: Vec3,
    dir: Vec3,
    max_depth: u32,
    rng: &mut Rng,
) -> Vec3 {
    let Some(hit) = bvh.intersect(origin, dir, f32::INFINITY) else {
        return Vec3::ZERO;
    };
    let mut it = Interaction::new(scene, &hit, dir);
    let mut wo = -dir;
    let mut beta = Vec3::ONE;
    // `delta`: delta scatterings so far (the vertex `it` is number delta + 1).
    let mut delta = 0u32;
    let mut l = Vec3::ZERO;
    while let Some(bs) = it.material.sample(it.frame.to_local(wo), rng) {
        let wi = it.frame.to_world(bs.wi);
        let same_side = wi.dot(it.ng) * wo.dot(it.ng) > 0.0;
        if same_side == bs.lobe.crosses() {
            break;
        }
        let vertex = delta + 1;
        if bs.lobe.is_delta() {
            if vertex >= max_depth {
                break;
            }
            // Follow the delta lobe. The sky, the suns' discs and the emitters met through
            // delta lobes alone are `specular_paths_direct`'s (its specular image collects
            // the light beyond the first surface), not this strategy's.
            let Some(next) = bvh.intersect(it.spawn(wi), wi, f32::INFINITY) else {
                break;
            };
            beta *= bs.weight;
            it = Interaction::new(scene, &next, wi);
            wo = -wi;
            delta += 1;
            continue;
        }
        let weight = beta * bs.weight;
        if delta > 0 {
            // (a) z's non-delta scattering, past the next-event estimation: its first ray
            // sees the emitters and the sky, not the suns' discs (the estimation at z took
            // the directional lights along their axes).
            let ps = PathSettings {
                first_ray_suns: false,
                ..settings(max_depth - vertex)
            };
            l += weight * path::radiance(scene, bvh, lights, (it.spawn(wi), wi), rng, &ps);
        } else if max_depth >= 2 {
            // (b) x1's non-delta lobe towards a delta lobe at x2.
            l += weight * through_x2(scene, bvh, lights, it.spawn(wi), wi, max_depth, rng);
        }
        break;
    }
    l
}

/// The light through a delta lobe of the surface x2 that the ray from x1 meets (zero where
/// it meets none or picks a non-delta lobe there, whose light the GPU gives).
fn through_x2(
    scene: &Scene,
    bvh: &SceneBvh,
    lights: &DirectLight,
    o: Vec3,
    d: Vec3,
    max_depth: u32,
    rng: &mut Rng,
) -> Vec3 {
    let Some(hit) = bvh.intersect(o, d, f32::INFINITY) else {
        return Vec3::ZERO;
    };
    let it = Interaction::new(scene, &hit, d);
    if !it.material.has_delta_lobe() {
        return Vec3::ZERO;
    }
    let wo = -d;
    let Some(bs) = it.material.sample(it.frame.to_local(wo), rng) else {
        return Vec3::ZERO;
    };
    let wi = it.frame.to_world(bs.wi);
    let same_side = wi.dot(it.ng) * wo.dot(it.ng) > 0.0;
    if !bs.lobe.is_delta() || same_side == bs.lobe.crosses() {
        return Vec3::ZERO;
    }
    // x3 is vertex 3: the path tracer from there takes max_depth − 2 more scatterings; the
    // emitters and suns met through delta lobes alone are the delta-chain light tracer's
    // ([`caustics`]).
    let ps = settings(max_depth - 2);
    let ray = (it.spawn(wi), wi);
    bs.weight * path::radiance_past_delta_chain((scene, bvh, lights), ray, rng, &ps)
}

/// The path tracer continuing a camera path for `max_depth` more scatterings; nothing of
/// it is light-traced here (the light tracer of [`caustics`] connects to the camera from the
/// first surface only, which these paths have passed).
fn settings(max_depth: u32) -> PathSettings {
    PathSettings {
        max_depth,
        rr_depth: 3,
        light_traced: false,
        strategy: Strategy::Mis,
        light_vertex: Connection::Mis,
        first_ray_suns: true,
    }
}
