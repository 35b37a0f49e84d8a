//! Method `direct`: shadow maps (only when lights or geometry moved), per sub-pixel sample
//! an eye G-buffer and deferred lighting accumulated on the GPU, the G-buffer at the pixel
//! centres, the composite, and the readback of what was asked for.

use super::gpu::{rgb_image, LightDraw, Targets};
use super::{GpuState, Images};
use super::{RenderOutput, RenderStats};
use crate::cancel::Progress;
use crate::error::Result;
use crate::image::Image;
use crate::raster::oct_decode;
use crate::scene::Scene;
use glam::{Vec2, Vec3, Vec4};
use std::collections::HashMap;
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
        g.targets.direct_current = false;
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

/// The textures to read back for `images` (`accum` for the ISPM direct AOV; `indirect`
/// when the method has one).
pub(super) fn readback_names(images: Images, indirect: bool) -> Vec<&'static str> {
    let mut names = vec!["radiance"];
    if images.aovs || images.extras {
        names.extend(["position", "normals", "albedo"]);
    }
    if images.extras {
        names.push("accum");
        if indirect {
            names.push("indirect");
        }
    }
    names
}

/// Radiance and the first-hit AOVs from the read-back textures.
pub(super) fn assemble(
    scene: &Scene,
    t: &Targets,
    data: &HashMap<&'static str, Vec<Vec4>>,
    stats: RenderStats,
) -> RenderOutput {
    let (w, h) = (t.width, t.height);
    let empty = || Image::new(0, 0);
    let mut out = RenderOutput {
        radiance: data
            .get("radiance")
            .map(|r| rgb_image(w, h, r))
            .unwrap_or_else(empty),
        albedo: empty(),
        normal: empty(),
        position: empty(),
        depth: Vec::new(),
        caustics: empty(),
        aovs: Vec::new(),
        stats,
    };
    if let (Some(position), Some(normals), Some(albedo)) = (
        data.get("position"),
        data.get("normals"),
        data.get("albedo"),
    ) {
        let cam = &scene.camera;
        out.albedo = Image::new(w, h);
        out.normal = Image::new(w, h);
        out.position = Image::new(w, h);
        out.caustics = Image::new(w, h);
        out.depth = vec![0.0; (w * h) as usize];
        for i in 0..(w * h) as usize {
            if position[i].w > 0.0 {
                let p = position[i].truncate();
                out.position.pixels[i] = p;
                out.normal.pixels[i] = oct_decode(Vec2::new(normals[i].x, normals[i].y));
                out.albedo.pixels[i] = albedo[i].truncate();
                out.depth[i] = (p - cam.position).dot(cam.forward);
            }
        }
    }
    out
}

/// The accumulated direct light divided by its weights.
pub(super) fn normalized(t: &Targets, accum: &[Vec4]) -> Image {
    let mut img = Image::new(t.width, t.height);
    for (d, a) in img.pixels.iter_mut().zip(accum) {
        *d = if a.w > 0.0 {
            a.truncate() / a.w
        } else {
            Vec3::ZERO
        };
    }
    img
}
