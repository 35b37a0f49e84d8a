//! Step 1 and 3 of an `ispm` frame: the photons' first hits, from rasterized bounce maps
//! (section 4.2, submitted first and read back after the direct light was submitted:
//! section 4.3's asynchronous readback) or the same photons cast in the CPU BVH
//! ([`crate::photon::bounce`], cheaper on CPU devices).

use super::super::context::FrameCtx;
use super::super::gpu::{GpuFrame, GpuScene};
use crate::error::{Error, Result};
use crate::gpu::{GpuContext, Pipelines};
use crate::photon::bounce::{trace_bounce_maps, BounceMap, FirstBounce};
use crate::photon::trace::Checked;
use crate::raster::bounce::{BouncePass, BounceTargets};
use crate::scene::light_views::LightView;
use crate::scene::Scene;

/// Where the first hits are found, and the bounce maps' resources.
pub(super) struct FirstHits {
    /// The choice ([`FirstBounce::resolve`]).
    pub bounce: FirstBounce,
    /// Why it was chosen.
    pub reason: String,
    /// The rasterized bounce maps' resources (`FirstBounce::Raster` only).
    targets: Option<BounceTargets>,
}

impl FirstHits {
    pub fn new(bounce: FirstBounce, reason: String) -> Self {
        FirstHits {
            bounce,
            reason,
            targets: None,
        }
    }

    fn raster(&self) -> bool {
        self.bounce == FirstBounce::Raster
    }

    /// Makes the bounce maps' resources fit `layers` and uploads their views with the
    /// frame's seed (nothing when the frame `reuse`s the photons it has).
    pub fn prepare(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        gs: &GpuScene,
        layers: &[LightView],
        seed: u64,
        reuse: bool,
    ) -> Result<()> {
        if reuse || !self.raster() {
            return Ok(());
        }
        if !self.targets.as_ref().is_some_and(|b| b.fits(layers)) {
            let buffers = (&gs.materials, &gs.model_materials);
            self.targets = BounceTargets::new(ctx, layers, buffers)?;
        }
        if let Some(b) = &self.targets {
            b.write_views(ctx, scene, layers, seed);
        }
        Ok(())
    }

    /// Submits the bounce maps with their readback copies (an empty submission when
    /// traced or reused); in `serial` frames waits and times them.
    pub fn submit(
        &self,
        gpu: &mut GpuFrame,
        fc: &mut FrameCtx,
        layers: &[LightView],
        reuse: bool,
    ) -> Result<wgpu::SubmissionIndex> {
        let mut record = |fc: &mut FrameCtx| {
            let (ctx, gs) = (&gpu.ctx, &gpu.scene);
            let mut encoder = gpu.encoder("bounce maps");
            if let (false, Some(b)) = (reuse, &self.targets) {
                b.record(
                    &BouncePass::get(ctx),
                    &mut encoder,
                    layers,
                    &gs.geometry,
                    &gs.cull,
                    (&gs.textures.group, gs.variant),
                    gpu.timer,
                );
            }
            let submission = ctx.queue.submit([encoder.finish()]);
            if fc.serial {
                ctx.wait()?;
            }
            Ok(submission)
        };
        if fc.serial {
            fc.timed("bounce maps (wall)", record)
        } else {
            record(fc)
        }
    }

    /// The first scatter of the frame's photons: the bounce maps read back once
    /// `submission` is done, or the same photons traced in `bvh`; nothing when the frame
    /// `reuse`s its photons.
    pub fn finish(
        &self,
        ctx: &GpuContext,
        fc: &mut FrameCtx,
        layers: &[LightView],
        submission: wgpu::SubmissionIndex,
        reuse: bool,
    ) -> Result<BounceMap> {
        let (scene, bvh, seed, progress) = (fc.scene, fc.bvh()?, fc.params.seed, fc.progress);
        let raster = self.raster();
        let name = if raster {
            "bounce readback"
        } else {
            "bounce trace"
        };
        let bm = fc.timed(name, |_| match (reuse, &self.targets) {
            (true, _) => Ok(Default::default()),
            (false, Some(b)) if raster => b.finish(ctx, layers, Some(submission)),
            (false, _) if raster => Ok(Default::default()),
            (false, _) => {
                let control = Checked::new(progress, "bounce maps");
                trace_bounce_maps(scene, bvh, layers, seed, &control)
            }
        })?;
        fc.stats.photons_emitted = bm.covered;
        fc.stats.photons_first_bounce = bm.rays.len() as u64;
        if !progress.update("bounce maps", 1.0) {
            return Err(Error::Cancelled);
        }
        Ok(bm)
    }
}
