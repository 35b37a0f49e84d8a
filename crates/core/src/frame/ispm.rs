//! Method `ispm` (McGuire & Luebke 2009) as a frame of the engine:
//!
//! 1. bounce maps (section 4.2) with the copies of their targets, submitted first;
//! 2. shadow maps, direct light and the eye G-buffer, submitted without waiting;
//! 3. the bounce-map readback, waiting for the bounce submission only (section 4.3), then
//!    the CPU photon trace of the later bounces and the boundary compensation while the GPU
//!    renders the direct light. With `FirstBounce::Traced` (CPU devices) step 1 is skipped
//!    and the same photons' first hits are cast here, in the CPU BVH
//!    ([`crate::photon::bounce`]);
//! 4. temporal reuse (Jozwowski 2002): the photons of the last frames, invalidated where
//!    lights or objects moved;
//! 5. mirrors and glass seen by the camera traced on the CPU (section 4);
//! 6. the photon-volume estimate (section 5), upsampling, the composite on the GPU and the
//!    readback of the images asked for.

use super::direct::{assemble, normalized, readback_names};
use super::gpu::rgb_image;
use super::options::IspmOptions;
use super::{FrameParams, RenderOutput, RenderStats};
use super::{GpuState, Images};
use crate::cancel::Progress;
use crate::error::{Error, Result};
use crate::estimate::volume_shape::partition;
use crate::estimate::{Binned, CpuEstimate, Estimator, IndirectEstimate, Mode, Volumes};
use crate::gpu::timer::Timer;
use crate::gpu::GpuContext;
use crate::gpu::Pipelines;
use crate::image::Image;
use crate::photon::bounce::{trace_bounce_maps, BounceMap, FirstBounce};
use crate::photon::delta_paths::Landings;
use crate::photon::focus::Focus;
use crate::photon::lbvh::Aabb;
use crate::photon::radius::VolumeRadius;
use crate::photon::radius::Z_RATIO;
use crate::photon::ring::PhotonRing;
use crate::photon::specular::{specular_paths, SpecularPaths};
use crate::photon::trace::Checked;
use crate::photon::trace::{continue_paths_from, emit_aimed_caustics, FirstSegment};
use crate::photon::PhotonRay;
use crate::photon::{boundary, PhotonTraceSettings};
use crate::raster::bounce::{BouncePass, BounceTargets};
use crate::scene::light_views::{light_views, LightView};
use crate::scene::Scene;
use crate::trace::SceneBvh;
use glam::Vec3;
use std::borrow::Cow;
use std::time::Instant;

/// The ISPM resources beyond the direct light's: bounce maps and the estimator.
pub(super) struct IspmState {
    /// Where the first hits are found, and why (`FirstBounce::resolve`).
    first_bounce: (FirstBounce, String),
    /// The rasterized bounce maps' resources (`FirstBounce::Raster` only).
    bounce: Option<BounceTargets>,
    estimate: IndirectEstimate,
    /// Why the estimator was chosen (`Estimator::resolve`).
    estimate_reason: String,
    /// Whether the scene has mirrors or glass (the specular texture is written each frame).
    specular: bool,
    /// The seed of the photons in the ring, when they are those of the current scene: a
    /// still scene with frame-coherent random numbers re-traces nothing.
    traced_seed: Option<u64>,
    /// The specular image of the last frame (reused while the camera and scene stand still).
    specular_image: Option<Image>,
    /// The camera side of the specular paths (kept while only the lights change).
    specular_landings: Option<Landings>,
    /// Whether the estimator's output is this scene's and camera's.
    splat_current: bool,
}

/// What changed since the photons in the ring were traced.
pub(super) struct Invalidation<'a> {
    /// Materials changed: every photon is stale.
    pub all: bool,
    pub lights: &'a [usize],
    /// Objects moved, with their bounds before the move.
    pub moved: &'a [(usize, Aabb)],
}

pub(super) struct FrameInputs<'a> {
    pub gpu: &'a mut GpuState,
    pub ring: &'a mut PhotonRing,
    pub invalid: Invalidation<'a>,
    pub scene: &'a Scene,
    pub bvh: &'a SceneBvh,
    pub options: &'a IspmOptions,
    pub params: &'a FrameParams,
    pub frame: u64,
    pub changes: crate::scene::Changes,
    pub images: Images,
    pub progress: &'a dyn Progress,
}

pub(super) fn frame(f: FrameInputs) -> Result<RenderOutput> {
    let FrameInputs {
        gpu: g,
        ring,
        invalid,
        scene,
        bvh,
        options,
        params,
        frame,
        changes,
        images,
        progress,
    } = f;
    let GpuState {
        ctx,
        scene: gs,
        targets,
        timer,
        ispm,
        serial: g_serial,
        ..
    } = g;
    let ctx = ctx.clone();
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    timer.reset();
    let mut stats = RenderStats {
        triangles: scene.triangles.len() as u64,
        samples_per_pixel: targets.spp(),
        ..Default::default()
    };
    let stage = |stats: &mut RenderStats, name: &str, t: Instant| {
        stats
            .stages
            .push((name.to_string(), t.elapsed().as_secs_f64()))
    };

    // Resources: created on the first frame at this size, else kept.
    let t = Instant::now();
    let layers = light_views(scene, options.photons);
    if ispm.is_none() {
        let (kind, estimate_reason) = options.estimator.resolve(&ctx.info);
        let (gbuf, k) = (&targets.gbuf, options.subsample);
        let binned =
            |mode| IndirectEstimate::Binned(Box::new(Binned::new(&ctx, gbuf, mode, [w, h], k)));
        let estimate = match kind {
            Estimator::Tiled => binned(Mode::Tiled),
            Estimator::Cluster => binned(Mode::Cluster),
            Estimator::Directional => binned(Mode::Directional),
            Estimator::Cpu => {
                IndirectEstimate::Cpu(Box::new(CpuEstimate::new(&ctx, gbuf, w, h, k)))
            }
            Estimator::Volumes | Estimator::Auto => {
                IndirectEstimate::Volumes(Box::new(Volumes::new(&ctx, gbuf, w, h, k)))
            }
        };
        targets.bind_composite(&ctx, Some(estimate.output().1));
        *ispm = Some(IspmState {
            first_bounce: options.first_bounce.resolve(&ctx.info),
            bounce: None,
            estimate,
            estimate_reason,
            specular: scene.has_delta_materials(),
            traced_seed: None,
            specular_image: None,
            specular_landings: None,
            splat_current: false,
        });
    }
    let Some(state) = ispm.as_mut() else {
        return Err(Error::Gpu("ISPM state missing".into()));
    };
    // Marked current again only when the frame completes: a cancelled or failed frame
    // leaves the next one to redo its work.
    let traced_seed = state.traced_seed.take();
    let splat_current = std::mem::replace(&mut state.splat_current, false);
    if changes.any() {
        state.specular_image = None;
    }
    // The specular paths' landings depend on the view, the geometry and the materials, not
    // on the lights.
    if changes.camera || changes.geometry || changes.materials {
        state.specular_landings = None;
    }
    // A still scene with frame-coherent random numbers has this frame's photons already.
    let reuse = ring.frames() == 1 && !changes.lighting() && traced_seed == Some(params.seed);
    let raster_bounce = state.first_bounce.0 == FirstBounce::Raster;
    if !reuse && raster_bounce {
        if !state.bounce.as_ref().is_some_and(|b| b.fits(&layers)) {
            state.bounce = BounceTargets::new(&ctx, &layers, &gs.materials)?;
        }
        if let Some(b) = &state.bounce {
            b.write_views(&ctx, scene, &layers, params.seed);
        }
    }
    targets.write_eye(&ctx, scene);
    stage(&mut stats, "upload", t);

    // 1. Bounce maps, submitted first with their readback copies.
    let serial = *g_serial;
    let t = Instant::now();
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("bounce maps"),
        });
    if let (false, Some(b)) = (reuse, &state.bounce) {
        b.record(
            &BouncePass::get(&ctx),
            &mut encoder,
            &layers,
            &gs.geometry,
            &gs.cull,
            (&gs.textures.group, gs.variant),
            timer,
        );
    }
    let bounce_submission = ctx.queue.submit([encoder.finish()]);
    if serial {
        ctx.wait()?;
        stage(&mut stats, "bounce maps (wall)", t);
    }

    // 2. Direct light and the eye G-buffer, not waited on.
    let t = Instant::now();
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("direct frame"),
        });
    // Progressive mode traces the direct light on the CPU (step 4): the eye G-buffer alone.
    let encoder = if params.progressive {
        targets.record_gbuffer(&ctx, &*gs, &mut encoder, timer);
        encoder
    } else {
        gs.record_shadows(&ctx, &mut encoder, timer, scene);
        targets.record_direct(&ctx, &*gs, encoder, timer, progress)?
    };
    ctx.queue.submit([encoder.finish()]);
    if serial {
        ctx.wait()?;
        stage(&mut stats, "direct light (wall)", t);
    }

    // 3. The bounce-map readback, then the CPU trace while the GPU lights the frame.
    let t = Instant::now();
    let bm = match (reuse, &state.bounce) {
        (true, _) => Default::default(),
        (false, Some(b)) if raster_bounce => b.finish(&ctx, &layers, Some(bounce_submission))?,
        (false, _) if raster_bounce => Default::default(),
        (false, _) => {
            let control = Checked::new(progress, "bounce maps");
            trace_bounce_maps(scene, bvh, &layers, params.seed, &control)?
        }
    };
    let bounce_stage = if raster_bounce {
        "bounce readback"
    } else {
        "bounce trace"
    };
    stage(&mut stats, bounce_stage, t);
    stats.photons_emitted = bm.covered;
    stats.photons_first_bounce = bm.rays.len() as u64;
    if !progress.update("bounce maps", 1.0) {
        return Err(Error::Cancelled);
    }

    // 4. Temporal reuse: drop what moved, trace this frame's photons per light, keep them.
    if invalid.all {
        ring.clear();
    }
    for &l in invalid.lights {
        ring.invalidate_light(l);
    }
    let grow = VolumeRadius::of_scene(scene, options.photons, options.kernel_scale)
        .scaled(params.radius_scale)
        .r_max;
    for (object, before) in invalid.moved {
        let o = &scene.objects[*object];
        let after = super::object_bounds(scene, o);
        let b = before.union(after);
        ring.invalidate_region(Aabb {
            min: b.min - Vec3::splat(grow),
            max: b.max + Vec3::splat(grow),
        });
    }
    // Progressive mode normalises the kernels' boundary loss per pixel (query side) instead
    // of per photon, which leaves the crease pixels dark (`progressive::query_coverage`).
    // Only at full resolution: an upsampled estimate comes from other pixels' samples, whose
    // coverage differs (cornell 24x24, subsample 2: relMSE at 64 passes 0.0175 against
    // 0.0072 with the photon-side compensation; subsample 1: 0.0012 against 0.0022).
    let query_side =
        params.progressive && options.refine.boundary_compensation && options.subsample <= 1;
    let t = Instant::now();
    let mut traced = 0u64;
    let mut compensation_seconds = 0.0;
    if !reuse && options.max_depth >= 2 {
        let pts = if options.footprint_volumes {
            PhotonTraceSettings {
                store_direct: false,
                ..super::gather::trace_settings(
                    scene,
                    options.photons,
                    options.max_depth,
                    options.refine.smoothing,
                    &options.kernel,
                    params.radius_scale,
                )
            }
        } else {
            PhotonTraceSettings {
                max_bounces: options.max_depth - 1,
                store_direct: false,
                differentials: None,
            }
        };
        // Photon focusing: lights whose projection maps hold every specular object get their
        // mirror and glass first hits from aimed CPU photons instead of the bounce map.
        let focus = Focus::of_scene(
            scene,
            if options.refine.photon_focus > 0.0 {
                1.0
            } else {
                0.0
            },
        );
        let mut start = 0;
        while start < bm.rays.len() {
            let light = bm.ray_lights[start];
            let end = start
                + bm.ray_lights[start..]
                    .iter()
                    .take_while(|&&l| l == light)
                    .count();
            let seed = params.seed ^ (light as u64).wrapping_mul(0xA24B_AED4_963E_E407);
            let control = Checked::new(progress, "cpu trace");
            let aimed = focus.covers_all(light as usize);
            // Aimed: the bounce map's own mirror and glass first hits are dropped.
            let rays: Cow<[PhotonRay]> = if aimed {
                (start..end)
                    .filter(|&i| !bm.first_delta[i])
                    .map(|i| bm.rays[i])
                    .collect()
            } else {
                Cow::Borrowed(&bm.rays[start..end])
            };
            // With footprints, photons that met a mirror or glass first carry the footprint
            // of their first segment from the light (re-cast on the CPU).
            let first = options
                .footprint_volumes
                .then(|| first_segment(scene, &layers, light as usize));
            let mut photons =
                continue_paths_from(scene, bvh, &rays, &pts, seed, &control, first)?.photons;
            if aimed {
                let texels: u64 = layers
                    .iter()
                    .filter(|l| l.light == light as usize)
                    .map(|l| l.res as u64 * l.res as u64)
                    .sum();
                let n =
                    ((texels as f64 * options.refine.photon_focus as f64).round() as u64).max(1);
                let set = emit_aimed_caustics(
                    scene,
                    bvh,
                    light as usize,
                    n,
                    &pts,
                    seed,
                    &control,
                    &focus,
                )?;
                stats.photons_emitted += n;
                photons.extend(set.photons);
            }
            traced += photons.len() as u64;
            stats.caustic_photons += photons
                .iter()
                .filter(|p| crate::photon::density::is_caustic(p))
                .count() as u64;
            // Volume radii are decided here, once, for the photon count the ring will hold
            // (the splat reads `footprint_radius`).
            let frames = (ring.held(light as usize) + 1).min(ring.frames()) as u64;
            let radius =
                VolumeRadius::of_scene(scene, options.photons * frames, options.kernel_scale)
                    .scaled(params.radius_scale);
            for p in &mut photons {
                p.footprint_radius = radius.of(p);
            }
            if options.refine.caustic_density_bound {
                crate::photon::density::bound_volume_radii(
                    &mut photons,
                    params.radius_scale,
                    radius.r_max,
                );
            }
            let mut compensated = Vec::new();
            if options.refine.boundary_compensation && !query_side {
                compensated = photons.clone();
                let tc = Instant::now();
                progress.update("boundary compensation", 0.0);
                boundary::compensate_until(
                    scene,
                    bvh,
                    &mut compensated,
                    |p| p.footprint_radius,
                    Z_RATIO,
                    seed,
                    &|| progress.cancelled(),
                );
                crate::cancel::check(progress)?;
                compensation_seconds += tc.elapsed().as_secs_f64();
            }
            ring.push(frame, light as usize, photons, compensated);
            start = end;
            if !progress.update("cpu trace", start as f64 / bm.rays.len() as f64) {
                return Err(Error::Cancelled);
            }
        }
    }
    stats.stages.push((
        "cpu trace".into(),
        t.elapsed().as_secs_f64() - compensation_seconds,
    ));
    if options.refine.boundary_compensation && !query_side {
        stats
            .stages
            .push(("boundary compensation".into(), compensation_seconds));
    }
    // Progressive mode: the direct light ray traced on the CPU (the GPU rendered the eye
    // G-buffer alone), added to the composite below; shadow maps are a bias no pass removes.
    let traced_direct = if params.progressive {
        let t = Instant::now();
        let d = super::progressive::direct_image(
            scene,
            bvh,
            options.direct.spp,
            params.seed,
            progress,
        )?;
        stage(&mut stats, "direct light (ray traced)", t);
        Some(d)
    } else {
        None
    };
    let photons = ring.collect();
    stats.photons_stored = photons.splat.len() as u64;
    let _ = traced;
    let photons_changed = !reuse;

    // 5. Mirrors and glass seen by the camera; their gather uses the photons as traced.
    let t = Instant::now();
    let specular = if state.specular && state.specular_image.is_some() && !photons_changed {
        state.specular_image.clone()
    } else if state.specular {
        let paths = SpecularPaths {
            samples: super::photon::camera_samples(options.direct.spp, options.max_depth, params),
            sampling: options.specular_sampling,
            gather: super::photon::knn_gather(scene, options.k, &options.kernel, params),
            precompute: !params.progressive,
        };
        let (img, camera_paths) = specular_paths(
            scene,
            bvh,
            &paths,
            photons.traced(),
            &mut state.specular_landings,
            progress,
        )?;
        stats.camera_paths = camera_paths;
        targets.write_specular(&ctx, &img);
        Some(img)
    } else {
        None
    };
    state.specular_image = specular.clone();
    stage(&mut stats, "specular paths", t);

    // 6. The indirect estimate, upsampling, composite, readback.
    let mut t = Instant::now();
    let radius = VolumeRadius::of_scene(scene, options.photons, options.kernel_scale)
        .scaled(params.radius_scale);
    state.estimate.set_sample_centre(targets.sample_centre());
    stats.estimator = state.estimate.kind().name().into();
    stats.estimator_reason = state.estimate_reason.clone();
    stats.first_bounce = state.first_bounce.0.name().into();
    stats.first_bounce_reason = state.first_bounce.1.clone();
    crate::cancel::check(progress)?;
    match &mut state.estimate {
        IndirectEstimate::Volumes(v) => {
            let (ordered, quads) = partition(
                options.volume_shape,
                &photons.splat,
                cam,
                options.subsample.max(1),
                radius,
            );
            stats.volume_quads = quads as u64;
            ctx.check_buffer("photon volumes", ordered.len() as u64 * 64)?;
            v.write_params(&ctx, scene, radius);
            if !ordered.is_empty() && (photons_changed || changes.camera) {
                v.write_photons(&ctx, &ordered);
            }
            v.set_draw(ordered.len() as u32, quads as u32);
        }
        IndirectEstimate::Binned(tl) => {
            if photons_changed {
                tl.write_photons(&ctx, &targets.gbuf, &photons.splat, cam)?;
            }
            tl.write_params(&ctx, scene, radius);
        }
        IndirectEstimate::Cpu(c) => {
            if photons_changed {
                c.set_photons(&photons.splat);
            }
            c.write_params(&ctx, scene, radius);
        }
    }
    stats.estimator_memory = state.estimate.memory();
    // A still frame (same photons, nothing moved) keeps last frame's estimate.
    let splat = photons_changed || changes.any() || !splat_current;
    let mut names = readback_names(images, true);
    let mut need = Vec::new();
    if query_side {
        need.extend(["position", "normals", "indirect"]);
    }
    for n in need {
        if !names.contains(&n) {
            names.push(n);
        }
    }
    if let (true, IndirectEstimate::Cpu(c)) = (splat, &mut state.estimate) {
        // Waits for the eye G-buffer (and the direct light submitted before it) when it was
        // redrawn; in serial frames, whose direct light was waited on, this is part of
        // "splat (wall)".
        let waited = c.compute(&ctx, &targets.gbuf, targets.gbuffer_generation)?;
        if !serial {
            if let Some(w) = waited {
                stats.stages.push(("gbuffer readback".into(), w));
            }
            let estimate = t.elapsed().as_secs_f64() - waited.unwrap_or(0.0);
            stats.stages.push(("cpu estimate".into(), estimate));
            t = Instant::now();
        }
        stats.estimator_memory = state.estimate.memory();
    }
    let data = loop {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("indirect estimate"),
            });
        if splat && serial {
            (encoder, t) = splat_serially(&ctx, &state.estimate, encoder, timer, &mut stats, t)?;
        } else if splat {
            state.estimate.record(&ctx, &mut encoder, timer);
        }
        targets.record_composite(&ctx, &mut encoder, timer);
        targets.record_readback(&ctx, &mut encoder, &names, Some(state.estimate.output().0));
        timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        stage(&mut stats, "photon upload", t);
        let t = Instant::now();
        let data = targets.read(&ctx, &names)?;
        stage(&mut stats, "readback", t);
        timer.collect(&ctx)?;
        // The binned estimators' lists are sized from the last frame: when they overflowed,
        // they have grown and the estimate is redone.
        if let (true, IndirectEstimate::Binned(tl)) = (splat, &mut state.estimate) {
            let t = Instant::now();
            if tl.overflowed(&ctx, &targets.gbuf)? {
                tl.write_params(&ctx, scene, radius);
                stats.estimator_memory = state.estimate.memory();
                stage(&mut stats, "photon lists regrown", t);
                continue;
            }
        }
        break data;
    };
    if splat {
        (stats.list_entries, stats.trivial_accepts) = state.estimate.list_entries();
    }
    stats.stages.append(&mut timer.totals);

    let mut out = assemble(scene, targets, &data, stats);
    let mut indirect = data.get("indirect").map(|a| rgb_image(w, h, a));
    if let (true, Some(ind), Some(pos), Some(nrm)) = (
        query_side,
        indirect.as_mut(),
        data.get("position"),
        data.get("normals"),
    ) {
        let t = Instant::now();
        let r = radius.diffuse();
        let coverage = super::progressive::query_coverage(scene, bvh, pos, nrm, r, params.seed);
        for ((o, i), c) in out
            .radiance
            .pixels
            .iter_mut()
            .zip(&mut ind.pixels)
            .zip(coverage)
        {
            let corrected = *i / c;
            *o += corrected - *i;
            *i = corrected;
        }
        out.stats
            .stages
            .push(("boundary compensation".into(), t.elapsed().as_secs_f64()));
    }
    let raster_direct = data.get("accum").map(|a| normalized(targets, a));
    if let Some(traced) = &traced_direct {
        // The composite holds no direct light (`record_gbuffer`): the ray-traced one added.
        for (o, t) in out.radiance.pixels.iter_mut().zip(&traced.pixels) {
            *o += *t;
        }
    }
    if images.extras {
        let empty = || Image::new(w, h);
        let direct = traced_direct.or(raster_direct).unwrap_or_else(empty);
        let indirect = indirect.unwrap_or_else(empty);
        let hits = photon_hits(scene, &out.position, photons.traced());
        out.aovs.push(("direct".into(), direct));
        out.aovs
            .push(("specular".into(), specular.unwrap_or_else(empty)));
        out.aovs.push(("indirect".into(), indirect));
        out.aovs.push(("photons".into(), hits));
    }
    state.traced_seed = Some(params.seed);
    state.splat_current = true;
    Ok(out)
}

/// The bounce maps of method `ispm` with `options` rendered on the GPU for `scene` and read
/// back once, for inspection and tests (the first frame's: the options' seed).
pub fn bounce_map(scene: &Scene, options: &super::RenderOptions) -> Result<BounceMap> {
    options.validate()?;
    let super::MethodOptions::Ispm(o) = &options.method else {
        return Err(Error::setting("method", "bounce maps are method `ispm`'s"));
    };
    let adapter = o.direct.adapter.as_deref();
    crate::raster::bounce::render_bounce_map(scene, adapter, o.photons, options.common.seed)
}

/// The splat recorded into `encoder` (the photons' upload began at `t`) and the upsampling,
/// each submitted and waited on and timed as "splat (wall)" and "upsample (wall)"
/// (`FrameDesc::serial`); returns the encoder for the rest of the frame and its start.
fn splat_serially(
    ctx: &GpuContext,
    estimate: &IndirectEstimate,
    mut encoder: wgpu::CommandEncoder,
    timer: &mut Timer,
    stats: &mut RenderStats,
    t: Instant,
) -> Result<(wgpu::CommandEncoder, Instant)> {
    let mut timed = |name: &str, t: Instant, encoder: wgpu::CommandEncoder| {
        ctx.queue.submit([encoder.finish()]);
        ctx.wait()?;
        stats
            .stages
            .push((name.to_string(), t.elapsed().as_secs_f64()));
        Ok::<_, Error>(Instant::now())
    };
    let new_encoder = |label| {
        ctx.device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
    };
    estimate.record_splat(ctx, &mut encoder, timer);
    let t = timed("splat (wall)", t, encoder)?;
    let mut upsample = new_encoder("upsampling");
    estimate.record_upsample(ctx, &mut upsample, timer);
    let t = timed("upsample (wall)", t, upsample)?;
    Ok((new_encoder("composite"), t))
}

/// The light of bounce-map photons of `light` and their angular spacing: the light's solid
/// angle over its bounce-map texels (a spot's square map covers about 4/π of its cone).
fn first_segment(scene: &Scene, layers: &[LightView], light: usize) -> FirstSegment {
    let l = &scene.lights[light];
    let texels: f64 = layers
        .iter()
        .filter(|b| b.light == light)
        .map(|b| (b.res as f64).powi(2))
        .sum();
    let omega = match l {
        crate::scene::Light::Point { .. } => l.solid_angle(),
        crate::scene::Light::Spot { .. } => l.solid_angle() * 4.0 / std::f32::consts::PI,
    };
    FirstSegment {
        position: l.position(),
        spacing: (omega as f64 / texels.max(1.0)).sqrt() as f32,
    }
}

/// Where the stored photons land, as seen from the camera: per pixel, the number of visible
/// photons of bounce 1 (green) and of later bounces (red).
fn photon_hits(scene: &Scene, position: &Image, photons: &[crate::photon::Photon]) -> Image {
    let cam = &scene.camera;
    let mut img = Image::new(cam.width, cam.height);
    for p in photons {
        let pos = p.position();
        let Some((x, y, _)) = cam.project(pos) else {
            continue;
        };
        let i = y as usize * cam.width as usize + x as usize;
        // Visible if the surface seen through the pixel is where the photon is.
        let seen = position.pixels[i];
        let dist = (pos - cam.position).length();
        if (seen - pos).length() > 0.02 * dist {
            continue;
        }
        img.pixels[i] += if p.bounce <= 1 { Vec3::Y } else { Vec3::X };
    }
    img
}
