//! Render targets of one image size, the eye views and the bind groups that read them: the
//! direct light (G-buffers, edge-adaptive supersampling, accumulation), the composite and
//! the readback of what a frame asks for.

use super::encode::Encodings;
use super::frame::Readback;
use super::scene::GpuScene;
use crate::error::{Error, Result};
use crate::frame::readout::{Precision, Readout};
use crate::gpu::layout::{buffer, texture};
use crate::gpu::raw::ViewRaw;
use crate::gpu::timer::Timer;
use crate::gpu::Pipelines;
use crate::gpu::{self, GpuContext};
use crate::image::Image;
use crate::raster::composite::CompositePass;
use crate::raster::direct::DirectPass;
use crate::raster::edges::EdgePass;
use crate::raster::gbuffer::GBufferPass;
use crate::raster::{
    self, buffer_init, camera_view, edges, gbuffer, sample_positions, view_binding,
    SAMPLES_PER_SUBMIT, VIEW_SIZE,
};
use crate::scene::{Changes, Scene};
use glam::{Vec2, Vec4};
use std::collections::HashMap;

/// Timestamp queries of one frame (wgpu's maximum per set); passes beyond it go untimed.
const TIMER_PASSES: u32 = wgpu::QUERY_SET_MAX_QUERIES / 2;

/// A number not handed out before in this process ([`Targets::gbuffer_generation`]).
fn next_generation() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

/// Render targets of one image size, the eye views and the bind groups that read them.
pub(crate) struct Targets {
    pub width: u32,
    pub height: u32,
    spp: u32,
    eye: wgpu::Buffer,
    /// The jittered sample views of the current camera (all `spp`).
    sample_views: Vec<ViewRaw>,
    /// The draws of the objects (clusters) that reach into any of the eye views (culled
    /// against the camera's frustum widened by a pixel each side, which holds every
    /// jittered sample's), written with the views.
    eye_draws: Vec<raster::Draw>,
    /// Offset (mod 1) of every sub-pixel sample position, the pixel centre's included: a
    /// new one per progressive pass (`frame::progressive`), zero otherwise.
    sample_offset: Vec2,
    /// Whether `eye` holds the current camera's views (false after a camera change).
    /// Written here only: [`Targets::invalidate`] from outside.
    eye_current: bool,
    /// Whether the accumulated direct light is that of the current scene and camera (a
    /// still frame re-renders nothing).
    direct_current: bool,
    /// Whether the centre G-buffer and the edge pixels' kept sub-pixel samples are those of
    /// the current camera, geometry and materials (a frame whose lights alone changed
    /// re-shades them without rasterizing them).
    samples_current: bool,
    /// The G-buffer at the pixel centres (AOVs, photon estimates, the direct light of
    /// pixels off edges).
    pub gbuf: gbuffer::GBuffer,
    /// The scene's materials' exact models (`GpuScene::model_materials`), which the
    /// estimators bind beside the G-buffer.
    pub model_materials: wgpu::Buffer,
    /// Which rendering of `gbuf` it holds: a new number, unique in the process, each time
    /// its pass is recorded (what was read back of an equal generation is still valid).
    pub gbuffer_generation: u64,
    /// The G-buffer of one jittered sub-pixel sample at a time.
    sub: gbuffer::GBuffer,
    sub_gbuffer_group: wgpu::BindGroup,
    /// Edge-adaptive supersampling's buffers (`None`: one sample, or every pixel
    /// supersampled).
    edges: Option<edges::EdgeBuffers>,
    /// The last frame listed its edge pixels; their count is to be checked.
    edges_found: bool,
    /// The light of the emitters under a pixel that the eye views leave out
    /// (`raster::subpixel`), written with the views; `None` where there are none.
    splats: Option<raster::splat::Splats>,
    accum: wgpu::Texture,
    accum_view: wgpu::TextureView,
    pub specular: wgpu::Texture,
    pub specular_view: wgpu::TextureView,
    pub black_view: wgpu::TextureView,
    radiance: wgpu::Texture,
    radiance_view: wgpu::TextureView,
    pub gbuffer_group: wgpu::BindGroup,
    direct_scene_group: wgpu::BindGroup,
    /// The penumbra taps the direct scene group holds (kept to make the group again).
    penumbra: wgpu::Buffer,
    direct_gbuffer_group: wgpu::BindGroup,
    composite_group: Option<wgpu::BindGroup>,
    readback: HashMap<&'static str, wgpu::Buffer>,
    /// The radiance's encodings for readback ([`super::encode`]).
    encodings: Encodings,
    /// What the frames hand back of the radiance ([`Targets::set_readout`]).
    readout: Readout,
    /// The frame's method found nothing changed since the last frame ([`Targets::set_still`]).
    still: bool,
    /// The readout and the textures that the last frame's readback buffers hold.
    last_output: Option<(Readout, Vec<&'static str>)>,
}

fn target(
    ctx: &GpuContext,
    label: &str,
    w: u32,
    h: u32,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    gpu::texture_2d(
        &ctx.device,
        label,
        w,
        h,
        wgpu::TextureFormat::Rgba32Float,
        usage,
    )
}

/// The G-buffer pass's bind group: the eye views and the materials.
fn gbuffer_group(ctx: &GpuContext, eye: &wgpu::Buffer, gs: &GpuScene) -> wgpu::BindGroup {
    gpu::create_bind_group(
        &ctx.device,
        &wgpu::BindGroupDescriptor {
            label: Some("gbuffer bind group"),
            layout: &GBufferPass::get(ctx).layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: view_binding(eye),
                },
                buffer(1, &gs.materials),
            ],
        },
    )
}

/// The direct pass's scene group: eye views, lights, shadow matrices and maps, the
/// comparison sampler, the penumbra taps, the sampled lights and the environment's tables.
fn direct_scene_group(
    ctx: &GpuContext,
    eye: &wgpu::Buffer,
    gs: &GpuScene,
    penumbra: &wgpu::Buffer,
) -> wgpu::BindGroup {
    let direct_pass = DirectPass::get(ctx);
    gpu::create_bind_group(
        &ctx.device,
        &wgpu::BindGroupDescriptor {
            label: Some("direct scene bind group"),
            layout: &direct_pass.scene_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: view_binding(eye),
                },
                buffer(1, &gs.lights),
                buffer(2, &gs.shadow_matrices),
                texture(3, &gs.shadow_array),
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::Sampler(&direct_pass.shadow_sampler),
                },
                buffer(5, penumbra),
                texture(6, &gs.samples.records_view),
                texture(7, &gs.samples.matrices_view),
                texture(8, &gs.samples.array),
                texture(9, &gs.samples.env_view),
                texture(10, &gs.samples.irradiance_view),
                buffer(11, &gs.samples.params),
                texture(12, &gs.samples.polygons_view),
                texture(13, &gs.samples.tree_view),
                texture(14, &direct_pass.ltc_table),
            ],
        },
    )
}

/// The direct pass's G-buffer group of `g`: its lighting inputs, its emission and the
/// materials' exact models of `gs`.
fn lighting_group(ctx: &GpuContext, g: &gbuffer::GBuffer, gs: &GpuScene) -> wgpu::BindGroup {
    let mut entries: Vec<_> = g
        .lighting_inputs()
        .iter()
        .enumerate()
        .map(|(i, v)| texture(i as u32, v))
        .collect();
    entries.push(texture(entries.len() as u32, g.emission()));
    entries.push(buffer(entries.len() as u32, &gs.model_materials));
    gpu::create_bind_group(
        &ctx.device,
        &wgpu::BindGroupDescriptor {
            label: Some("direct gbuffer bind group"),
            layout: &DirectPass::get(ctx).gbuffer_layout,
            entries: &entries,
        },
    )
}

/// Which of the work [`Targets`] keeps from frame to frame is stale.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Stale {
    /// The eye views (camera, or the scene bounds their depth range follows).
    pub eye: bool,
    /// The centre G-buffer and the edge pixels' kept sub-pixel samples.
    pub samples: bool,
    /// The accumulated direct light.
    pub direct: bool,
}

impl Stale {
    /// After shadow maps were redrawn: the direct light.
    pub const SHADOWS: Stale = Stale {
        eye: false,
        samples: false,
        direct: true,
    };

    /// After the scene changes `c`.
    pub fn of_changes(c: Changes) -> Stale {
        Stale {
            // Materials too: which objects are small emitters left out of the eye views
            // (`raster::subpixel`) and their splats' radiance follow the materials.
            eye: c.camera || c.geometry || c.materials,
            samples: c.camera || c.geometry || c.materials,
            direct: c.any(),
        }
    }
}

impl Targets {
    /// Targets for `scene`'s camera with `spp` direct-light samples, supersampled at edges
    /// only when `edge_supersampling`.
    pub fn new(
        ctx: &GpuContext,
        gs: &GpuScene,
        scene: &Scene,
        spp: u32,
        edge_supersampling: bool,
    ) -> Result<Self> {
        let device = &ctx.device;
        let (w, h) = (scene.camera.width, scene.camera.height);
        let eye = buffer_init(
            ctx,
            "eye views",
            &vec![0u8; (1 + SAMPLES_PER_SUBMIT.min(spp) as usize) * VIEW_SIZE as usize],
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let gbuf = gbuffer::GBuffer::new(device, w, h);
        let sub = gbuffer::GBuffer::new(device, w, h);
        let rw = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let accum = target(
            ctx,
            "direct accumulation",
            w,
            h,
            rw | wgpu::TextureUsages::STORAGE_BINDING,
        );
        let specular = target(
            ctx,
            "specular paths",
            w,
            h,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        );
        let black = target(ctx, "black", w, h, wgpu::TextureUsages::TEXTURE_BINDING);
        let radiance = target(ctx, "radiance", w, h, rw);
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let (accum_view, specular_view, black_view, radiance_view) =
            (view(&accum), view(&specular), view(&black), view(&radiance));
        let gbuffer_group = gbuffer_group(ctx, &eye, gs);
        let taps = if edge_supersampling {
            raster::direct::penumbra_taps(spp)
        } else {
            1
        };
        let penumbra = buffer_init(
            ctx,
            "penumbra taps",
            bytemuck::cast_slice(&[taps, 0, 0, 0]),
            wgpu::BufferUsages::UNIFORM,
        );
        let direct_scene_group = direct_scene_group(ctx, &eye, gs, &penumbra);
        let lighting_group = |g: &gbuffer::GBuffer| lighting_group(ctx, g, gs);
        let model_materials = gs.model_materials.clone();
        let direct_gbuffer_group = lighting_group(&gbuf);
        let sub_gbuffer_group = lighting_group(&sub);
        let edges = if spp > 1 && edge_supersampling {
            Some(edges::EdgeBuffers::new(
                ctx,
                &EdgePass::get(ctx),
                (w, h, spp),
                edges::initial_capacity(w * h),
                &accum_view,
            )?)
        } else {
            None
        };
        Ok(Targets {
            width: w,
            height: h,
            spp,
            eye,
            sample_views: Vec::new(),
            eye_draws: Vec::new(),
            sample_offset: Vec2::ZERO,
            eye_current: false,
            direct_current: false,
            samples_current: false,
            gbuf,
            gbuffer_generation: next_generation(),
            sub,
            sub_gbuffer_group,
            edges,
            edges_found: false,
            splats: None,
            accum,
            accum_view,
            specular,
            specular_view,
            black_view,
            radiance,
            radiance_view,
            gbuffer_group,
            direct_scene_group,
            penumbra,
            direct_gbuffer_group,
            model_materials,
            composite_group: None,
            readback: HashMap::new(),
            encodings: Encodings::new(w, h),
            readout: Readout::default(),
            still: false,
            last_output: None,
        })
    }

    /// Makes the direct pass's scene group again over `gs`'s current lights and
    /// environment tables (after [`super::samples::LightSamples::set_environment`]).
    pub fn rebind_scene(&mut self, ctx: &GpuContext, gs: &GpuScene) {
        self.direct_scene_group = direct_scene_group(ctx, &self.eye, gs, &self.penumbra);
    }

    /// Points the composite pass at `indirect` (the estimator's output, or black).
    /// Uploads the CPU-traced image of mirrors and glass seen by the camera (`image` at the
    /// targets' size), which the composite adds.
    pub fn write_specular(&self, ctx: &GpuContext, image: &Image) {
        let texels: Vec<[f32; 4]> = image.pixels.iter().map(|p| [p.x, p.y, p.z, 0.0]).collect();
        let bytes: &[u8] = bytemuck::cast_slice(&texels);
        crate::gpu::alloc::note_upload("specular paths", bytes.len() as u64);
        ctx.queue.write_texture(
            self.specular.as_image_copy(),
            bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(self.width * 16),
                rows_per_image: Some(self.height),
            },
            self.specular.size(),
        );
    }

    pub fn bind_composite(&mut self, ctx: &GpuContext, indirect: Option<&wgpu::TextureView>) {
        let indirect = indirect.unwrap_or(&self.black_view);
        self.composite_group = Some(gpu::create_bind_group(
            &ctx.device,
            &wgpu::BindGroupDescriptor {
                label: Some("composite bind group"),
                layout: &CompositePass::get(ctx).layout,
                entries: &[
                    texture(0, &self.accum_view),
                    texture(1, &self.specular_view),
                    texture(2, indirect),
                ],
            },
        ));
    }

    /// Sub-pixel samples of the direct light.
    pub fn spp(&self) -> u32 {
        self.spp
    }

    /// The direct pass's G-buffer group (the lighting inputs), shared by `bidir`'s VPL pass.
    pub fn lighting_group(&self) -> &wgpu::BindGroup {
        &self.direct_gbuffer_group
    }

    /// Whether the accumulated direct light is the current scene's (nothing changed since).
    pub fn direct_current(&self) -> bool {
        self.direct_current
    }

    pub fn has_composite(&self) -> bool {
        self.composite_group.is_some()
    }

    /// Where in its pixel the centre G-buffer is sampled.
    pub fn sample_centre(&self) -> Vec2 {
        (Vec2::splat(0.5) + self.sample_offset).fract()
    }

    /// Marks the kept work that `stale` names to be redone at the next frame: the one way
    /// the eye views, the kept samples and the accumulated direct light are invalidated
    /// from outside.
    pub fn invalidate(&mut self, stale: Stale) {
        self.eye_current &= !stale.eye;
        self.samples_current &= !stale.samples;
        self.direct_current &= !stale.direct;
    }

    /// Moves every sub-pixel sample by `offset` (mod 1); the eye views and the direct light
    /// are redone at the next frame when it changes.
    pub fn set_sample_offset(&mut self, offset: Vec2) {
        if offset != self.sample_offset {
            self.sample_offset = offset;
            self.eye_current = false;
            self.direct_current = false;
            self.samples_current = false;
        }
    }

    /// Writes the eye views of the current camera (the pixel centre, then the first batch of
    /// jittered samples) if the camera changed.
    pub fn write_eye(&mut self, ctx: &GpuContext, scene: &Scene, cull: &raster::CullUnits) {
        if self.eye_current {
            return;
        }
        let draws = cull
            .draws(&[raster::eye_cull_view(scene)])
            .pop()
            .unwrap_or_default();
        // Emitters under a pixel are splatted instead (`raster::subpixel`).
        self.eye_draws = raster::subpixel::without(draws, &raster::subpixel::small_objects(scene));
        self.splats =
            raster::splat::SplatPass::get(ctx).splats(ctx, scene, &raster::subpixel::splats(scene));
        let spp = self.spp;
        let o = self.sample_offset;
        let shift = |j: Vec2| (j + o).fract();
        self.sample_views = sample_positions(spp)
            .into_iter()
            .map(|j| camera_view(scene, shift(j), 1.0 / spp as f32))
            .collect();
        let mut views = vec![camera_view(scene, shift(Vec2::splat(0.5)), 0.0)];
        views.extend_from_slice(&self.sample_views[..SAMPLES_PER_SUBMIT.min(spp) as usize]);
        gpu::write_buffer(
            &ctx.queue,
            "eye views",
            &self.eye,
            0,
            bytemuck::cast_slice(&views),
        );
        self.eye_current = true;
    }

    /// Direct light. With one sample, or with edge-adaptive supersampling
    /// ([`raster::edges`]): the centre G-buffer shaded once per pixel, and the mean over the
    /// jittered sub-pixel samples written over the edge pixels (the samples rasterized and
    /// kept only when the camera, geometry or materials changed). With full supersampling:
    /// per sub-pixel sample an eye G-buffer and its lighting added into the accumulation
    /// target. Either way the centre G-buffer (AOVs, photon estimates) is current after.
    pub fn record_direct(
        &mut self,
        ctx: &GpuContext,
        gs: &GpuScene,
        mut encoder: wgpu::CommandEncoder,
        timer: &mut Timer,
        progress: &dyn crate::cancel::Progress,
    ) -> Result<wgpu::CommandEncoder> {
        if self.direct_current {
            return Ok(encoder);
        }
        let (gbuffer_p, direct_p, edge_p) = (
            GBufferPass::get(ctx),
            DirectPass::get(ctx),
            EdgePass::get(ctx),
        );
        // A G-buffer pass whose depth starts cleared, or (`Load`) as an edge mask left it.
        let gbuffer_over = |encoder: &mut wgpu::CommandEncoder,
                            timer: &mut Timer,
                            target: &gbuffer::GBuffer,
                            offset: u32,
                            depth: wgpu::LoadOp<f32>| {
            let ts = timer.pass("gbuffer");
            gbuffer_p.record_over(
                encoder,
                target,
                (&self.gbuffer_group, offset, depth),
                (&gs.geometry, Some(&self.eye_draws)),
                (&gs.textures.group, gs.variant),
                ts,
            );
        };
        let clear = wgpu::LoadOp::Clear(gbuffer::CLEAR_DEPTH);
        let gbuffer_pass =
            |encoder: &mut wgpu::CommandEncoder,
             timer: &mut Timer,
             target: &gbuffer::GBuffer,
             offset: u32| gbuffer_over(encoder, timer, target, offset, clear);
        let scene_group = &self.direct_scene_group;
        let variant = gs.direct_variant();
        // The edge passes over the centre G-buffer (finding edges, shading them).
        let centre_edges = self.edges.as_ref().map(|edges| edges::EdgeGroups {
            scene: scene_group,
            gbuffer: &self.direct_gbuffer_group,
            edges,
            variant,
        });
        if self.spp > 1 && self.edges.is_none() {
            encoder = self.for_each_sample(ctx, encoder, progress, |encoder, s, offset| {
                gbuffer_pass(encoder, timer, &self.sub, offset);
                let ts = timer.pass("direct light");
                direct_p.record(
                    encoder,
                    &self.accum_view,
                    s == 0,
                    false,
                    [scene_group, &self.sub_gbuffer_group],
                    (offset, variant),
                    ts,
                );
            })?;
        }
        if !self.samples_current {
            gbuffer_pass(&mut encoder, timer, &self.gbuf, 0);
            self.gbuffer_generation = next_generation();
            if let Some(find) = &centre_edges {
                let ts = timer.compute_pass("edges");
                edge_p.record_find(&mut encoder, find, ts);
                let store = edges::EdgeGroups {
                    gbuffer: &self.sub_gbuffer_group,
                    ..*find
                };
                let masked = edges::mask_enabled();
                encoder = self.for_each_sample(ctx, encoder, progress, |encoder, s, offset| {
                    if masked {
                        // Only the listed pixels are kept: the pass shades only them.
                        let ts = timer.pass("edge mask");
                        edge_p.record_mask(encoder, find.edges, &self.sub.depth, ts);
                        gbuffer_over(encoder, timer, &self.sub, offset, wgpu::LoadOp::Load);
                    } else {
                        gbuffer_pass(encoder, timer, &self.sub, offset);
                    }
                    let ts = timer.compute_pass("edges");
                    edge_p.record_store(encoder, &store, s, ts);
                })?;
            }
        }
        if self.spp == 1 || centre_edges.is_some() {
            let ts = timer.pass("direct light");
            direct_p.record(
                &mut encoder,
                &self.accum_view,
                true,
                true,
                [scene_group, &self.direct_gbuffer_group],
                (0, variant),
                ts,
            );
            if let Some(groups) = &centre_edges {
                let ts = timer.compute_pass("edge shading");
                edge_p.record_shade(&mut encoder, (groups, variant), ts);
            }
        }
        if let Some(splats) = &self.splats {
            let ts = timer.pass("emitter splats");
            raster::splat::SplatPass::get(ctx).record(
                &mut encoder,
                &self.accum_view,
                splats,
                &self.direct_gbuffer_group,
                ts,
            );
        }
        // Current once recorded in full (a cancelled frame leaves it to the next).
        self.edges_found |= !self.samples_current && self.edges.is_some();
        self.samples_current = true;
        self.direct_current = true;
        Ok(encoder)
    }

    /// The G-buffer at the pixel centres alone, and the direct light's accumulation cleared
    /// (the composite then adds none): for frames whose direct light is found elsewhere
    /// (progressive `ispm` traces it on the CPU, `frame::progressive::direct_image`).
    /// Nothing when the direct light is current.
    pub fn record_gbuffer(
        &mut self,
        ctx: &GpuContext,
        gs: &GpuScene,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut Timer,
    ) {
        if self.direct_current {
            return;
        }
        let ts = timer.pass("gbuffer");
        self.gbuffer_generation = next_generation();
        GBufferPass::get(ctx).record(
            encoder,
            &self.gbuf,
            &self.gbuffer_group,
            0,
            (&gs.geometry, Some(&self.eye_draws)),
            (&gs.textures.group, gs.variant),
            ts,
        );
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("direct light cleared"),
            color_attachments: &[Some(crate::gpu::cleared(&self.accum_view))],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        // The edge pixels' sub-pixel samples were not rendered: a lit frame renders them.
        self.samples_current = false;
        self.direct_current = true;
    }

    /// Writes the eye views of the sub-pixel samples `samples` after the frame's own view.
    fn write_eye_views(&self, ctx: &GpuContext, samples: std::ops::Range<u32>) {
        let views = &self.sample_views[samples.start as usize..samples.end as usize];
        gpu::write_buffer(
            &ctx.queue,
            "eye views",
            &self.eye,
            VIEW_SIZE,
            bytemuck::cast_slice(views),
        );
    }

    /// Records `record(encoder, sample, view offset)` for every sub-pixel sample, writing
    /// their eye views in batches (submitting the encoder between batches, whose views are
    /// then in use); reports progress.
    fn for_each_sample(
        &self,
        ctx: &GpuContext,
        mut encoder: wgpu::CommandEncoder,
        progress: &dyn crate::cancel::Progress,
        mut record: impl FnMut(&mut wgpu::CommandEncoder, u32, u32),
    ) -> Result<wgpu::CommandEncoder> {
        let spp = self.spp;
        let mut done = 0;
        let per_submit = crate::raster::samples_per_submit(self.width, self.height);
        if spp > per_submit {
            // An earlier frame left its last batch's views; no pass recorded so far reads them.
            self.write_eye_views(ctx, 0..per_submit);
        }
        while done < spp {
            let batch = per_submit.min(spp - done);
            if done > 0 {
                ctx.queue.submit([encoder.finish()]);
                self.write_eye_views(ctx, done..done + batch);
                encoder = ctx
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("direct samples"),
                    });
            }
            for s in 0..batch {
                let offset = ((s + 1) as u64 * VIEW_SIZE) as u32;
                record(&mut encoder, done + s, offset);
            }
            done += batch;
            if !progress.update("direct", done as f64 / spp as f64) {
                return Err(Error::Cancelled);
            }
        }
        Ok(encoder)
    }

    /// After a frame that listed the edge pixels (its work done): when more were found than
    /// the buffers hold, grows them and marks the direct light stale, so that the caller
    /// renders the frame again. True when it did.
    pub fn grow_edges(&mut self, ctx: &GpuContext) -> Result<bool> {
        if !std::mem::take(&mut self.edges_found) {
            return Ok(false);
        }
        let Some(edges) = &self.edges else {
            return Ok(false);
        };
        let found = edges.found(ctx)?;
        let most = edges::max_capacity(ctx, self.spp);
        if found <= edges.capacity || edges.capacity >= most {
            return Ok(false);
        }
        let capacity = (found + found / 4).min(most);
        self.edges = Some(edges::EdgeBuffers::new(
            ctx,
            &EdgePass::get(ctx),
            (self.width, self.height, self.spp),
            capacity,
            &self.accum_view,
        )?);
        self.samples_current = false;
        self.direct_current = false;
        Ok(true)
    }

    /// Records the composite pass.
    pub fn record_composite(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut Timer,
    ) {
        if let Some(group) = &self.composite_group {
            let ts = timer.pass("composite");
            CompositePass::get(ctx).record(encoder, &self.radiance_view, group, ts);
        }
    }

    /// Sets what the next frames hand back of the radiance: a method whose composite is
    /// its final radiance reads back only that ([`Targets::readout_names`]).
    pub fn set_readout(&mut self, readout: Readout) {
        self.readout = readout;
    }

    /// The method of this frame found that nothing its composite reads changed since the
    /// last frame (a still frame: the same photons, estimate, direct and specular light).
    /// Reset by the frame's [`Targets::output_kept`].
    pub fn set_still(&mut self, still: bool) {
        self.still = still;
    }

    /// Whether the readback buffers already hold what this frame would copy into them
    /// (a still frame asking for the same `names` in the same readout as the last): then
    /// the frame records no composite, encoding or copy and reads them again. Otherwise
    /// notes `names` as what the frame is about to copy and returns false.
    pub fn output_kept(&mut self, names: &[&'static str]) -> bool {
        let still = std::mem::take(&mut self.still);
        let now = (self.readout, names.to_vec());
        if still && self.last_output.as_ref() == Some(&now) {
            return true;
        }
        self.last_output = Some(now);
        false
    }

    /// The textures to read back for `names` (a method's list): "radiance" replaced by
    /// what the readout asks for ("radiance" in 32-bit floats, "radiance16" in half
    /// floats, "display" the display image).
    pub fn readout_names(&self, names: &[&'static str]) -> Vec<&'static str> {
        let r = self.readout;
        let mut out = Vec::new();
        for &name in names {
            if name != "radiance" {
                out.push(name);
                continue;
            }
            match r.radiance {
                Some(Precision::Float32) => out.push("radiance"),
                Some(Precision::Float16) => out.push("radiance16"),
                None => {}
            }
            if r.display.is_some() {
                out.push("display");
            }
        }
        out
    }

    /// Records the encodings of the radiance that `names` ([`Targets::readout_names`])
    /// read back, after the composite.
    pub fn record_encodings(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        names: &[&'static str],
        timer: &mut Timer,
    ) {
        let radiance = &self.radiance_view;
        if let (true, Some(d)) = (names.contains(&"display"), self.readout.display) {
            self.encodings
                .record_display(ctx, encoder, radiance, d, timer);
        }
        if names.contains(&"radiance16") {
            self.encodings.record_half(ctx, encoder, radiance, timer);
        }
    }

    /// The texture read back under `name`.
    fn texture_of<'a>(
        &'a self,
        name: &str,
        indirect: Option<&'a wgpu::Texture>,
    ) -> Option<&'a wgpu::Texture> {
        Some(match name {
            "radiance" => &self.radiance,
            "accum" => &self.accum,
            "position" => &self.gbuf.textures[0],
            "normals" => &self.gbuf.textures[1],
            "albedo" => &self.gbuf.textures[4],
            "indirect" => indirect?,
            _ => return None,
        })
    }

    /// The radiance's encoding read back under `name` (a storage buffer, rows unpadded).
    fn encoded(&self, name: &str) -> Option<&wgpu::Buffer> {
        let e = &self.encodings;
        match name {
            "display" => e.display.as_ref().map(|t| &t.buffer),
            "radiance16" => e.half.as_ref().map(|t| &t.buffer),
            _ => None,
        }
    }

    /// Bytes of a texel read back under `name`, and of its rows in the readback buffer
    /// (a texture's padded to wgpu's copy alignment; an encoding's as they are).
    fn row_bytes(&self, name: &str) -> (usize, usize) {
        let w = self.width as usize;
        match name {
            "display" => (4, w * 4),
            "radiance16" => (8, w * 8),
            _ => (
                16,
                (w * 16).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT as usize),
            ),
        }
    }

    /// Records copies of the named textures and encodings into their readback buffers
    /// (created on first use at this size).
    pub fn record_readback(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        names: &[&'static str],
        indirect: Option<&wgpu::Texture>,
    ) {
        let h = self.height;
        for &name in names {
            if !self.readback.contains_key(name) {
                let row = self.row_bytes(name).1 as u64;
                let buffer = gpu::readback_buffer(&ctx.device, "readback", row * h as u64);
                self.readback.insert(name, buffer);
            }
        }
        for &name in names {
            if let Some(encoded) = self.encoded(name) {
                let dst = &self.readback[name];
                encoder.copy_buffer_to_buffer(encoded, 0, dst, 0, encoded.size());
                continue;
            }
            let Some(texture) = self.texture_of(name, indirect) else {
                continue;
            };
            encoder.copy_texture_to_buffer(
                texture.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: &self.readback[name],
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(self.row_bytes(name).1 as u32),
                        rows_per_image: Some(h),
                    },
                },
                texture.size(),
            );
        }
    }

    /// Maps the readback buffers of `names` (after all submitted work) and returns their
    /// texels, rows unpadded: the float textures as texels, the display image as RGB
    /// bytes and the half-float radiance as RGB halves (alpha dropped).
    pub fn read(&self, ctx: &GpuContext, names: &[&'static str]) -> Result<Readback> {
        let (w, h) = (self.width as usize, self.height as usize);
        let buffers: Vec<&wgpu::Buffer> = names.iter().map(|n| &self.readback[n]).collect();
        let mut out = Readback::default();
        // The rows are copied out of the mapped buffers directly (one copy, not two).
        let mut texels = HashMap::new();
        ctx.read_buffers_with(&buffers, None, |i, b| {
            let name = names[i];
            let (texel, row) = self.row_bytes(name);
            let rows = (0..h).map(|y| &b[y * row..y * row + w * texel]);
            match name {
                // The encodings' rows are unpadded: RGBA per pixel, alpha dropped.
                "display" => {
                    let mut rgb = vec![0u8; w * h * 3];
                    for (o, p) in rgb.chunks_exact_mut(3).zip(b.chunks_exact(4)) {
                        o.copy_from_slice(&p[..3]);
                    }
                    out.display = Some(rgb);
                }
                "radiance16" => {
                    let halves: &[u16] = bytemuck::cast_slice(&b[..w * h * 8]);
                    let mut rgb = vec![half::f16::ZERO; w * h * 3];
                    for (o, p) in rgb.chunks_exact_mut(3).zip(halves.chunks_exact(4)) {
                        for (o, p) in o.iter_mut().zip(p) {
                            *o = half::f16::from_bits(*p);
                        }
                    }
                    out.half = Some(rgb);
                }
                _ => {
                    let mut v: Vec<Vec4> = Vec::with_capacity(w * h);
                    for r in rows {
                        v.extend_from_slice(bytemuck::cast_slice::<u8, Vec4>(r));
                    }
                    texels.insert(name, v);
                }
            }
        })?;
        out.texels = texels;
        Ok(out)
    }
}

/// The timer of a frame, created once.
pub(crate) fn frame_timer(ctx: &GpuContext) -> Timer {
    Timer::new(ctx, TIMER_PASSES)
}

/// RGB of texels.
pub(crate) fn rgb_image(w: u32, h: u32, texels: &[Vec4]) -> Image {
    let mut img = Image::new(w, h);
    for (d, t) in img.pixels.iter_mut().zip(texels) {
        *d = t.truncate();
    }
    img
}
