//! One frame of a GPU method (`direct`, `ispm`, `bidir`) over what the renderer keeps: the
//! scene on the GPU, the render targets and the GPU timer. [`GpuFrame::begin`] resets the
//! timer and uploads the eye G-buffer's views, [`GpuFrame::record_shadows`] records the
//! lights' shadow maps into the frame's first encoder, and [`GpuFrame::finish`] records the
//! composite and the readback, submits and reads back; [`GpuFrame::output`] assembles the
//! images. Each method records its own passes in between.

use super::super::context::FrameCtx;
use super::super::RenderOutput;
use super::{assemble, GpuScene, LightDraw, Stale, Targets};
use crate::error::Result;
use crate::gpu::timer::Timer;
use crate::gpu::GpuContext;
use glam::Vec4;
use std::collections::HashMap;
use std::sync::Arc;

/// What a frame read back: the float textures by name, and the radiance's encodings
/// ([`super::encode`]) where asked for.
#[derive(Default)]
pub(crate) struct Readback {
    pub texels: HashMap<&'static str, Vec<Vec4>>,
    /// The display image: RGB, 3 bytes a pixel.
    pub display: Option<Vec<u8>>,
    /// The radiance in half floats: RGB, 3 a pixel.
    pub half: Option<Vec<half::f16>>,
}

impl Readback {
    /// The texels of float texture `name`, if read back.
    pub fn get(&self, name: &str) -> Option<&Vec<Vec4>> {
        self.texels.get(name)
    }
}

/// One GPU frame (see the module).
pub(crate) struct GpuFrame<'g> {
    pub ctx: Arc<GpuContext>,
    pub scene: &'g mut GpuScene,
    pub targets: &'g mut Targets,
    pub timer: &'g mut Timer,
}

impl<'g> GpuFrame<'g> {
    /// Begins a frame: the timer reset and the eye G-buffer's views uploaded (added to
    /// stage "upload").
    pub fn begin(
        ctx: &Arc<GpuContext>,
        scene: &'g mut GpuScene,
        targets: &'g mut Targets,
        timer: &'g mut Timer,
        fc: &mut FrameCtx,
    ) -> Self {
        timer.reset();
        fc.timed("upload", |fc| targets.write_eye(ctx, fc.scene, &scene.cull));
        GpuFrame {
            ctx: ctx.clone(),
            scene,
            targets,
            timer,
        }
    }

    /// A command encoder labelled `label`.
    pub fn encoder(&self, label: &str) -> wgpu::CommandEncoder {
        self.ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
    }

    /// Records the shadow maps of the lights into `encoder` (those whose lights or
    /// occluders changed, [`GpuScene::record_shadows`]) and marks what reads them stale.
    pub fn record_shadows(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        fc: &FrameCtx,
        draw: LightDraw,
    ) {
        let ctx = &self.ctx;
        if self
            .scene
            .record_shadows(ctx, encoder, self.timer, fc.scene, draw)
        {
            self.targets.invalidate(Stale::SHADOWS);
        }
    }

    /// Records the direct light (eye G-buffers, deferred shading; [`Targets::record_direct`])
    /// after what `encoder` holds.
    pub fn record_direct(
        &mut self,
        encoder: wgpu::CommandEncoder,
        fc: &FrameCtx,
    ) -> Result<wgpu::CommandEncoder> {
        let (ctx, timer) = (&self.ctx, &mut *self.timer);
        self.targets
            .record_direct(ctx, self.scene, encoder, timer, fc.progress)
    }

    /// Ends the frame's GPU work: the composite, the radiance's encodings and the readback
    /// of `names` (none of them in a still frame, [`Targets::output_kept`]) (`indirect`: the method's indirect-light texture; "radiance" read back in
    /// the form the frame asks for, [`Targets::readout_names`]) recorded after what
    /// `encoder` holds, the timestamps resolved, submitted and read back (stage
    /// "readback"); the GPU passes' times added to the stages.
    pub fn finish(
        &mut self,
        mut encoder: wgpu::CommandEncoder,
        names: &[&'static str],
        indirect: Option<&wgpu::Texture>,
        fc: &mut FrameCtx,
    ) -> Result<Readback> {
        let ctx = &self.ctx;
        let names = self.targets.readout_names(names);
        // A still frame reads the buffers of the last again: no pass at all.
        if !self.targets.output_kept(&names) {
            self.targets.record_composite(ctx, &mut encoder, self.timer);
            self.targets
                .record_encodings(ctx, &mut encoder, &names, self.timer);
            self.targets
                .record_readback(ctx, &mut encoder, &names, indirect);
        }
        self.timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        let targets = &*self.targets;
        let data = fc.timed("readback", |_| targets.read(ctx, &names))?;
        self.timer.collect(ctx)?;
        for (name, seconds) in self.timer.totals.drain(..) {
            fc.add_stage(&name, seconds);
        }
        Ok(data)
    }

    /// The frame's output: radiance and the first-hit AOVs from `data`, with the frame's
    /// statistics.
    pub fn output(&self, data: &Readback, fc: FrameCtx) -> RenderOutput {
        assemble(fc.scene, self.targets, data, fc.stats)
    }
}
