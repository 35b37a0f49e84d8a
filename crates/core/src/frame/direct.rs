//! Method `direct`: shadow maps (only when lights or geometry moved), per sub-pixel sample
//! an eye G-buffer and deferred lighting accumulated on the GPU, the G-buffer at the pixel
//! centres, the light met one delta scattering from the camera (mirrors, glass: traced on
//! the CPU, [`crate::photon::delta_light`]), the composite, and the readback of what was
//! asked for.

use super::context::FrameCtx;
use super::gpu::{normalized, readback_names, rgb_image, GpuFrame, LightDraw};
use super::options::derived::camera_samples;
use super::{GpuState, Images, RenderOutput};
use crate::error::Result;
use crate::photon::delta_light;

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
    // Nothing to redraw: the composite and the readback of the last frame are this one's.
    let still = gpu.targets.direct_current();
    // Before the direct light is recorded (and marked current): a frame cancelled while
    // tracing leaves both to be redone.
    if !gpu.targets.direct_current() {
        one_bounce_light(&gpu, &mut fc)?;
    }
    let encoder = gpu.record_direct(encoder, &fc)?;
    let names = readback_names(images, false);
    gpu.targets.set_still(still);
    let data = gpu.finish(encoder, &names, None, &mut fc)?;
    let mut out = gpu.output(&data, fc);
    if images.extras {
        if let Some(a) = data.get("accum") {
            out.aovs.push(("direct".into(), normalized(gpu.targets, a)));
        }
    }
    Ok(out)
}

/// Mitsuba's `direct` counts the light its BSDF sample at the first surface finds through
/// a delta lobe (a mirror, a smooth coating, glass) and through rough glass; the GPU's
/// direct light shades the non-delta lobes alone: the rest is traced on the CPU
/// ([`crate::photon::delta_light`]) into the specular texture, which the composite adds.
/// Nothing runs in a scene without mirrors or glass (the texture stays black); the image is
/// kept while the direct light is (a still view).
fn one_bounce_light(gpu: &GpuFrame, fc: &mut FrameCtx) -> Result<()> {
    if !fc.scene.has_specular_traced() {
        return Ok(());
    }
    fc.timed("specular paths", |fc| {
        let samples = camera_samples(gpu.targets.spp(), 1, fc.params);
        let img = delta_light::one_bounce_light(fc.scene, fc.bvh()?, &samples, fc.progress)?;
        gpu.targets.write_specular(&gpu.ctx, &img);
        Ok(())
    })
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
    if let Some(r) = data.get("radiance") {
        out.radiance = rgb_image(w, h, r);
    }
    out.display = data.display.clone();
    out.radiance_half = data.half.clone();
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
