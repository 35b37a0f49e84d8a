//! Method `direct`: shadow maps (only when lights or geometry moved), per sub-pixel sample
//! an eye G-buffer and deferred lighting accumulated on the GPU, the G-buffer at the pixel
//! centres, the composite, and the readback of what was asked for.

use super::gpu::{assemble, normalized, readback_names, rgb_image, LightDraw, Stale};
use super::{GpuState, Images};
use super::{RenderOutput, RenderStats};
use crate::cancel::Progress;
use crate::error::Result;
use crate::scene::Scene;
use std::time::Instant;

pub(super) fn frame(
    g: &mut GpuState,
    scene: &Scene,
    draw: LightDraw,
    images: Images,
    progress: &dyn Progress,
) -> Result<RenderOutput> {
    let ctx = g.ctx.clone();
    g.timer.reset();
    if !g.targets.has_composite() {
        g.targets.bind_composite(&ctx, None);
    }
    let t = Instant::now();
    g.targets.write_eye(&ctx, scene, &g.scene.cull);
    let upload = t.elapsed().as_secs_f64();

    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("direct frame"),
        });
    if g.scene
        .record_shadows(&ctx, &mut encoder, &mut g.timer, scene, draw)
    {
        g.targets.invalidate(Stale::SHADOWS);
    }
    let mut encoder = g
        .targets
        .record_direct(&ctx, &g.scene, encoder, &mut g.timer, progress)?;
    g.targets.record_composite(&ctx, &mut encoder, &mut g.timer);
    let names = readback_names(images, false);
    g.targets.record_readback(&ctx, &mut encoder, &names, None);
    g.timer.resolve(&mut encoder);
    ctx.queue.submit([encoder.finish()]);

    let t = Instant::now();
    let data = g.targets.read(&ctx, &names)?;
    let readback = t.elapsed().as_secs_f64();
    g.timer.collect(&ctx)?;
    let mut stats = RenderStats {
        triangles: scene.triangle_count() as u64,
        samples_per_pixel: g.targets.spp(),
        ..Default::default()
    };
    stats.stages.push(("upload".into(), upload));
    stats.stages.append(&mut g.timer.totals);
    stats.stages.push(("readback".into(), readback));
    let mut out = assemble(scene, &g.targets, &data, stats);
    if images.extras {
        if let Some(a) = data.get("accum") {
            out.aovs.push(("direct".into(), normalized(&g.targets, a)));
        }
    }
    Ok(out)
}

/// Renders the direct light and the composite of the frame `out` again (after the edge
/// buffers grew, [`super::gpu::Targets::grow_edges`]), over the indirect and specular light
/// the frame left in its targets, and replaces its radiance and `direct` AOV.
pub(super) fn redo(
    g: &mut GpuState,
    images: Images,
    progress: &dyn Progress,
    out: &mut RenderOutput,
) -> Result<()> {
    let ctx = g.ctx.clone();
    let t = Instant::now();
    g.timer.reset();
    let encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("direct light again"),
        });
    let mut encoder = g
        .targets
        .record_direct(&ctx, &g.scene, encoder, &mut g.timer, progress)?;
    g.targets.record_composite(&ctx, &mut encoder, &mut g.timer);
    let mut names = vec!["radiance"];
    if images.extras {
        names.push("accum");
    }
    g.targets.record_readback(&ctx, &mut encoder, &names, None);
    g.timer.resolve(&mut encoder);
    ctx.queue.submit([encoder.finish()]);
    let data = g.targets.read(&ctx, &names)?;
    g.timer.collect(&ctx)?;
    let (w, h) = (g.targets.width, g.targets.height);
    out.radiance = rgb_image(w, h, &data["radiance"]);
    if let Some(a) = data.get("accum") {
        let direct = normalized(&g.targets, a);
        for (name, img) in &mut out.aovs {
            if name == "direct" {
                *img = direct.clone();
            }
        }
    }
    out.stats.stages.append(&mut g.timer.totals);
    out.stats
        .stages
        .push(("edge buffers regrown".into(), t.elapsed().as_secs_f64()));
    Ok(())
}
