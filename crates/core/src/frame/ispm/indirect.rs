//! Step 6 of an `ispm` frame: the indirect estimate over the frame's photons (the chosen
//! estimator: photon volumes, binned compute passes or the CPU sum; section 5), its
//! upsampling, the composite with the direct and specular light, and the readback of the
//! images asked for.

use super::super::gpu::Targets;
use super::super::options::IspmOptions;
use super::super::{FrameParams, RenderStats};
use super::stage;
use crate::error::{Error, Result};
use crate::estimate::volume_shape::partition;
use crate::estimate::{Binned, CpuEstimate, Estimator, IndirectEstimate, Mode, Volumes};
use crate::gpu::timer::Timer;
use crate::gpu::GpuContext;
use crate::photon::radius::VolumeRadius;
use crate::photon::ring::RingPhotons;
use crate::scene::{Changes, Scene};
use glam::Vec4;
use std::collections::HashMap;
use std::time::Instant;

/// The read-back textures of a frame, by name.
pub(super) type Readback = HashMap<&'static str, Vec<Vec4>>;

/// The indirect estimator of a renderer, kept across frames.
pub(super) struct Indirect {
    estimate: IndirectEstimate,
    /// Why the estimator was chosen (`Estimator::resolve`).
    reason: String,
    /// Whether the estimator's output is this scene's and camera's.
    current: bool,
}

/// What the estimate of a frame splats and reads back.
pub(super) struct IndirectFrame<'a> {
    pub scene: &'a Scene,
    pub options: &'a IspmOptions,
    pub params: &'a FrameParams,
    pub photons: &'a RingPhotons,
    /// The photons are not last frame's.
    pub photons_changed: bool,
    pub changes: Changes,
    /// The estimator's output was current before this frame.
    pub was_current: bool,
    /// The textures to read back.
    pub names: &'a [&'static str],
    /// Wait and time each stage (`FrameDesc::serial`).
    pub serial: bool,
}

impl Indirect {
    /// The estimator `options` ask for on this adapter, over `targets` (and the composite
    /// pointed at its output).
    pub fn new(ctx: &GpuContext, targets: &mut Targets, options: &IspmOptions) -> Self {
        let (kind, reason) = options.estimator.resolve(&ctx.info);
        let (gbuf, k) = (&targets.gbuf, options.subsample);
        let (w, h) = (targets.width, targets.height);
        let binned =
            |mode| IndirectEstimate::Binned(Box::new(Binned::new(ctx, gbuf, mode, [w, h], k)));
        let estimate = match kind {
            Estimator::Tiled => binned(Mode::Tiled),
            Estimator::Cluster => binned(Mode::Cluster),
            Estimator::Directional => binned(Mode::Directional),
            Estimator::Cpu => IndirectEstimate::Cpu(Box::new(CpuEstimate::new(ctx, gbuf, w, h, k))),
            Estimator::Volumes | Estimator::Auto => {
                IndirectEstimate::Volumes(Box::new(Volumes::new(ctx, gbuf, w, h, k)))
            }
        };
        targets.bind_composite(ctx, Some(estimate.output().1));
        Indirect {
            estimate,
            reason,
            current: false,
        }
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
    /// textures and the radii the photons were splatted with.
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        targets: &mut Targets,
        timer: &mut Timer,
        f: &IndirectFrame,
        stats: &mut RenderStats,
    ) -> Result<(Readback, VolumeRadius)> {
        let mut t = Instant::now();
        let (scene, options) = (f.scene, f.options);
        let radius = VolumeRadius::of_scene(scene, options.photons, options.kernel_scale)
            .scaled(f.params.radius_scale);
        self.estimate.set_sample_centre(targets.sample_centre());
        stats.estimator = self.estimate.kind().name().into();
        stats.estimator_reason = self.reason.clone();
        self.upload(ctx, targets, f, radius, stats)?;
        stats.estimator_memory = self.estimate.memory();
        // A still frame (same photons, nothing moved) keeps last frame's estimate.
        let splat = f.photons_changed || f.changes.any() || !f.was_current;
        if let (true, IndirectEstimate::Cpu(c)) = (splat, &mut self.estimate) {
            // Waits for the eye G-buffer (and the direct light submitted before it) when it
            // was redrawn; in serial frames, whose direct light was waited on, this is part
            // of "splat (wall)".
            let waited = c.compute(ctx, &targets.gbuf, targets.gbuffer_generation)?;
            if !f.serial {
                if let Some(w) = waited {
                    stats.stages.push(("gbuffer readback".into(), w));
                }
                let estimate = t.elapsed().as_secs_f64() - waited.unwrap_or(0.0);
                stats.stages.push(("cpu estimate".into(), estimate));
                t = Instant::now();
            }
            stats.estimator_memory = self.estimate.memory();
        }
        let data = loop {
            let mut encoder = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("indirect estimate"),
                });
            if splat && f.serial {
                (encoder, t) = splat_serially(ctx, &self.estimate, encoder, timer, stats, t)?;
            } else if splat {
                self.estimate.record(ctx, &mut encoder, timer);
            }
            targets.record_composite(ctx, &mut encoder, timer);
            let indirect = Some(self.estimate.output().0);
            targets.record_readback(ctx, &mut encoder, f.names, indirect);
            timer.resolve(&mut encoder);
            ctx.queue.submit([encoder.finish()]);
            stage(stats, "photon upload", t);
            let t = Instant::now();
            let data = targets.read(ctx, f.names)?;
            stage(stats, "readback", t);
            timer.collect(ctx)?;
            // The binned estimators' lists are sized from the last frame: when they
            // overflowed, they have grown and the estimate is redone.
            if let (true, IndirectEstimate::Binned(tl)) = (splat, &mut self.estimate) {
                let t = Instant::now();
                if tl.overflowed(ctx, &targets.gbuf)? {
                    tl.write_params(ctx, scene, radius);
                    stats.estimator_memory = self.estimate.memory();
                    stage(stats, "photon lists regrown", t);
                    continue;
                }
            }
            break data;
        };
        if splat {
            (stats.list_entries, stats.trivial_accepts) = self.estimate.list_entries();
        }
        Ok((data, radius))
    }

    /// Uploads the photons (when they or, for the volumes' order, the camera changed) and
    /// the view-dependent parameters.
    fn upload(
        &mut self,
        ctx: &GpuContext,
        targets: &Targets,
        f: &IndirectFrame,
        radius: VolumeRadius,
        stats: &mut RenderStats,
    ) -> Result<()> {
        let (scene, cam, splat) = (f.scene, &f.scene.camera, &f.photons.splat);
        match &mut self.estimate {
            IndirectEstimate::Volumes(v) => {
                let shape = f.options.volume_shape;
                let subsample = f.options.subsample.max(1);
                let (ordered, quads) = partition(shape, splat, cam, subsample, radius);
                stats.volume_quads = quads as u64;
                ctx.check_buffer("photon volumes", ordered.len() as u64 * 64)?;
                v.write_params(ctx, scene, radius);
                if !ordered.is_empty() && (f.photons_changed || f.changes.camera) {
                    v.write_photons(ctx, &ordered);
                }
                v.set_draw(ordered.len() as u32, quads as u32);
            }
            IndirectEstimate::Binned(tl) => {
                if f.photons_changed {
                    tl.write_photons(ctx, &targets.gbuf, splat, cam)?;
                }
                tl.write_params(ctx, scene, radius);
            }
            IndirectEstimate::Cpu(c) => {
                if f.photons_changed {
                    c.set_photons(splat);
                }
                c.write_params(ctx, scene, radius);
            }
        }
        Ok(())
    }
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
