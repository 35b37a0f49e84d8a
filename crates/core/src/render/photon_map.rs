//! Method `photon`: classic (Jensen) photon mapping, the baseline for ISPM.
//!
//! 1. Emit `photons` photons and trace them, storing photons of every bounce, direct light
//!    included.
//! 2. Build the kd-tree over the stored photons.
//! 3. For each pixel sample, follow the camera ray through delta lobes (mirror, glass) to
//!    non-delta surfaces and estimate their radiance from the k nearest photons. Nothing
//!    else: direct light comes from the photons too, so the image converges to the full
//!    solution as the photon count grows and the gather radius shrinks.

use super::{Progress, RenderOutput, RenderStats, Settings};
use crate::error::{Error, Result};
use crate::image::Image;
use crate::photon::estimate::{Gather, PhotonMap};
use crate::photon::{emit_and_trace, Neighbour, PhotonTraceSettings};
use crate::sampling::Rng;
use crate::scene::Scene;
use crate::trace::path::{self, FirstHit};
use crate::trace::{Interaction, SceneBvh};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

/// Most delta scatterings a camera path follows before giving up.
const MAX_DELTA_BOUNCES: u32 = 8;
/// Default maximum gather radius, as a fraction of the scene's bounding-box diagonal.
const DEFAULT_RADIUS_FRACTION: f32 = 0.05;

pub fn render(scene: &Scene, settings: &Settings, progress: &dyn Progress) -> Result<RenderOutput> {
    let t0 = Instant::now();
    let mut stats = RenderStats {
        triangles: scene.triangles.len() as u64,
        ..Default::default()
    };
    let mut stage =
        |name: &str, t: Instant| stats.stages.push((name.into(), t.elapsed().as_secs_f64()));

    let t = Instant::now();
    let bvh = SceneBvh::build(scene);
    stage("bvh build", t);

    // Photon tracing: every bounce, direct light included.
    let t = Instant::now();
    let pts = PhotonTraceSettings {
        max_bounces: settings.max_depth - 1,
        store_direct: true,
    };
    let set = emit_and_trace(scene, &bvh, settings.photons, &pts, settings.seed);
    stage("photon trace", t);
    if !progress.update("photon trace", 1.0) {
        return Err(Error::Cancelled);
    }

    let t = Instant::now();
    let map = PhotonMap::build(set.photons);
    stage("kd-tree build", t);

    let t = Instant::now();
    let gather = Gather {
        k: settings.k as usize,
        max_radius: settings
            .max_radius
            .unwrap_or_else(|| DEFAULT_RADIUS_FRACTION * scene_diagonal(scene)),
        kernel: settings.kernel,
    };
    let rows = gather_rows(scene, &bvh, &map, &gather, settings, progress)?;
    stage("radiance estimate", t);

    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut out = RenderOutput {
        radiance: Image::new(w, h),
        albedo: Image::new(w, h),
        normal: Image::new(w, h),
        position: Image::new(w, h),
        depth: vec![0.0; (w * h) as usize],
        caustics: Image::new(w, h),
        stats,
    };
    for (i, (l, fh)) in rows.into_iter().flatten().enumerate() {
        out.radiance.pixels[i] = l;
        out.albedo.pixels[i] = fh.albedo;
        out.normal.pixels[i] = fh.normal;
        out.position.pixels[i] = fh.position;
        out.depth[i] = fh.depth;
    }
    out.stats.samples_per_pixel = settings.spp;
    out.stats.camera_paths = settings.spp as u64 * w as u64 * h as u64;
    out.stats.light_paths = set.emitted;
    out.stats.total_seconds = t0.elapsed().as_secs_f64();
    Ok(out)
}

/// Pixel radiance and first-hit AOVs, one row per parallel work item.
fn gather_rows(
    scene: &Scene,
    bvh: &SceneBvh,
    map: &PhotonMap,
    gather: &Gather,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<Vec<Vec<(Vec3, FirstHit)>>> {
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let max_delta = MAX_DELTA_BOUNCES.min(settings.max_depth);
    let done = AtomicU64::new(0);
    let cancelled = AtomicBool::new(false);
    let rows = (0..h)
        .into_par_iter()
        .map_init(Vec::new, |scratch, y| {
            if cancelled.load(Ordering::Relaxed) {
                return Vec::new();
            }
            let row = (0..w)
                .map(|x| {
                    let pixel = (y * w + x) as u64;
                    let mut sum = Vec3::ZERO;
                    for s in 0..settings.spp {
                        let mut rng = Rng::new(settings.seed, pixel, s as u64);
                        let j = rng.next_2d();
                        let dir = cam.direction(x as f32 + j.x, y as f32 + j.y);
                        sum += radiance(
                            scene,
                            bvh,
                            map,
                            gather,
                            cam.position,
                            dir,
                            max_delta,
                            &mut rng,
                            scratch,
                        );
                    }
                    let first = path::first_hit(
                        scene,
                        bvh,
                        cam.position,
                        cam.direction(x as f32 + 0.5, y as f32 + 0.5),
                    );
                    (sum / settings.spp as f32, first)
                })
                .collect();
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            if !progress.update("radiance estimate", d as f64 / h as f64) {
                cancelled.store(true, Ordering::Relaxed);
            }
            row
        })
        .collect();
    if cancelled.load(Ordering::Relaxed) {
        return Err(Error::Cancelled);
    }
    Ok(rows)
}

/// Radiance arriving at `origin` from `-dir`: photon estimates at every non-delta surface
/// the ray reaches through up to `max_delta` delta scatterings. The photon estimate covers
/// a surface's non-delta lobes; its delta lobe (if any) is followed when `Material::sample`
/// picks it, with the sample weight accounting for that choice.
#[allow(clippy::too_many_arguments)]
fn radiance(
    scene: &Scene,
    bvh: &SceneBvh,
    map: &PhotonMap,
    gather: &Gather,
    origin: Vec3,
    dir: Vec3,
    max_delta: u32,
    rng: &mut Rng,
    scratch: &mut Vec<Neighbour>,
) -> Vec3 {
    let mut l = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    let (mut o, mut d) = (origin, dir);
    for _ in 0..=max_delta {
        let Some(hit) = bvh.intersect(o, d, f32::INFINITY) else {
            break;
        };
        let it = Interaction::new(scene, &hit, d);
        let wo = -d;
        l += beta * map.radiance(&it, wo, gather, scratch);

        // Continue only through a delta lobe, geometrically consistent.
        let Some(bs) = it.material.sample(it.frame.to_local(wo), rng) else {
            break;
        };
        if !bs.lobe.is_delta() {
            break;
        }
        let wi = it.frame.to_world(bs.wi);
        let same_side = wi.dot(it.ng) * wo.dot(it.ng) > 0.0;
        if same_side == matches!(bs.lobe, crate::bsdf::Lobe::GlassRefract) {
            break;
        }
        beta *= bs.weight;
        o = it.spawn(wi);
        d = wi;
    }
    l
}

/// Length of the scene's bounding-box diagonal (m).
fn scene_diagonal(scene: &Scene) -> f32 {
    let (lo, hi) = scene
        .positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    if lo.x > hi.x {
        return 1.0;
    }
    (hi - lo).length()
}
