//! Method `ispm` (McGuire & Luebke 2009) as a frame of the engine, one step a module:
//!
//! 1. [`first_hits`]: bounce maps (section 4.2) with the copies of their targets, submitted
//!    first (or, on CPU devices, the same photons' first hits cast in the CPU BVH at step
//!    3, [`crate::photon::bounce`]);
//! 2. shadow maps, direct light and the eye G-buffer ([`super::gpu::Targets`]), submitted
//!    without waiting;
//! 3. [`first_hits`]: the bounce-map readback, waiting for the bounce submission only
//!    (section 4.3), while the GPU renders the direct light;
//! 4. [`photons`]: temporal reuse (Jozwowski 2002), the CPU trace of the later bounces and
//!    the boundary compensation;
//! 5. [`specular`]: mirrors and glass seen by the camera, traced on the CPU (section 4);
//! 6. [`indirect`]: the photon estimate (section 5), upsampling, the composite on the GPU
//!    and the readback of the images asked for.

mod first_hits;
mod indirect;
mod photons;
mod specular;

use super::context::FrameCtx;
use super::gpu::{assemble, normalized, readback_names, Stale};
use super::gpu::{rgb_image, GpuScene, LightDraw, Targets};
use super::options::IspmOptions;
use super::{FrameParams, GpuState, Images, RenderOutput, RenderStats};
use crate::cancel::Progress;
use crate::error::{Error, Result};
use crate::gpu::timer::Timer;
use crate::gpu::GpuContext;
use crate::image::Image;
use crate::photon::bounce::BounceMap;
use crate::photon::radius::{SceneExtent, VolumeRadius};
use crate::photon::ring::{PhotonRing, RingPhotons};
use crate::scene::light_views::light_views;
use crate::scene::{Changes, Scene};
use crate::trace::SceneBvh;
use first_hits::FirstHits;
use glam::Vec3;
use indirect::{Indirect, IndirectFrame, Readback};
pub(super) use photons::Invalidation;
use specular::Specular;
use std::time::Instant;

/// What `ispm` keeps from one frame to the next beyond the direct light's resources.
pub(super) struct IspmState {
    first_hits: FirstHits,
    specular: Specular,
    indirect: Indirect,
    /// The seed of the photons in the ring, when they are those of the current scene: a
    /// still scene with frame-coherent random numbers re-traces nothing.
    traced_seed: Option<u64>,
}

impl IspmState {
    fn new(ctx: &GpuContext, targets: &mut Targets, scene: &Scene, o: &IspmOptions) -> Self {
        IspmState {
            first_hits: FirstHits::new(o.first_bounce.resolve(&ctx.info)),
            specular: Specular::new(scene),
            indirect: Indirect::new(ctx, targets, o),
            traced_seed: None,
        }
    }
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
    pub changes: Changes,
    pub draw: LightDraw,
    pub images: Images,
    pub progress: &'a dyn Progress,
}

/// Adds stage `name`, begun at `t`.
fn stage(stats: &mut RenderStats, name: &str, t: Instant) {
    stats
        .stages
        .push((name.to_string(), t.elapsed().as_secs_f64()));
}

pub(super) fn frame(f: FrameInputs) -> Result<RenderOutput> {
    let FrameInputs {
        gpu,
        ring,
        invalid,
        scene,
        bvh,
        options,
        params,
        frame,
        changes,
        draw,
        images,
        progress,
    } = f;
    let GpuState {
        ctx,
        scene: gs,
        targets,
        timer,
        ispm,
        serial,
        ..
    } = gpu;
    let (ctx, serial) = (ctx.clone(), *serial);
    timer.reset();
    let mut fc = FrameCtx {
        scene,
        bvh,
        params,
        progress,
        serial,
        stats: RenderStats {
            triangles: scene.triangle_count() as u64,
            samples_per_pixel: targets.spp(),
            ..Default::default()
        },
    };

    // Resources: created on the first frame at this size, else kept. Marked current again
    // only when the frame completes: a cancelled or failed frame leaves the next one to
    // redo its work.
    let t = Instant::now();
    // The bounce maps' share of the photons: the point and spot lights' of the power.
    // Derived once a frame and passed down: the photon budget (the bounce maps' layers are
    // sized from its share) and the volume radii of the frame's photons.
    let budget = photons::PhotonBudget::of(scene, options.photons);
    let extent = SceneExtent::of(scene);
    let radius = VolumeRadius::of_extent(extent, options.photons, options.kernel_scale)
        .scaled(params.radius_scale);
    let layers = light_views(scene, budget.maps);
    let state = ispm.get_or_insert_with(|| IspmState::new(&ctx, targets, scene, options));
    let traced_seed = state.traced_seed.take();
    let was_current = state.indirect.take_current();
    state.specular.invalidate(changes);
    // A still scene with frame-coherent random numbers has this frame's photons already.
    let reuse = ring.frames() == 1 && !changes.lighting() && traced_seed == Some(params.seed);
    let first_hits = &mut state.first_hits;
    first_hits.prepare(&ctx, scene, &gs.materials, &layers, params.seed, reuse)?;
    targets.write_eye(&ctx, scene, &gs.cull);
    fc.stage("upload", t);

    // 1. Bounce maps, submitted first with their readback copies.
    let bounce = first_hits.submit(&ctx, gs, &layers, reuse, timer, &mut fc)?;
    // 2. Direct light and the eye G-buffer, not waited on.
    record_direct_light(&ctx, gs, targets, timer, &mut fc, draw)?;
    // 3. The first hits: the bounce-map readback (or the traced first bounce).
    let bm = first_hits.finish(&ctx, &mut fc, &layers, bounce, reuse)?;
    // 4. Temporal reuse: drop what moved, trace this frame's photons per light, keep them.
    photons::invalidate(ring, &invalid, scene, radius);
    // Progressive mode normalises the kernels' boundary loss per pixel (query side) instead
    // of per photon, which leaves the crease pixels dark (`progressive::query_coverage`).
    // Only at full resolution: an upsampled estimate comes from other pixels' samples,
    // whose coverage differs (cornell 24x24, subsample 2: relMSE at 64 passes 0.0175
    // against 0.0072 with the photon-side compensation; subsample 1: 0.0012 against 0.0022).
    let query_side =
        params.progressive && options.refine.boundary_compensation && options.subsample <= 1;
    let trace = photons::Trace {
        scene,
        bvh,
        options,
        params,
        layers: &layers,
        budget,
        extent,
        frame,
        compensate: options.refine.boundary_compensation && !query_side,
        progress,
    };
    trace_or_reuse(&trace, &bm, reuse, ring, &mut fc.stats)?;
    // Progressive mode: the direct light ray traced on the CPU (the GPU rendered the eye
    // G-buffer alone), added to the composite below; shadow maps are a bias no pass removes.
    let traced_direct = traced_direct_light(scene, bvh, options, params, progress, &mut fc.stats)?;
    let photons = ring.collect();
    fc.stats.photons_stored = photons.splat.len() as u64;
    // 5. Mirrors and glass seen by the camera; their gather uses the photons as traced.
    let specular =
        state
            .specular
            .render(&ctx, targets, &mut fc, options, photons.traced(), !reuse)?;
    // 6. The indirect estimate, upsampling, composite, readback.
    fc.stats.first_bounce = first_hits.choice.0.name().into();
    fc.stats.first_bounce_reason = first_hits.choice.1.clone();
    crate::cancel::check(progress)?;
    let mut names = readback_names(images, true);
    if query_side {
        for n in ["position", "normals", "indirect"] {
            if !names.contains(&n) {
                names.push(n);
            }
        }
    }
    let indirect = IndirectFrame {
        scene,
        options,
        photons: &photons,
        photons_changed: !reuse,
        changes,
        was_current,
        names: &names,
        serial,
        radius,
    };
    let data = state
        .indirect
        .render(&ctx, targets, timer, &indirect, &mut fc.stats)?;
    fc.stats.stages.append(&mut timer.totals);
    let parts = Parts {
        data: &data,
        radius,
        query_side,
        traced_direct,
        specular,
        photons: &photons,
    };
    let out = output(scene, bvh, targets, params, parts, images, fc.stats);
    state.traced_seed = Some(params.seed);
    state.indirect.mark_current();
    Ok(out)
}

/// Step 2: the direct light (shadow maps, eye G-buffers, deferred shading) or, in
/// progressive mode (whose direct light is traced on the CPU), the eye G-buffer alone;
/// submitted, waited on and timed only in `serial` frames.
fn record_direct_light(
    ctx: &GpuContext,
    gs: &mut GpuScene,
    targets: &mut Targets,
    timer: &mut Timer,
    fc: &mut FrameCtx,
    draw: LightDraw,
) -> Result<()> {
    let (scene, progress) = (fc.scene, fc.progress);
    let t = Instant::now();
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("direct frame"),
        });
    let encoder = if fc.params.progressive {
        targets.record_gbuffer(ctx, gs, &mut encoder, timer);
        encoder
    } else {
        if gs.record_shadows(ctx, &mut encoder, timer, scene, draw) {
            targets.invalidate(Stale::SHADOWS);
        }
        targets.record_direct(ctx, gs, encoder, timer, progress)?
    };
    ctx.queue.submit([encoder.finish()]);
    if fc.serial {
        ctx.wait()?;
        fc.stage("direct light (wall)", t);
    }
    Ok(())
}

/// Step 4's trace, unless the frame reuses the photons it has (or traces no later bounce):
/// then the stage is empty.
fn trace_or_reuse(
    trace: &photons::Trace,
    bm: &BounceMap,
    reuse: bool,
    ring: &mut PhotonRing,
    stats: &mut RenderStats,
) -> Result<()> {
    if !reuse && trace.options.max_depth >= 2 {
        return trace.run(bm, ring, stats);
    }
    stats.stages.push(("cpu trace".into(), 0.0));
    if trace.compensate {
        stats.stages.push(("boundary compensation".into(), 0.0));
    }
    Ok(())
}

/// The direct light ray traced on the CPU, in progressive mode.
fn traced_direct_light(
    scene: &Scene,
    bvh: &SceneBvh,
    options: &IspmOptions,
    params: &FrameParams,
    progress: &dyn Progress,
    stats: &mut RenderStats,
) -> Result<Option<Image>> {
    if !params.progressive {
        return Ok(None);
    }
    let t = Instant::now();
    let seed = params.seed;
    let d = super::progressive::direct_image(scene, bvh, options.direct.spp, seed, progress)?;
    stage(stats, "direct light (ray traced)", t);
    Ok(Some(d))
}

/// What the frame's output is assembled from.
struct Parts<'a> {
    data: &'a Readback,
    radius: VolumeRadius,
    query_side: bool,
    traced_direct: Option<Image>,
    specular: Option<Image>,
    photons: &'a RingPhotons,
}

/// The frame's images: the composite read back, corrected per pixel for the kernels'
/// boundary loss (progressive, query side), with the ray-traced direct light added
/// (progressive), and the method's own images (`direct`, `specular`, `indirect`,
/// `photons`) when asked for.
fn output(
    scene: &Scene,
    bvh: &SceneBvh,
    targets: &Targets,
    params: &FrameParams,
    parts: Parts,
    images: Images,
    stats: RenderStats,
) -> RenderOutput {
    let (w, h) = (targets.width, targets.height);
    let data = parts.data;
    let mut out = assemble(scene, targets, data, stats);
    let mut indirect = data.get("indirect").map(|a| rgb_image(w, h, a));
    if let (true, Some(ind), Some(pos), Some(nrm)) = (
        parts.query_side,
        indirect.as_mut(),
        data.get("position"),
        data.get("normals"),
    ) {
        let t = Instant::now();
        let r = parts.radius.diffuse();
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
        stage(&mut out.stats, "boundary compensation", t);
    }
    let raster_direct = data.get("accum").map(|a| normalized(targets, a));
    if let Some(traced) = &parts.traced_direct {
        // The composite holds no direct light (`record_gbuffer`): the ray-traced one added.
        for (o, t) in out.radiance.pixels.iter_mut().zip(&traced.pixels) {
            *o += *t;
        }
    }
    if images.extras {
        let empty = || Image::new(w, h);
        let direct = parts.traced_direct.or(raster_direct).unwrap_or_else(empty);
        let indirect = indirect.unwrap_or_else(empty);
        let hits = photon_hits(scene, &out.position, parts.photons.traced());
        out.aovs.push(("direct".into(), direct));
        let specular = parts.specular.unwrap_or_else(empty);
        out.aovs.push(("specular".into(), specular));
        out.aovs.push(("indirect".into(), indirect));
        out.aovs.push(("photons".into(), hits));
    }
    out
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
