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
        one_bounce_light(&gpu, &mut fc, &mut g.delta_light)?;
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

/// What the specular texture holds of [`one_bounce_light`]'s image, kept across frames
/// (the renderer's [`super::GpuState`]): the image depends on the camera, the geometry, the
/// materials, the environment, the suns' discs, the seed and the samples per pixel, not on
/// point or spot lights, so a frame in which those alone moved traces nothing.
#[derive(Debug, Default)]
pub(super) struct DeltaLightState {
    content: Content,
}

#[derive(Clone, Debug, Default, PartialEq)]
enum Content {
    /// Black: new targets (zero-initialised), or written black.
    #[default]
    Black,
    /// Traced for the current camera, geometry, materials and environment.
    Traced(TraceKey),
    /// Traced before the camera, geometry, materials or environment changed.
    Stale,
}

/// The rest of what a traced image depends on.
#[derive(Clone, Debug, PartialEq)]
struct TraceKey {
    seed: u64,
    spp: u32,
    /// Each sun's disc: direction, half-angle cosine and irradiance (bits).
    discs: Vec<u32>,
}

impl DeltaLightState {
    /// The camera, the geometry, the materials or the environment changed.
    pub(super) fn invalidate(&mut self) {
        if self.content != Content::Black {
            self.content = Content::Stale;
        }
    }
}

fn trace_key(scene: &crate::scene::Scene, seed: u64, spp: u32) -> TraceKey {
    let mut discs = Vec::new();
    for l in &scene.lights {
        if let crate::scene::Light::Directional {
            direction,
            irradiance,
            cos_half_angle,
        } = *l
        {
            if l.disc_radiance().is_some() {
                discs.extend(direction.to_array().map(f32::to_bits));
                discs.extend(irradiance.to_array().map(f32::to_bits));
                discs.push(cos_half_angle.to_bits());
            }
        }
    }
    TraceKey { seed, spp, discs }
}

/// Mitsuba's `direct` counts the light its BSDF sample at the first surface finds through
/// a delta lobe (a mirror, a smooth coating, glass) and through rough glass; the GPU's
/// direct light shades the non-delta lobes alone: the rest is traced on the CPU
/// ([`crate::photon::delta_light`]) into the specular texture, which the composite adds.
/// Nothing runs in a scene without mirrors or glass, or without light such a path can meet
/// (emitters, the environment, a sun's disc: `cornell-glass` has none, its image is black);
/// the image is kept while the direct light is (a still view) and while only point or spot
/// lights change ([`DeltaLightState`]).
fn one_bounce_light(gpu: &GpuFrame, fc: &mut FrameCtx, state: &mut DeltaLightState) -> Result<()> {
    let scene = fc.scene;
    if !scene.has_specular_traced() || !delta_light::can_meet_light(scene) {
        if state.content != Content::Black {
            let black = crate::image::Image::new(gpu.targets.width, gpu.targets.height);
            gpu.targets.write_specular(&gpu.ctx, &black);
            state.content = Content::Black;
        }
        return Ok(());
    }
    let samples = camera_samples(gpu.targets.spp(), 1, fc.params);
    let key = Content::Traced(trace_key(scene, samples.seed, samples.spp));
    if state.content == key {
        return Ok(());
    }
    fc.timed("specular paths", |fc| {
        let img = delta_light::one_bounce_light(fc.scene, fc.bvh()?, &samples, fc.progress)?;
        gpu.targets.write_specular(&gpu.ctx, &img);
        Ok(())
    })?;
    state.content = key;
    Ok(())
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
