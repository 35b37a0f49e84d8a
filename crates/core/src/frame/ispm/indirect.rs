//! Step 6 of an `ispm` frame: the indirect estimate over the frame's photons (the chosen
//! estimator: photon volumes, binned compute passes or the CPU sum; section 5), its
//! upsampling, the composite with the direct and specular light, and the readback of the
//! images asked for.
//!
//! At `subsample` > 1 the caustic photons (`photon::density::is_caustic`: no diffuse bounce,
//! the narrow kernels) are splatted at full resolution by a second estimator of the same
//! kind, whose estimate the upsampling adds. Their light has the detail of their kernels,
//! which the low-resolution samples alias: a caustic smaller than a low-resolution texel was
//! spread over its neighbours at that texel's value or missed (cornell-glass 48×48, the
//! glass sphere's caustic: the image mean 1.25% above the full-resolution splat's,
//! `scripts/probe/caustic_breakdown.py`). The paper's upsampling is the step it calls
//! inconsistent (section 5.2); the diffuse photons' smooth light keeps it.

use super::super::context::FrameCtx;
use super::super::gpu::{GpuFrame, Readback, Targets};
use super::super::options::IspmOptions;
use crate::error::{Error, Result};
use crate::estimate::volume_shape::partition;
use crate::estimate::{Binned, CpuEstimate, Estimator, IndirectEstimate, Mode, Volumes};
use crate::gpu::photon::resident::ResidentPhotons;
use crate::gpu::GpuContext;
use crate::photon::density::is_caustic;
use crate::photon::radius::VolumeRadius;
use crate::photon::ring::RingPhotons;
use crate::photon::Photon;
use crate::scene::{Changes, Scene};
use std::time::Instant;

/// The indirect estimator of a renderer, kept across frames.
pub(super) struct Indirect {
    estimate: IndirectEstimate,
    /// At subsample > 1, the caustic photons' estimate at full resolution (added by the
    /// upsampling of `estimate`, which splats the others).
    caustics: Option<IndirectEstimate>,
    /// Why the estimator was chosen (`Estimator::resolve`).
    reason: String,
    /// Whether the estimator's output is this scene's and camera's.
    current: bool,
    /// The photons the last upload drew as quads (volumes; the frame's statistic).
    quads: u64,
}

/// What the estimate of a frame splats and reads back.
pub(super) struct IndirectFrame<'a> {
    pub scene: &'a Scene,
    pub options: &'a IspmOptions,
    pub photons: &'a RingPhotons,
    /// The frame's photons when they stayed on the GPU (then `photons` holds none).
    pub resident: Option<&'a ResidentPhotons>,
    /// The photons are not last frame's.
    pub photons_changed: bool,
    pub changes: Changes,
    /// The estimator's output was current before this frame.
    pub was_current: bool,
    /// The textures to read back.
    pub names: &'a [&'static str],
    /// Wait and time each stage (`FrameDesc::serial`).
    pub serial: bool,
    /// The frame's volume radii (kernel-scaled), made once a frame by the orchestrator.
    pub radius: VolumeRadius,
}

impl Indirect {
    /// The estimator `options` ask for on this adapter, over `targets` (and the composite
    /// pointed at its output).
    pub fn new(ctx: &GpuContext, targets: &mut Targets, options: &IspmOptions) -> Self {
        let (kind, reason) = options.estimator.resolve(&ctx.info);
        let (gbuf, k) = (&targets.gbuf, options.subsample.max(1));
        let caustics = (k > 1).then(|| estimator(ctx, targets, kind, 1));
        let mut estimate = estimator(ctx, targets, kind, k);
        if let Some(c) = &caustics {
            estimate.add_full_resolution(ctx, gbuf, c);
        }
        targets.bind_composite(ctx, Some(estimate.output().1));
        Indirect {
            estimate,
            caustics,
            reason,
            current: false,
            quads: 0,
        }
    }

    /// The estimator that runs (the caustic photons' too, if apart).
    pub fn kind(&self) -> Estimator {
        self.estimate.kind()
    }

    /// The estimators: the main one, then the caustic photons' (if apart).
    fn estimates(&self) -> impl Iterator<Item = &IndirectEstimate> {
        std::iter::once(&self.estimate).chain(&self.caustics)
    }

    /// Whether the output is current, set false until the frame completes (a cancelled or
    /// failed frame leaves the next one to redo its work).
    pub fn take_current(&mut self) -> bool {
        std::mem::replace(&mut self.current, false)
    }

    /// The frame completed: its output is current.
    pub fn mark_current(&mut self) {
        self.current = true;
    }

    /// Uploads the frame's photons and parameters, splats them (unless a still frame keeps
    /// last frame's estimate), composites and reads back `f.names`; returns the read-back
    /// textures.
    pub fn render(
        &mut self,
        gpu: &mut GpuFrame,
        fc: &mut FrameCtx,
        f: &IndirectFrame,
    ) -> Result<Readback> {
        let mut t = Instant::now();
        let scene = f.scene;
        let radius = f.radius;
        let centre = gpu.targets.sample_centre();
        self.estimate.set_sample_centre(centre);
        if let Some(c) = &mut self.caustics {
            c.set_sample_centre(centre);
        }
        fc.stats.estimator = self.estimate.kind().name().into();
        fc.stats.estimator_reason = self.reason.clone();
        // A still frame (same photons, nothing moved) keeps last frame's estimate, and
        // with it the photons and parameters uploaded for it: no photon is touched.
        let splat = f.photons_changed || f.changes.any() || !f.was_current;
        if splat {
            self.quads = self.upload(&gpu.ctx, gpu.targets, f, radius)?;
        }
        fc.stats.volume_quads = self.quads;
        fc.stats.estimator_memory = self.memory();
        if splat && self.estimate.kind() == Estimator::Cpu {
            // Waits for the eye G-buffer (and the direct light submitted before it) when it
            // was redrawn; in serial frames, whose direct light was waited on, this is part
            // of "splat (wall)".
            let mut waited = None;
            let generation = gpu.targets.gbuffer_generation;
            for e in std::iter::once(&mut self.estimate).chain(&mut self.caustics) {
                if let IndirectEstimate::Cpu(c) = e {
                    if let Some(w) = c.compute(&gpu.ctx, (&gpu.targets.gbuf, scene), generation)? {
                        waited = Some(waited.unwrap_or(0.0) + w);
                    }
                }
            }
            if !f.serial {
                // The estimate's time less the G-buffer readback it waited for.
                if let Some(w) = waited {
                    fc.add_stage("gbuffer readback", w);
                }
                let estimate = t.elapsed().as_secs_f64() - waited.unwrap_or(0.0);
                fc.add_stage("cpu estimate", estimate);
                t = Instant::now();
            }
            fc.stats.estimator_memory = self.memory();
        }
        let data = loop {
            let mut encoder = gpu.encoder("indirect estimate");
            if splat && f.serial {
                (encoder, t) = splat_serially(gpu, self, encoder, fc, t)?;
            } else if splat {
                // The caustic estimate first: the main one's upsampling adds it.
                if let Some(c) = &self.caustics {
                    c.record(&gpu.ctx, &mut encoder, gpu.timer);
                }
                self.estimate.record(&gpu.ctx, &mut encoder, gpu.timer);
            }
            fc.add_stage("photon upload", t.elapsed().as_secs_f64());
            let indirect = Some(self.estimate.output().0);
            let data = gpu.finish(encoder, f.names, indirect, fc)?;
            // The binned estimators' lists are sized from the last frame: when they
            // overflowed, they have grown and the estimate is redone.
            if splat && self.regrown(gpu, fc, scene, radius)? {
                t = Instant::now();
                continue;
            }
            break data;
        };
        if splat {
            let entries = self.estimates().map(|e| e.list_entries());
            (fc.stats.list_entries, fc.stats.trivial_accepts) =
                entries.fold((0, 0), |(a, b), (c, d)| (a + c, b + d));
        }
        Ok(data)
    }

    /// The binned estimators, after the frame's submission: whether any one's lists
    /// overflowed (then they have grown, and the caller records again).
    fn regrown(
        &mut self,
        gpu: &GpuFrame,
        fc: &mut FrameCtx,
        scene: &Scene,
        radius: VolumeRadius,
    ) -> Result<bool> {
        let t = Instant::now();
        let mut regrown = false;
        for e in std::iter::once(&mut self.estimate).chain(&mut self.caustics) {
            if let IndirectEstimate::Binned(tl) = e {
                if tl.overflowed(&gpu.ctx, &gpu.targets.gbuf)? {
                    tl.write_params(&gpu.ctx, scene, radius);
                    regrown = true;
                }
            }
        }
        if regrown {
            fc.stats.estimator_memory = self.memory();
            fc.add_stage("photon lists regrown", t.elapsed().as_secs_f64());
        }
        Ok(regrown)
    }

    /// The estimators' memory by part (the caustic estimate's parts named so).
    fn memory(&self) -> Vec<(String, u64)> {
        let mut parts = self.estimate.memory();
        if let Some(c) = &self.caustics {
            // Buffers not yet allocated (a frame without caustic photons) are left out.
            let caustic = c.memory().into_iter().filter(|(_, b)| *b > 0);
            parts.extend(caustic.map(|(n, b)| (format!("caustics: {n}"), b)));
        }
        parts
    }

    /// Uploads the photons (when they or, for the volumes' order, the camera changed) and
    /// the view-dependent parameters: the caustic photons to their own estimator where
    /// they are splatted apart. Returns the photons drawn as quads (volumes).
    fn upload(
        &mut self,
        ctx: &GpuContext,
        targets: &Targets,
        f: &IndirectFrame,
        radius: VolumeRadius,
    ) -> Result<u64> {
        // Photons left on the GPU (`super::resident`: a binned estimator at subsample 1,
        // already sized there) are copied into the photon texture on the GPU.
        if let (Some(r), IndirectEstimate::Binned(tl)) = (f.resident, &mut self.estimate) {
            if f.photons_changed {
                tl.copy_photons(ctx, &targets.gbuf, &r.buffer, r.count)?;
            }
            tl.write_params(ctx, f.scene, radius);
            return Ok(0);
        }
        let (mut caustic, mut rest): (Vec<Photon>, Vec<Photon>) =
            f.photons.splat.iter().partition(|p| is_caustic(p));
        at_least_a_pixel(&mut caustic, &f.scene.camera, targets.height);
        let k = f.options.subsample.max(1);
        let Some(caustics) = &mut self.caustics else {
            rest.append(&mut caustic);
            return upload(&mut self.estimate, ctx, targets, f, &rest, k, radius);
        };
        Ok(
            upload(&mut self.estimate, ctx, targets, f, &rest, k, radius)?
                + upload(caustics, ctx, targets, f, &caustic, 1, radius)?,
        )
    }
}

/// Widens the kernels of the caustic `photons` to at least the footprint of a pixel of an
/// image `height` pixels high seen by `cam` at the photon's distance.
///
/// A pixel's value is the mean of its area's light, but the estimators read the light at
/// one point per pixel: a caustic narrower than a pixel is then counted whole where it
/// covers a pixel's centre and not at all elsewhere, which does not average out over seeds
/// (the caustic lies where the geometry puts it). cornell-glass at 32x32: the glass
/// sphere's caustic (0.3% of the pixels) put the image mean 1.8% above `path`'s
/// (`scripts/probe/caustic_breakdown.py`). A kernel at least a pixel wide makes the point reading
/// the kernel's mean over about a pixel, as the pixel's own filter would; the kernels are
/// normalised, so no light is added or lost. The footprint is from this frame's camera
/// (the binned and CPU estimators keep it until the photons change).
fn at_least_a_pixel(photons: &mut [Photon], cam: &crate::scene::Camera, height: u32) {
    let per_metre = pixel_per_metre(cam, height);
    for p in photons {
        let pixel = (p.position() - cam.position).length() * per_metre;
        p.footprint_radius = p.footprint_radius.max(pixel);
    }
}

/// The least caustic kernel radius per metre from `cam` in an image `height` pixels high
/// ([`at_least_a_pixel`]; the GPU-kept photons are widened by it on the GPU).
pub(super) fn pixel_per_metre(cam: &crate::scene::Camera, height: u32) -> f32 {
    PIXEL_RADII * 2.0 * (cam.fov_y.to_radians() / 2.0).tan() / height.max(1) as f32
}

/// The least caustic kernel radius, in pixel footprints ([`at_least_a_pixel`]).
const PIXEL_RADII: f32 = 1.0;

/// The estimator `kind` over the eye G-buffer of `targets` (and its materials' exact
/// models), at 1/`k` resolution.
fn estimator(ctx: &GpuContext, targets: &Targets, kind: Estimator, k: u32) -> IndirectEstimate {
    let (gbuf, models) = (&targets.gbuf, &targets.model_materials);
    let [w, h] = [targets.width, targets.height];
    let binned = |mode| {
        IndirectEstimate::Binned(Box::new(Binned::new(ctx, (gbuf, models), mode, [w, h], k)))
    };
    match kind {
        Estimator::Tiled => binned(Mode::Tiled),
        Estimator::Cluster => binned(Mode::Cluster),
        Estimator::Directional => binned(Mode::Directional),
        Estimator::Cpu => IndirectEstimate::Cpu(Box::new(CpuEstimate::new(ctx, gbuf, w, h, k))),
        Estimator::Volumes | Estimator::Auto => {
            IndirectEstimate::Volumes(Box::new(Volumes::new(ctx, (gbuf, models), w, h, k)))
        }
    }
}

/// Uploads `photons` to `estimate` (splatting at 1/`k` resolution) when they or, for the
/// volumes' order, the camera changed, and the view-dependent parameters; returns the
/// photons drawn as quads (volumes).
fn upload(
    estimate: &mut IndirectEstimate,
    ctx: &GpuContext,
    targets: &Targets,
    f: &IndirectFrame,
    photons: &[Photon],
    k: u32,
    radius: VolumeRadius,
) -> Result<u64> {
    let (scene, cam) = (f.scene, &f.scene.camera);
    match estimate {
        IndirectEstimate::Volumes(v) => {
            let (ordered, quads) = partition(f.options.volume_shape, photons, cam, k, radius);
            ctx.check_buffer("photon volumes", ordered.len() as u64 * 64)?;
            v.write_params(ctx, scene, radius);
            if !ordered.is_empty() && (f.photons_changed || f.changes.camera) {
                v.write_photons(ctx, &ordered);
            }
            v.set_draw(ordered.len() as u32, quads as u32);
            Ok(quads as u64)
        }
        IndirectEstimate::Binned(tl) => {
            if f.photons_changed {
                tl.write_photons(ctx, &targets.gbuf, photons, cam)?;
            }
            tl.write_params(ctx, scene, radius);
            Ok(0)
        }
        IndirectEstimate::Cpu(c) => {
            if f.photons_changed {
                c.set_photons(photons);
            }
            c.write_params(ctx, scene, radius);
            Ok(0)
        }
    }
}

/// The splats recorded into `encoder` (the photons' upload began at `t`) and the upsampling,
/// each submitted and waited on and timed as "splat (wall)" and "upsample (wall)"
/// (`FrameDesc::serial`); returns the encoder for the rest of the frame and its start.
fn splat_serially(
    gpu: &mut GpuFrame,
    indirect: &Indirect,
    mut encoder: wgpu::CommandEncoder,
    fc: &mut FrameCtx,
    t: Instant,
) -> Result<(wgpu::CommandEncoder, Instant)> {
    // Each wall stage runs from the end of the last one (the first from `t`).
    let ctx = gpu.ctx.clone();
    let mut timed = |name: &str, t: Instant, encoder: wgpu::CommandEncoder| {
        ctx.queue.submit([encoder.finish()]);
        ctx.wait()?;
        fc.add_stage(name, t.elapsed().as_secs_f64());
        Ok::<_, Error>(Instant::now())
    };
    for e in indirect.estimates() {
        e.record_splat(&gpu.ctx, &mut encoder, gpu.timer);
    }
    let t = timed("splat (wall)", t, encoder)?;
    let mut upsample = gpu.encoder("upsampling");
    indirect
        .estimate
        .record_upsample(&gpu.ctx, &mut upsample, gpu.timer);
    let t = timed("upsample (wall)", t, upsample)?;
    Ok((gpu.encoder("composite"), t))
}
