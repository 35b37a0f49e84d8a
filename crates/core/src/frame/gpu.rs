//! What the GPU methods keep from one frame to the next: the scene on the GPU (vertices,
//! materials, lights, shadow maps), the render targets of one image size with their bind
//! groups, the pass timer and the readback buffers. Everything is created once; a frame
//! writes only what changed ([`crate::scene::Changes`]) and records passes.

use crate::error::{Error, Result};
use crate::gpu::raw::ViewRaw;
use crate::gpu::timer::Timer;
use crate::gpu::Pipelines;
use crate::gpu::{self, GpuContext};
use crate::image::Image;
use crate::raster::composite::CompositePass;
use crate::raster::direct::DirectPass;
use crate::raster::edges::EdgePass;
use crate::raster::gbuffer::GBufferPass;
use crate::raster::shadow::ShadowPass;
use crate::raster::textures::TexturesLayout;
use crate::raster::{
    self, buffer_init, camera_view, edges, gbuffer, sample_positions, shadow, view_binding,
    Geometry, SAMPLES_PER_SUBMIT, VIEW_SIZE,
};
use crate::scene::Scene;
use glam::{Vec2, Vec4};
use std::collections::HashMap;

/// Timestamp queries of one frame (wgpu's maximum per set); passes beyond it go untimed.
const TIMER_PASSES: u32 = wgpu::QUERY_SET_MAX_QUERIES / 2;

/// The scene's GPU-resident data.
pub(crate) struct GpuScene {
    pub geometry: Geometry,
    pub materials: wgpu::Buffer,
    /// Textures and material maps (group 1 of the passes that rasterize the scene).
    pub textures: raster::textures::GpuTextures,
    /// Whether any material is alpha-masked (the shadow pass then discards cut-outs).
    masked: bool,
    /// The fragment shaders the scene needs (textures, alpha masks).
    pub variant: raster::textures::Variant,
    pub lights: wgpu::Buffer,
    shadow_matrices: wgpu::Buffer,
    shadow_views: wgpu::Buffer,
    shadow_layers: Vec<wgpu::TextureView>,
    shadow_array: wgpu::TextureView,
    shadow_group: wgpu::BindGroup,
    /// Shadow-map layers (one per spot light, six per point light).
    pub layers: u32,
    /// The shadow maps must be rendered again (lights or geometry moved).
    pub shadows_stale: bool,
    /// World -> clip per shadow layer (CPU copies, for culling the shadow passes).
    shadow_clip: Vec<glam::Mat4>,
    /// The geometry's culling units for the light-view passes (shadow, bounce, RSM, VPL
    /// maps), rebuilt when geometry moves.
    pub cull: shadow::CullUnits,
}

fn storage_init(ctx: &GpuContext, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    buffer_init(ctx, label, bytes, usage)
}

impl GpuScene {
    pub fn new(ctx: &GpuContext, scene: &Scene, shadow_map_size: u32) -> Result<Self> {
        let textures =
            raster::textures::GpuTextures::new(ctx, scene, &TexturesLayout::get(ctx).layout)?;
        let shadows = shadow::ShadowViews::new(scene, shadow_map_size);
        let layers = (shadows.matrices.len() as u32).max(1);
        let materials: Vec<_> = scene.materials.iter().map(|m| m.to_raw()).collect();
        let matrices: Vec<[f32; 16]> = shadows.matrices.iter().map(|m| m.to_cols_array()).collect();
        let shadow_views = buffer_init(
            ctx,
            "shadow views",
            bytemuck::cast_slice(&shadow::ShadowPass::views(&shadows)),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let (shadow_layers, shadow_array) =
            shadow::layered_maps(&ctx.device, "shadow maps", shadow_map_size, layers);
        let shadow_group = gpu::create_bind_group(
            &ctx.device,
            &wgpu::BindGroupDescriptor {
                label: Some("shadow bind group"),
                layout: &ShadowPass::get(ctx).layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: view_binding(&shadow_views),
                }],
            },
        );
        Ok(GpuScene {
            geometry: Geometry::upload(ctx, scene),
            materials: storage_init(ctx, "materials", bytemuck::cast_slice(&materials)),
            textures,
            masked: scene.has_alpha_masks(),
            variant: raster::textures::Variant::of(scene),
            lights: storage_init(ctx, "lights", bytemuck::cast_slice(&shadows.lights)),
            shadow_matrices: storage_init(ctx, "shadow matrices", bytemuck::cast_slice(&matrices)),
            shadow_views,
            shadow_layers,
            shadow_array,
            shadow_group,
            layers,
            shadows_stale: true,
            shadow_clip: shadows.matrices,
            cull: shadow::CullUnits::of(scene),
        })
    }

    /// Whether the scene's lights still fit these shadow maps (same number of layers).
    pub fn fits(scene: &Scene, layers: u32) -> bool {
        let needed: u32 = scene
            .lights
            .iter()
            .map(|l| match l {
                crate::scene::Light::Point { .. } => 6,
                crate::scene::Light::Spot { .. } => 1,
            })
            .sum();
        needed.max(1) == layers
    }

    /// Uploads the vertices of scene triangles `range`.
    pub fn write_triangles(&self, ctx: &GpuContext, scene: &Scene, range: std::ops::Range<usize>) {
        let verts = raster::vertices_of(scene, range.clone());
        let offset = (range.start * 3 * std::mem::size_of::<crate::gpu::raw::VertexRaw>()) as u64;
        gpu::write_buffer(
            &ctx.queue,
            "scene vertices",
            &self.geometry.vertices,
            offset,
            bytemuck::cast_slice(&verts),
        );
    }

    pub fn write_materials(&mut self, ctx: &GpuContext, scene: &Scene) {
        let materials: Vec<_> = scene.materials.iter().map(|m| m.to_raw()).collect();
        gpu::write_buffer(
            &ctx.queue,
            "materials",
            &self.materials,
            0,
            bytemuck::cast_slice(&materials),
        );
        self.textures.write_maps(ctx, scene);
        let masked = scene.has_alpha_masks();
        if masked || self.masked {
            // Cut-outs appeared, changed or went: the shadow maps change with them.
            self.shadows_stale = true;
        }
        self.masked = masked;
        self.variant = raster::textures::Variant::of(scene);
    }

    /// Uploads the lights and their shadow views (they depend on the scene's bounds too).
    pub fn write_lights(&mut self, ctx: &GpuContext, scene: &Scene, shadow_map_size: u32) {
        let shadows = shadow::ShadowViews::new(scene, shadow_map_size);
        let matrices: Vec<[f32; 16]> = shadows.matrices.iter().map(|m| m.to_cols_array()).collect();
        let q = &ctx.queue;
        gpu::write_buffer(
            q,
            "lights",
            &self.lights,
            0,
            bytemuck::cast_slice(&shadows.lights),
        );
        gpu::write_buffer(
            q,
            "shadow matrices",
            &self.shadow_matrices,
            0,
            bytemuck::cast_slice(&matrices),
        );
        gpu::write_buffer(
            q,
            "shadow views",
            &self.shadow_views,
            0,
            bytemuck::cast_slice(&shadow::ShadowPass::views(&shadows)),
        );
        self.shadow_clip = shadows.matrices;
        self.shadows_stale = true;
    }

    /// The lights' shadow matrices and maps (for lookups outside the direct pass).
    pub fn shadow_lookup(&self) -> (&wgpu::Buffer, &wgpu::TextureView) {
        (&self.shadow_matrices, &self.shadow_array)
    }

    /// The texture group for shadow passes of scenes with alpha masks (they discard
    /// cut-outs), `None` otherwise.
    pub fn shadow_masks(&self) -> Option<&wgpu::BindGroup> {
        self.masked.then_some(&self.textures.group)
    }

    /// Renders the shadow maps if lights or geometry moved since they were last rendered.
    pub fn record_shadows(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut Timer,
        scene: &Scene,
    ) {
        if !self.shadows_stale || scene.lights.is_empty() {
            return;
        }
        // Each layer draws only the triangle runs that reach into its view.
        let draws = self.cull.draws(&self.shadow_clip);
        for (layer, view) in self.shadow_layers.iter().enumerate() {
            let offset = (layer as u64 * VIEW_SIZE) as u32;
            let ts = timer.pass("shadow maps");
            ShadowPass::get(ctx).record(
                encoder,
                view,
                &self.shadow_group,
                offset,
                &self.geometry,
                draws.get(layer).map(|d| d.as_slice()),
                self.masked.then_some(&self.textures.group),
                ts,
            );
        }
        self.shadows_stale = false;
    }
}

/// Fails with a setting or GPU error when the image, the shadow maps or their layers exceed
/// the adapter's limits.
pub(super) fn check_limits(
    ctx: &GpuContext,
    scene: &Scene,
    shadow_map_size: u32,
    layers: u32,
) -> Result<()> {
    let l = ctx.device.limits();
    let max = l.max_texture_dimension_2d;
    if scene.camera.width > max || scene.camera.height > max {
        return Err(Error::setting(
            "width",
            format!("the GPU allows images up to {max} pixels a side"),
        ));
    }
    if shadow_map_size > max {
        return Err(Error::setting(
            "shadow_map_size",
            format!("the GPU allows at most {max}"),
        ));
    }
    if layers > l.max_texture_array_layers {
        return Err(Error::Gpu(format!(
            "{layers} shadow-map layers exceed the GPU's {}",
            l.max_texture_array_layers
        )));
    }
    Ok(())
}

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
    /// Offset (mod 1) of every sub-pixel sample position, the pixel centre's included: a
    /// new one per progressive pass (`frame::progressive`), zero otherwise.
    sample_offset: Vec2,
    /// Whether `eye` holds the current camera's views (false after a camera change).
    pub eye_current: bool,
    /// Whether the accumulated direct light is that of the current scene and camera (a
    /// still frame re-renders nothing).
    pub direct_current: bool,
    /// Whether the centre G-buffer and the edge pixels' kept sub-pixel samples are those of
    /// the current camera, geometry and materials (a frame whose lights alone changed
    /// re-shades them without rasterizing them).
    pub samples_current: bool,
    /// The G-buffer at the pixel centres (AOVs, photon estimates, the direct light of
    /// pixels off edges).
    pub gbuf: gbuffer::GBuffer,
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
    accum: wgpu::Texture,
    accum_view: wgpu::TextureView,
    pub specular: wgpu::Texture,
    pub specular_view: wgpu::TextureView,
    pub black_view: wgpu::TextureView,
    radiance: wgpu::Texture,
    radiance_view: wgpu::TextureView,
    pub gbuffer_group: wgpu::BindGroup,
    direct_scene_group: wgpu::BindGroup,
    direct_gbuffer_group: wgpu::BindGroup,
    composite_group: Option<wgpu::BindGroup>,
    readback: HashMap<&'static str, wgpu::Buffer>,
}

fn target(
    ctx: &GpuContext,
    label: &str,
    w: u32,
    h: u32,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    gpu::create_texture(
        &ctx.device,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage,
            view_formats: &[],
        },
    )
}

fn tex_entry(binding: u32, view: &wgpu::TextureView) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::TextureView(view),
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
        let direct_pass = DirectPass::get(ctx);
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
        let gbuffer_group = gpu::create_bind_group(
            device,
            &wgpu::BindGroupDescriptor {
                label: Some("gbuffer bind group"),
                layout: &GBufferPass::get(ctx).layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: view_binding(&eye),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: gs.materials.as_entire_binding(),
                    },
                ],
            },
        );
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
        let direct_scene_group = gpu::create_bind_group(
            device,
            &wgpu::BindGroupDescriptor {
                label: Some("direct scene bind group"),
                layout: &direct_pass.scene_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: view_binding(&eye),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: gs.lights.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: gs.shadow_matrices.as_entire_binding(),
                    },
                    tex_entry(3, &gs.shadow_array),
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: wgpu::BindingResource::Sampler(&direct_pass.shadow_sampler),
                    },
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: penumbra.as_entire_binding(),
                    },
                ],
            },
        );
        let lighting_group = |g: &gbuffer::GBuffer| {
            gpu::create_bind_group(
                device,
                &wgpu::BindGroupDescriptor {
                    label: Some("direct gbuffer bind group"),
                    layout: &direct_pass.gbuffer_layout,
                    entries: &g
                        .lighting_inputs()
                        .iter()
                        .enumerate()
                        .map(|(i, v)| tex_entry(i as u32, v))
                        .collect::<Vec<_>>(),
                },
            )
        };
        let direct_gbuffer_group = lighting_group(&gbuf);
        let sub_gbuffer_group = lighting_group(&sub);
        let edges = if spp > 1 && edge_supersampling {
            Some(edges::EdgeBuffers::new(
                ctx,
                &EdgePass::get(ctx).layout,
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
            accum,
            accum_view,
            specular,
            specular_view,
            black_view,
            radiance,
            radiance_view,
            gbuffer_group,
            direct_scene_group,
            direct_gbuffer_group,
            composite_group: None,
            readback: HashMap::new(),
        })
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
                    tex_entry(0, &self.accum_view),
                    tex_entry(1, &self.specular_view),
                    tex_entry(2, indirect),
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

    pub fn has_composite(&self) -> bool {
        self.composite_group.is_some()
    }

    /// Where in its pixel the centre G-buffer is sampled.
    pub fn sample_centre(&self) -> Vec2 {
        (Vec2::splat(0.5) + self.sample_offset).fract()
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
    pub fn write_eye(&mut self, ctx: &GpuContext, scene: &Scene) {
        if self.eye_current {
            return;
        }
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
        let gbuffer_pass = |encoder: &mut wgpu::CommandEncoder,
                            timer: &mut Timer,
                            target: &gbuffer::GBuffer,
                            offset: u32| {
            let ts = timer.pass("gbuffer");
            gbuffer_p.record(
                encoder,
                target,
                &self.gbuffer_group,
                offset,
                &gs.geometry,
                (&gs.textures.group, gs.variant),
                ts,
            );
        };
        let scene_group = &self.direct_scene_group;
        // The edge passes over the centre G-buffer (finding edges, shading them).
        let centre_edges = self.edges.as_ref().map(|edges| edges::EdgeGroups {
            scene: scene_group,
            gbuffer: &self.direct_gbuffer_group,
            edges,
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
                    offset,
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
                encoder = self.for_each_sample(ctx, encoder, progress, |encoder, s, offset| {
                    gbuffer_pass(encoder, timer, &self.sub, offset);
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
                0,
                ts,
            );
            if let Some(groups) = &centre_edges {
                let ts = timer.compute_pass("edge shading");
                edge_p.record_shade(&mut encoder, groups, ts);
            }
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
            &gs.geometry,
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
            let views = &self.sample_views[..per_submit as usize];
            gpu::write_buffer(
                &ctx.queue,
                "eye views",
                &self.eye,
                VIEW_SIZE,
                bytemuck::cast_slice(views),
            );
        }
        while done < spp {
            let batch = per_submit.min(spp - done);
            if done > 0 {
                ctx.queue.submit([encoder.finish()]);
                let views = &self.sample_views[done as usize..(done + batch) as usize];
                gpu::write_buffer(
                    &ctx.queue,
                    "eye views",
                    &self.eye,
                    VIEW_SIZE,
                    bytemuck::cast_slice(views),
                );
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
            &EdgePass::get(ctx).layout,
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

    /// Records copies of the named textures into their readback buffers (created on first
    /// use at this size).
    pub fn record_readback(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        names: &[&'static str],
        indirect: Option<&wgpu::Texture>,
    ) {
        let (w, h) = (self.width, self.height);
        let row = (w * 16).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        for &name in names {
            if !self.readback.contains_key(name) {
                let buffer = gpu::readback_buffer(&ctx.device, "readback", row as u64 * h as u64);
                self.readback.insert(name, buffer);
            }
        }
        for &name in names {
            let Some(texture) = self.texture_of(name, indirect) else {
                continue;
            };
            encoder.copy_texture_to_buffer(
                texture.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: &self.readback[name],
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(row),
                        rows_per_image: Some(h),
                    },
                },
                texture.size(),
            );
        }
    }

    /// Maps the readback buffers of `names` (after all submitted work) and returns their
    /// texels, rows unpadded.
    pub fn read(
        &self,
        ctx: &GpuContext,
        names: &[&'static str],
    ) -> Result<HashMap<&'static str, Vec<Vec4>>> {
        let (w, h) = (self.width as usize, self.height as usize);
        let row = (w * 16).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT as usize);
        let buffers: Vec<&wgpu::Buffer> = names.iter().map(|n| &self.readback[n]).collect();
        let bytes = ctx.read_buffers(&buffers, None)?;
        Ok(names
            .iter()
            .zip(bytes)
            .map(|(&n, b)| {
                let mut out = Vec::with_capacity(w * h);
                for y in 0..h {
                    out.extend_from_slice(bytemuck::cast_slice::<u8, Vec4>(
                        &b[y * row..y * row + w * 16],
                    ));
                }
                (n, out)
            })
            .collect())
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
