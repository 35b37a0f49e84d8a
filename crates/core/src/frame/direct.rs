//! Method `direct`: shadow maps (only when lights or geometry moved), per sub-pixel sample
//! an eye G-buffer and deferred lighting accumulated on the GPU, the G-buffer at the pixel
//! centres, the composite, and the readback of what was asked for.

use super::context::FrameCtx;
use super::gpu::{normalized, readback_names, rgb_image, GpuFrame, LightDraw};
use super::{GpuState, Images, RenderOutput};
use crate::error::Result;

pub(super) fn frame(
    g: &mut GpuState,
    mut fc: FrameCtx,
    draw: LightDraw,
    images: Images,
) -> Result<RenderOutput> {
    if !g.targets.has_composite() {
        g.targets.bind_composite(&g.ctx, None);
    }
    let mut gpu = GpuFrame::begin(&g.ctx, &mut g.scene, &mut g.targets, &mut g.timer, &mut fc);
    let mut encoder = gpu.encoder("direct frame");
    gpu.record_shadows(&mut encoder, &fc, draw);
    let encoder = gpu.record_direct(encoder, &fc)?;
    let names = readback_names(images, false);
    let data = gpu.finish(encoder, &names, None, &mut fc)?;
    let mut out = gpu.output(&data, fc);
    if images.extras {
        if let Some(a) = data.get("accum") {
            out.aovs.push(("direct".into(), normalized(gpu.targets, a)));
        }
    }
    Ok(out)
}

/// Renders the direct light and the composite of the frame `out` again (after the edge
/// buffers grew, [`super::gpu::Targets::grow_edges`]), over the indirect and specular light
/// the frame left in its targets, and replaces its radiance and `direct` AOV.
pub(super) fn redo(
    g: &mut GpuState,
    mut fc: FrameCtx,
    images: Images,
    out: &mut RenderOutput,
) -> Result<()> {
    let GpuState {
        ctx,
        scene,
        targets,
        timer,
        ..
    } = g;
    let data = fc.timed("edge buffers regrown", |fc| {
        timer.reset();
        let mut gpu = GpuFrame {
            ctx: ctx.clone(),
            scene,
            targets,
            timer,
        };
        let encoder = gpu.encoder("direct light again");
        let encoder = gpu.record_direct(encoder, fc)?;
        let mut names = vec!["radiance"];
        if images.extras {
            names.push("accum");
        }
        gpu.finish(encoder, &names, None, fc)
    })?;
    let (w, h) = (targets.width, targets.height);
    out.radiance = rgb_image(w, h, &data["radiance"]);
    if let Some(a) = data.get("accum") {
        let direct = normalized(targets, a);
        for (name, img) in &mut out.aovs {
            if name == "direct" {
                *img = direct.clone();
            }
        }
    }
    out.stats.stages.append(&mut fc.stats.stages);
    Ok(())
}
