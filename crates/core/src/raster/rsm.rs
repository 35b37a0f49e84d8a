//! Reflective shadow maps (Dachsbacher & Stamminger 2005) for method `bidir`: per light the
//! views of the ISPM bounce map ([`super::ispm::bounce_layers`]: one perspective view per spot
//! light, six cube faces per point light, resolutions split by power), each covered texel
//! holding the surface point the light's flux through it reaches (position, normals,
//! material, flux). The targets are copied into mappable buffers in the same submission and
//! read back as [`RsmTexel`]s, from which the frame draws its VPLs.

use super::ispm::{BounceLayer, BounceViewRaw};
use super::timer::Timer;
use super::{buffer_init, gbuffer, Geometry};
use crate::error::{Error, Result};
use crate::gpu::{self, shaders, GpuContext};
use glam::{Vec2, Vec3, Vec4};

const TARGET: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const VIEW_SIZE: u64 = std::mem::size_of::<BounceViewRaw>() as u64;
/// position, normals, diffuse, specular, flux.
const TARGETS: usize = 5;

/// One covered RSM texel.
#[derive(Clone, Copy, Debug)]
pub struct RsmTexel {
    /// Index into `Scene::lights`.
    pub light: usize,
    pub position: Vec3,
    /// Shading and geometric normals, facing the light.
    pub ns: Vec3,
    pub ng: Vec3,
    pub diffuse: Vec3,
    pub roughness: f32,
    pub specular: Vec3,
    pub fresnel: bool,
    /// Flux through the texel (W).
    pub flux: Vec3,
}

/// The RSM pipelines (one per [`super::textures::Variant`]) and their group-0 layout.
pub struct RsmPass {
    pub pipelines: Vec<wgpu::RenderPipeline>,
    /// Group 0: the layer's view (uniform, dynamic offset) and the materials (storage).
    pub layout: wgpu::BindGroupLayout,
}

impl RsmPass {
    pub fn new(device: &wgpu::Device, textures: &wgpu::BindGroupLayout) -> Self {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("rsm bind group layout"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(VIEW_SIZE),
                    },
                    count: None,
                },
                super::storage_entry(1, wgpu::ShaderStages::FRAGMENT),
            ],
        });
        let module = shaders::module(
            device,
            "rsm shader",
            &[
                shaders::COMMON,
                shaders::BSDF,
                shaders::TEXTURE,
                shaders::RSM,
            ],
        );
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("rsm pipeline layout"),
            bind_group_layouts: &[Some(&layout), Some(textures)],
            immediate_size: 0,
        });
        let targets: [_; TARGETS] =
            std::array::from_fn(|_| Some(wgpu::ColorTargetState::from(TARGET)));
        let pipeline = |entry: &str| {
            gpu::create_render_pipeline(
                device,
                &wgpu::RenderPipelineDescriptor {
                    label: Some("rsm pipeline"),
                    layout: Some(&pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_main"),
                        compilation_options: Default::default(),
                        buffers: &[Some(gbuffer::vertex_layout())],
                    },
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: gbuffer::DEPTH,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::Less),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        targets: &targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                },
            )
        };
        let pipelines = super::textures::Variant::ALL
            .iter()
            .map(|v| pipeline(v.entry_point()))
            .collect();
        RsmPass { pipelines, layout }
    }
}

/// The RSM targets of a set of layers, their views and mappable copies.
pub struct RsmTargets {
    max_res: u32,
    n_layers: u32,
    row: u32,
    targets: Vec<wgpu::Texture>,
    layer_views: Vec<(Vec<wgpu::TextureView>, wgpu::TextureView)>,
    staging: Vec<wgpu::Buffer>,
    views: wgpu::Buffer,
    group: wgpu::BindGroup,
}

impl RsmTargets {
    /// Resources for `layers` (`None` when no light emits).
    pub fn new(
        ctx: &GpuContext,
        pass: &RsmPass,
        layers: &[BounceLayer],
        materials: &wgpu::Buffer,
    ) -> Result<Option<Self>> {
        if layers.is_empty() {
            return Ok(None);
        }
        let device = &ctx.device;
        let max_res = layers.iter().map(|l| l.res).max().unwrap_or(1);
        let limits = device.limits();
        if max_res > limits.max_texture_dimension_2d {
            return Err(Error::setting(
                "rsm_size",
                format!(
                    "the reflective shadow map needs {max_res} texels a side; the GPU allows {}",
                    limits.max_texture_dimension_2d
                ),
            ));
        }
        let n_layers = layers.len() as u32;
        if n_layers > limits.max_texture_array_layers {
            return Err(Error::Gpu(format!(
                "{n_layers} reflective-shadow-map layers exceed the GPU's {}",
                limits.max_texture_array_layers
            )));
        }
        let views = buffer_init(
            ctx,
            "rsm views",
            &vec![0u8; n_layers as usize * VIEW_SIZE as usize],
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let group = gpu::create_bind_group(
            device,
            &wgpu::BindGroupDescriptor {
                label: Some("rsm bind group"),
                layout: &pass.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &views,
                            offset: 0,
                            size: wgpu::BufferSize::new(VIEW_SIZE),
                        }),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: materials.as_entire_binding(),
                    },
                ],
            },
        );
        let size = wgpu::Extent3d {
            width: max_res,
            height: max_res,
            depth_or_array_layers: n_layers,
        };
        let make = |label, format, usage| {
            gpu::create_texture(
                device,
                &wgpu::TextureDescriptor {
                    label: Some(label),
                    size,
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                },
            )
        };
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let targets: Vec<_> = [
            "rsm position",
            "rsm normals",
            "rsm diffuse",
            "rsm specular",
            "rsm flux",
        ]
        .into_iter()
        .map(|label| make(label, TARGET, usage))
        .collect();
        let depth = make(
            "rsm depth",
            gbuffer::DEPTH,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        let layer_view = |t: &wgpu::Texture, i: u32| {
            t.create_view(&wgpu::TextureViewDescriptor {
                label: Some("rsm layer"),
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: i,
                array_layer_count: Some(1),
                ..Default::default()
            })
        };
        let layer_views = (0..n_layers)
            .map(|i| {
                (
                    targets.iter().map(|t| layer_view(t, i)).collect(),
                    layer_view(&depth, i),
                )
            })
            .collect();
        let row = (max_res * 16).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let staging = (0..TARGETS)
            .map(|_| {
                gpu::create_buffer(
                    device,
                    &wgpu::BufferDescriptor {
                        label: Some("rsm readback"),
                        size: row as u64 * max_res as u64 * n_layers as u64,
                        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    },
                )
            })
            .collect();
        let rsm = RsmTargets {
            max_res,
            n_layers,
            row,
            targets,
            layer_views,
            staging,
            views,
            group,
        };
        rsm.write_views(ctx, layers);
        Ok(Some(rsm))
    }

    /// Whether these resources serve `layers`.
    pub fn fits(&self, layers: &[BounceLayer]) -> bool {
        self.n_layers as usize == layers.len()
            && self.max_res == layers.iter().map(|l| l.res).max().unwrap_or(1)
    }

    /// Uploads the layers' views (after lights or geometry moved).
    pub fn write_views(&self, ctx: &GpuContext, layers: &[BounceLayer]) {
        let views: Vec<BounceViewRaw> = layers.iter().map(|l| l.view).collect();
        gpu::write_buffer(
            &ctx.queue,
            "rsm views",
            &self.views,
            0,
            bytemuck::cast_slice(&views),
        );
    }

    /// Records the RSM passes of all layers and the copies of their targets.
    pub fn record(
        &self,
        pass: &RsmPass,
        encoder: &mut wgpu::CommandEncoder,
        layers: &[BounceLayer],
        geometry: &Geometry,
        textures: (&wgpu::BindGroup, super::textures::Variant),
        timer: &mut Timer,
    ) {
        for (i, layer) in layers.iter().enumerate() {
            let (views, depth_view) = &self.layer_views[i];
            let attachments: Vec<_> = views
                .iter()
                .map(|view| {
                    Some(wgpu::RenderPassColorAttachment {
                        view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    })
                })
                .collect();
            let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("rsm pass"),
                color_attachments: &attachments,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.pass("rsm"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            rp.set_pipeline(&pass.pipelines[textures.1 as usize]);
            rp.set_viewport(0.0, 0.0, layer.res as f32, layer.res as f32, 0.0, 1.0);
            rp.set_scissor_rect(0, 0, layer.res, layer.res);
            rp.set_bind_group(0, &self.group, &[(i as u64 * VIEW_SIZE) as u32]);
            rp.set_bind_group(1, textures.0, &[]);
            rp.set_vertex_buffer(0, geometry.vertices.slice(..));
            rp.draw(0..geometry.count, 0..1);
        }
        let size = wgpu::Extent3d {
            width: self.max_res,
            height: self.max_res,
            depth_or_array_layers: self.n_layers,
        };
        for (texture, buffer) in self.targets.iter().zip(&self.staging) {
            encoder.copy_texture_to_buffer(
                texture.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(self.row),
                        rows_per_image: Some(self.max_res),
                    },
                },
                size,
            );
        }
    }

    /// Maps the copies once submission `after` is done: the covered texels with flux.
    pub fn read(
        &self,
        ctx: &GpuContext,
        layers: &[BounceLayer],
        after: Option<wgpu::SubmissionIndex>,
    ) -> Result<Vec<RsmTexel>> {
        let (max_res, row) = (self.max_res as usize, self.row as usize);
        let buffers: Vec<&wgpu::Buffer> = self.staging.iter().collect();
        let read: Vec<Vec<Vec4>> = ctx
            .read_buffers(&buffers, after)?
            .into_iter()
            .map(|bytes| {
                bytes
                    .chunks_exact(row)
                    .flat_map(|r| bytemuck::cast_slice::<u8, Vec4>(&r[..max_res * 16]).to_vec())
                    .collect()
            })
            .collect();
        let [position, normals, diffuse, specular, flux] = &read[..] else {
            return Err(Error::Gpu("reflective shadow map readback".into()));
        };
        let mut out = Vec::new();
        for (li, layer) in layers.iter().enumerate() {
            for y in 0..layer.res as usize {
                for x in 0..layer.res as usize {
                    let i = li * max_res * max_res + y * max_res + x;
                    let phi = flux[i].truncate();
                    if position[i].w <= 0.0 || phi.max_element() <= 0.0 {
                        continue;
                    }
                    let n = normals[i];
                    out.push(RsmTexel {
                        light: layer.light,
                        position: position[i].truncate(),
                        ns: super::oct_decode(Vec2::new(n.x, n.y)),
                        ng: super::oct_decode(Vec2::new(n.z, n.w)),
                        diffuse: diffuse[i].truncate(),
                        roughness: diffuse[i].w,
                        specular: specular[i].truncate(),
                        fresnel: specular[i].w > 0.5,
                        flux: phi,
                    });
                }
            }
        }
        Ok(out)
    }
}
