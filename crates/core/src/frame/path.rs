//! Method `path`: the reference renderer (path tracing + light tracing for caustics).

use super::options::PathOptions;
use super::{FrameParams, RenderOutput, RenderStats};
use crate::cancel::{Progress, StageProgress};
use crate::error::Result;
use crate::image::Image;
use crate::sampling::Rng;
use crate::scene::Scene;
use crate::trace::direct::DirectLight;
use crate::trace::light_tracer::{self, LightTraceSettings};
use crate::trace::light_vertex::Connection;
use crate::trace::path::{self, PathSettings};
use crate::trace::SceneBvh;
use glam::Vec3;
use rayon::prelude::*;
use std::time::Instant;

pub fn render(
    scene: &Scene,
    bvh: &SceneBvh,
    options: &PathOptions,
    frame: &FrameParams,
    progress: &dyn Progress,
) -> Result<RenderOutput> {
    let t0 = Instant::now();
    let mut stats = RenderStats::of(scene);

    let (w, h) = (scene.camera.width, scene.camera.height);
    let spp = options.spp;
    let sources = light_tracer::light_sources(scene);
    let light_paths =
        if scene.has_delta_materials() && options.max_depth >= 2 && !sources.is_empty() {
            options
                .light_paths
                .unwrap_or(spp as u64 * w as u64 * h as u64)
        } else {
            0
        };
    let ps = PathSettings {
        max_depth: options.max_depth,
        rr_depth: 3,
        light_traced: light_paths > 0,
        strategy: path::Strategy::Mis,
        light_vertex: if options.light_vertices {
            Connection::Mis
        } else {
            Connection::Off
        },
        first_ray_suns: true,
    };
    let lights = DirectLight::of(scene);
    // Progress counts camera rows and light-path chunks together.
    let light_chunks = light_paths.div_ceil(light_tracer::CHUNK);
    // The camera connections of all light paths are kept until they are summed in order:
    // about one (pixel, radiance) splat of 16 bytes per path.
    crate::memory::check(
        || format!("the camera splats of {light_paths} light paths"),
        light_paths.saturating_mul(16),
    )?;
    let stage = StageProgress::new(progress, "path", h as u64 + light_chunks);

    // Camera paths, one row per work item.
    let t = Instant::now();
    let cam = &scene.camera;
    let rows: Vec<Vec<(Vec3, path::FirstHit)>> = (0..h)
        .into_par_iter()
        .map(|y| {
            if stage.stopped() {
                return Vec::new();
            }
            let row = (0..w)
                .map_while(|x| {
                    // Cancellation is asked per pixel: a row at high spp takes seconds.
                    if stage.stopped() {
                        return None;
                    }
                    let pixel = (y * w + x) as u64;
                    let mut sum = Vec3::ZERO;
                    for s in 0..spp {
                        if s % 64 == 63 && stage.stopped() {
                            return None;
                        }
                        // Camera paths draw from a per-pixel low-discrepancy sequence.
                        let mut rng = Rng::sobol(frame.seed, pixel, s);
                        let j = rng.next_2d();
                        let dir = cam.direction(x as f32 + j.x, y as f32 + j.y);
                        let ray = (cam.position, dir);
                        sum += path::radiance(scene, bvh, &lights, ray, &mut rng, &ps);
                    }
                    // Auxiliary images through the pixel centre are noise-free.
                    let first = if frame.first_hit_aovs {
                        path::first_hit(
                            scene,
                            bvh,
                            cam.position,
                            cam.direction(x as f32 + 0.5, y as f32 + 0.5),
                        )
                    } else {
                        path::FirstHit::default()
                    };
                    Some((sum / spp as f32, first))
                })
                .collect();
            stage.advance(1);
            row
        })
        .collect();
    stats
        .stages
        .push(("camera paths".into(), t.elapsed().as_secs_f64()));
    stage.finish()?;

    // Light paths for caustics.
    let t = Instant::now();
    let lts = LightTraceSettings {
        max_depth: options.max_depth,
        rr_depth: 3,
        chain_only: false,
    };
    let seeds = (light_paths, frame.seed, u64::MAX - 1);
    let caustics = light_tracer::image(scene, bvh, &sources, seeds, &lts, &stage);
    stats
        .stages
        .push(("light paths".into(), t.elapsed().as_secs_f64()));
    stage.finish()?;

    let mut radiance = Image::new(w, h);
    let mut hits = Vec::with_capacity((w * h) as usize);
    for (i, (l, fh)) in rows.into_iter().flatten().enumerate() {
        radiance.pixels[i] = l + caustics.pixels[i];
        hits.push(fh);
    }
    let first = path::FirstHitImages::of(w, h, hits);
    let mut out = RenderOutput::of_cpu(radiance, first, caustics, stats);
    out.stats.samples_per_pixel = spp;
    out.stats.camera_paths = spp as u64 * w as u64 * h as u64;
    out.stats.light_paths = light_paths;
    out.stats.total_seconds = t0.elapsed().as_secs_f64();
    Ok(out)
}
