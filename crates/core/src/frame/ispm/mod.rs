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
mod gpu_trace;
mod indirect;
mod photons;
mod resident;
mod specular;

use super::context::FrameCtx;
use super::gpu::{normalized, readback_names, rgb_image};
use super::gpu::{GpuFrame, LightDraw, Readback, Targets};
use super::options::IspmOptions;
use super::{GpuState, Images, RenderOutput};
use crate::error::{Error, Result};
use crate::gpu::photon::resident::ResidentPhotons;
use crate::gpu::photon::PhotonTrace;
use crate::gpu::GpuContext;
use crate::image::Image;
use crate::photon::bounce::BounceMap;
use crate::photon::radius::{SceneExtent, VolumeRadius};
use crate::photon::ring::{PhotonRing, RingPhotons};
use crate::photon::sky_pilot::KeptPilot;
use crate::scene::light_views::light_views;
use crate::scene::{Changes, Scene};
use first_hits::FirstHits;
use glam::Vec3;
use gpu_trace::GpuTrace;
use indirect::{Indirect, IndirectFrame};
pub(super) use photons::Invalidation;
use specular::Specular;

/// What `ispm` keeps from one frame to the next beyond the direct light's resources.
pub(super) struct IspmState {
    first_hits: FirstHits,
    /// Where the later bounces are traced (`photon_trace`).
    gpu_trace: GpuTrace,
    specular: Specular,
    indirect: Indirect,
    /// The seed of the photons in the ring, when they are those of the current scene: a
    /// still scene with frame-coherent random numbers re-traces nothing.
    traced_seed: Option<u64>,
    /// The ring's photons as last collected, with the ring's generation then
    /// ([`PhotonRing::generation`]): a frame whose ring did not change collects nothing.
    collected: Option<(u64, RingPhotons)>,
    /// The last traced frame's photons when they stayed on the GPU (`resident`).
    resident: Option<ResidentPhotons>,
    /// The sky's pilot (`photon/sky_pilot.rs`), dropped when geometry or materials change.
    sky_pilot: KeptPilot,
}

impl IspmState {
    fn new(
        ctx: &GpuContext,
        targets: &mut Targets,
        scene: &Scene,
        o: &IspmOptions,
    ) -> Result<Self> {
        let (bounce, reason) = o.first_bounce.resolve(&ctx.info);
        Ok(IspmState {
            first_hits: FirstHits::new(bounce, reason),
            gpu_trace: GpuTrace::new(ctx, scene, o)?,
            specular: Specular::new(scene),
            indirect: Indirect::new(ctx, targets, o),
            traced_seed: None,
            collected: None,
            resident: None,
            sky_pilot: KeptPilot::default(),
        })
    }
}

pub(super) struct FrameInputs<'a> {
    pub gpu: &'a mut GpuState,
    pub fc: FrameCtx<'a>,
    pub ring: &'a mut PhotonRing,
    pub invalid: Invalidation<'a>,
    pub options: &'a IspmOptions,
    pub frame: u64,
    pub changes: Changes,
    pub draw: LightDraw,
    pub images: Images,
}

pub(super) fn frame(f: FrameInputs) -> Result<RenderOutput> {
    let FrameInputs {
        gpu,
        mut fc,
        ring,
        invalid,
        options,
        frame,
        changes,
        draw,
        images,
    } = f;
    let GpuState {
        ctx,
        scene: gs,
        targets,
        timer,
        ispm,
        ..
    } = gpu;
    let (scene, params) = (fc.scene, fc.params);

    // Resources: created on the first frame at this size, else kept. Marked current again
    // only when the frame completes: a cancelled or failed frame leaves the next one to
    // redo its work.
    // The bounce maps' share of the photons: the point and spot lights' of the power.
    // Derived once a frame and passed down: the photon budget (the bounce maps' layers are
    // sized from its share) and the volume radii of the frame's photons.
    let budget = photons::PhotonBudget::of(scene, options.photons);
    let extent = SceneExtent::of(scene);
    let radius = VolumeRadius::of_extent(extent, options.photons, options.kernel_scale)
        .scaled(params.radius_scale);
    let layers = light_views(scene, budget.maps);
    let state = match ispm {
        Some(s) => s,
        None => ispm.insert(IspmState::new(ctx, targets, scene, options)?),
    };
    let traced_seed = state.traced_seed.take();
    let was_current = state.indirect.take_current();
    state.specular.invalidate(changes);
    state.sky_pilot.invalidate(changes);
    // A still scene with frame-coherent random numbers has this frame's photons already.
    let reuse = ring.frames() == 1 && !changes.lighting() && traced_seed == Some(params.seed);
    let first_hits = &mut state.first_hits;
    fc.timed("upload", |_| {
        first_hits.prepare(ctx, scene, gs, &layers, params.seed, reuse)
    })?;
    let mut gpu = GpuFrame::begin(ctx, gs, targets, timer, &mut fc);
    // A still frame (the same photons and estimate, nothing moved, the direct light kept)
    // reads back the last frame's output again ([`Targets::output_kept`]).
    let still = reuse && !changes.any() && was_current && gpu.targets.direct_current();

    // 1. Bounce maps, submitted first with their readback copies.
    let bounce = first_hits.submit(&mut gpu, &mut fc, &layers, reuse)?;
    // 2. Direct light and the eye G-buffer, not waited on.
    record_direct_light(&mut gpu, &mut fc, draw)?;
    // 3. The first hits: the bounce-map readback (or the traced first bounce).
    let bm = first_hits.finish(&gpu.ctx, &mut fc, &layers, bounce, reuse)?;
    // 4. Temporal reuse: drop what moved, trace this frame's photons per light, keep them.
    photons::invalidate(ring, &invalid, scene, radius);
    // Progressive mode normalises the kernels' boundary loss per pixel (query side) instead
    // of per photon, which leaves the crease pixels dark (`progressive::query_coverage`).
    // Only at full resolution: an upsampled estimate comes from other pixels' samples,
    // whose coverage differs (cornell 24x24, subsample 2: relMSE at 64 passes 0.0175
    // against 0.0072 with the photon-side compensation; subsample 1: 0.0012 against 0.0022).
    let query_side =
        params.progressive && options.refine.boundary_compensation && options.subsample <= 1;
    let tracing = !reuse && options.max_depth >= 2;
    let compensate = options.refine.boundary_compensation && !query_side;
    let need = resident::Need {
        fc: &fc,
        options,
        estimator: state.indirect.kind(),
        images,
        ring_frames: ring.frames(),
        cpu_photons: budget.cpu,
        compensate,
    };
    let records =
        (state.gpu_trace.choice == PhotonTrace::Gpu).then(|| resident::readback_reason(&need));
    fc.stats.photon_records = records.as_ref().map(resident::stat).unwrap_or_default();
    let gpu_scene = match tracing {
        true => state.gpu_trace.scene(ctx, &mut fc, changes)?,
        false => None,
    };
    let sizing = resident::sizing(&records, scene, radius, gpu.targets.height);
    let trace = photons::Trace {
        gpu: gpu_scene.map(|scene| photons::OnGpu { ctx, scene }),
        resident: sizing,
        scene,
        bvh: fc.bvh()?,
        options,
        params,
        layers: &layers,
        budget,
        extent,
        frame,
        compensate,
        sky_pilot: &state.sky_pilot,
        progress: fc.progress,
    };
    trace_or_reuse(&trace, &bm, reuse, ring, &mut state.resident, &mut fc)?;
    // Progressive mode: the direct light ray traced on the CPU (the GPU rendered the eye
    // G-buffer alone), added to the composite below; shadow maps are a bias no pass removes.
    let traced_direct = traced_direct_light(&mut fc, options)?;
    let photons = collect(&mut state.collected, ring, &mut fc);
    fc.stats.photons_stored = resident::stored(&state.resident, photons);
    // 5. Mirrors and glass seen by the camera; their gather uses the photons as traced.
    let specular = state
        .specular
        .render(&gpu, &mut fc, options, photons.traced(), !reuse)?;
    // 6. The indirect estimate, upsampling, composite, readback.
    fc.stats.first_bounce = first_hits.bounce.name().into();
    fc.stats.first_bounce_reason = first_hits.reason.clone();
    fc.stats.photon_trace = state.gpu_trace.choice.name().into();
    fc.stats.photon_trace_reason = state.gpu_trace.reason.clone();
    crate::cancel::check(fc.progress)?;
    let names = names_to_read(images, query_side);
    let indirect = IndirectFrame {
        scene,
        options,
        photons,
        resident: state.resident.as_ref(),
        photons_changed: !reuse,
        changes,
        was_current,
        names: &names,
        serial: fc.serial,
        radius,
    };
    gpu.targets.set_still(still);
    let data = state.indirect.render(&mut gpu, &mut fc, &indirect)?;
    let parts = Parts {
        data: &data,
        radius,
        query_side,
        traced_direct,
        specular,
        photons,
    };
    let out = output(&gpu, parts, images, fc)?;
    state.traced_seed = Some(params.seed);
    state.indirect.mark_current();
    Ok(out)
}

/// The images the frame reads back: those asked for, and with the query-side boundary
/// compensation (progressive mode) the position, normals and indirect estimate it needs.
fn names_to_read(images: Images, query_side: bool) -> Vec<&'static str> {
    let mut names = readback_names(images, true);
    if query_side {
        for n in ["position", "normals", "indirect"] {
            if !names.contains(&n) {
                names.push(n);
            }
        }
    }
    names
}

/// Step 2: the direct light (shadow maps, eye G-buffers, deferred shading) or, in
/// progressive mode (whose direct light is traced on the CPU), the eye G-buffer alone;
/// submitted, waited on and timed only in `serial` frames.
fn record_direct_light(gpu: &mut GpuFrame, fc: &mut FrameCtx, draw: LightDraw) -> Result<()> {
    let mut record = |fc: &mut FrameCtx| {
        let mut encoder = gpu.encoder("direct frame");
        let encoder = if fc.params.progressive {
            let (ctx, timer) = (&gpu.ctx, &mut *gpu.timer);
            gpu.targets
                .record_gbuffer(ctx, gpu.scene, &mut encoder, timer);
            encoder
        } else {
            gpu.record_shadows(&mut encoder, fc, draw);
            gpu.record_direct(encoder, fc)?
        };
        gpu.ctx.queue.submit([encoder.finish()]);
        if fc.serial {
            gpu.ctx.wait()?;
        }
        Ok(())
    };
    if fc.serial {
        fc.timed("direct light (wall)", record)
    } else {
        record(fc)
    }
}

/// Step 4's trace, unless the frame reuses the photons it has (or traces no later bounce):
/// then the stage is empty. A trace replaces `kept` with the photons it left on the GPU.
fn trace_or_reuse(
    trace: &photons::Trace,
    bm: &BounceMap,
    reuse: bool,
    ring: &mut PhotonRing,
    kept: &mut Option<ResidentPhotons>,
    fc: &mut FrameCtx,
) -> Result<()> {
    if !reuse && trace.options.max_depth >= 2 {
        *kept = trace.run(bm, ring, fc)?;
        return Ok(());
    }
    fc.add_stage("cpu trace", 0.0);
    if trace.compensate {
        fc.add_stage("boundary compensation", 0.0);
    }
    Ok(())
}

/// The ring's valid photons, weighted (stage "photon collect"): collected again only when
/// the ring changed since the collection kept in `kept` (a still frame, or a camera move
/// that reuses its photons, collects nothing: the stage is 0).
fn collect<'a>(
    kept: &'a mut Option<(u64, RingPhotons)>,
    ring: &PhotonRing,
    fc: &mut FrameCtx,
) -> &'a RingPhotons {
    let generation = ring.generation();
    let photons = match kept.take() {
        Some((g, photons)) if g == generation => {
            fc.add_stage("photon collect", 0.0);
            photons
        }
        _ => fc.timed("photon collect", |_| ring.collect()),
    };
    &kept.insert((generation, photons)).1
}

/// The direct light ray traced on the CPU, in progressive mode.
fn traced_direct_light(fc: &mut FrameCtx, options: &IspmOptions) -> Result<Option<Image>> {
    if !fc.params.progressive {
        return Ok(None);
    }
    let (scene, bvh, seed, progress) = (fc.scene, fc.bvh()?, fc.params.seed, fc.progress);
    let spp = options.direct.spp;
    let d = fc.timed("direct light (ray traced)", |_| {
        super::progressive::direct_image(scene, bvh, spp, seed, progress)
    })?;
    Ok(Some(d))
}

/// What the frame's output is assembled from.
struct Parts<'a> {
    data: &'a Readback,
    radius: VolumeRadius,
    query_side: bool,
    traced_direct: Option<Image>,
    specular: Option<&'a Image>,
    photons: &'a RingPhotons,
}

/// The frame's images: the composite read back, corrected per pixel for the kernels'
/// boundary loss (progressive, query side), with the ray-traced direct light added
/// (progressive), and the method's own images (`direct`, `specular`, `indirect`,
/// `photons`) when asked for.
fn output(gpu: &GpuFrame, parts: Parts, images: Images, mut fc: FrameCtx) -> Result<RenderOutput> {
    let targets = &*gpu.targets;
    let (w, h) = (targets.width, targets.height);
    let data = parts.data;
    let (scene, bvh, seed) = (fc.scene, fc.bvh()?, fc.params.seed);
    let mut indirect = data.get("indirect").map(|a| rgb_image(w, h, a));
    // The coverage is computed before the output is assembled (which takes the stats),
    // and applied to it after.
    let coverage = match (parts.query_side, data.get("position"), data.get("normals")) {
        (true, Some(pos), Some(nrm)) if indirect.is_some() => {
            let r = parts.radius.diffuse();
            Some(fc.timed("boundary compensation", |_| {
                super::progressive::query_coverage(scene, bvh, pos, nrm, r, seed)
            }))
        }
        _ => None,
    };
    let mut out = gpu.output(data, fc);
    if let (Some(ind), Some(coverage)) = (indirect.as_mut(), coverage) {
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
        let specular = parts.specular.cloned().unwrap_or_else(empty);
        out.aovs.push(("specular".into(), specular));
        out.aovs.push(("indirect".into(), indirect));
        out.aovs.push(("photons".into(), hits));
    }
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
