//! Edge-adaptive supersampling of the direct light.
//!
//! Supersampling every pixel with `spp` jittered G-buffer and lighting passes costs `spp`
//! full-screen passes per frame, yet a box-filtered pixel differs from its centre sample
//! (beyond the curvature of smooth shading, which PCF and mip-mapped textures already
//! filter) only where the pixel straddles a discontinuity: a silhouette, a crease, a
//! material boundary. So the direct light is shaded once per pixel at its centre, the pixels
//! whose 3×3 neighbourhood of centre samples crosses a discontinuity are listed, and only
//! those get the mean over all `spp` sub-pixel samples (the same box filter as full
//! supersampling). The listed pixels' sub-sample G-buffer values are kept: while the camera,
//! the geometry and the materials stand still, a frame whose lights changed re-shades them
//! without rasterizing anything but the shadow maps. Each sub-pixel G-buffer pass is masked
//! to the listed pixels (a depth mask, [`EdgePass::record_mask`]): its fragment stage and its
//! six targets' writes happen only there, the same values as a full pass gives them.
//!
//! Shader: `direct_edges.wgsl` (groups 0 and 1 are the direct pass's, group 2 these
//! buffers). Sub-pixel features that no pixel centre sees (a wire thinner than a pixel) are
//! not found; the `edge_supersampling` option (`DirectLightOptions::edge_supersampling`) turns the whole scheme off.

use super::direct_variant::{DirectVariant, VariantCache};
use super::wgsl;
use crate::error::Result;
use crate::gpu::pipeline::{pipeline_layout, RenderSpec};
use crate::gpu::{self, shaders, GpuContext};

/// Bytes kept per listed pixel and sub-pixel sample: position, normals, packed materials,
/// emission.
pub const SAMPLE_BYTES: u64 = 64;
/// Threads per workgroup of the passes over the listed pixels.
const GROUP: u32 = 64;
/// The most bytes the kept samples may take: beyond them (only with edge pixels in the
/// millions), the remaining edge pixels keep their footprint-filtered centre shading.
const MAX_CACHE_BYTES: u64 = 1 << 30;

/// The edge passes' pipelines, compiled once per device.
pub struct EdgePass {
    pub layout: wgpu::BindGroupLayout,
    /// `find_edges` and `store_samples` per emission variant ([`EdgePass::reads`]): a
    /// scene without emitters reads and keeps no emission texel.
    find: VariantCache<wgpu::ComputePipeline>,
    args: wgpu::ComputePipeline,
    store: VariantCache<wgpu::ComputePipeline>,
    /// `shade_edges` per [`DirectVariant`], compiled on first use.
    shade: VariantCache<wgpu::ComputePipeline>,
    device: wgpu::Device,
    module: wgpu::ShaderModule,
    pipeline_layout: wgpu::PipelineLayout,
    /// The edge mask of the sub-pixel G-buffer passes (`edge_mask.wgsl`) and its group's
    /// layout (the image size).
    mask: wgpu::RenderPipeline,
    mask_layout: wgpu::BindGroupLayout,
}

/// The bind groups of one frame's edge passes: the direct pass's scene and G-buffer groups
/// (the centre G-buffer to find edges, a sub-sample's to store it) and the edge buffers'.
#[derive(Clone, Copy)]
pub struct EdgeGroups<'a> {
    pub scene: &'a wgpu::BindGroup,
    pub gbuffer: &'a wgpu::BindGroup,
    pub edges: &'a EdgeBuffers,
    /// The scene's direct-light variant (of it, finding and keeping the samples read the
    /// emission flag alone).
    pub variant: DirectVariant,
}

impl EdgePass {
    pub fn new(
        device: &wgpu::Device,
        scene_layout: &wgpu::BindGroupLayout,
        gbuffer_layout: &wgpu::BindGroupLayout,
    ) -> Self {
        let cs = wgpu::ShaderStages::COMPUTE;
        let storage = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: cs,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("edge bind group layout"),
            entries: &[
                storage(0),
                storage(1),
                storage(2),
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: cs,
                    ty: wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: super::direct::ACCUM,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                    count: None,
                },
                storage(4),
                wgpu::BindGroupLayoutEntry {
                    binding: 5,
                    visibility: cs,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(PARAMS_BYTES),
                    },
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("edge pipeline layout"),
            bind_group_layouts: &[Some(scene_layout), Some(gbuffer_layout), Some(&layout)],
            immediate_size: 0,
        });
        let module = shaders::module(
            device,
            "direct edges shader",
            &[
                &[shaders::COMMON, shaders::BSDF][..],
                &wgsl::DIRECT_SHADING,
                &[wgsl::DIRECT_EDGES],
            ]
            .concat(),
        );
        let pipeline = |entry: &str| {
            gpu::create_compute_pipeline(
                device,
                &wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                },
            )
        };
        let (mask, mask_layout) = mask_pipeline(device);
        EdgePass {
            find: VariantCache::default(),
            args: pipeline("edge_args"),
            store: VariantCache::default(),
            shade: VariantCache::default(),
            device: device.clone(),
            module: module.clone(),
            pipeline_layout: pipeline_layout.clone(),
            layout,
            mask,
            mask_layout,
        }
    }

    fn begin<'e>(
        encoder: &'e mut wgpu::CommandEncoder,
        groups: &EdgeGroups,
        sample: u32,
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) -> wgpu::ComputePass<'e> {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("edge pass"),
            timestamp_writes: timestamps,
        });
        pass.set_bind_group(0, groups.scene, &[0]);
        pass.set_bind_group(1, groups.gbuffer, &[]);
        let offset = groups.edges.params_offset(sample);
        pass.set_bind_group(2, &groups.edges.group, &[offset]);
        pass
    }

    /// Lists the edge pixels of the centre G-buffer (`groups.gbuffer`) and makes the
    /// indirect dispatch arguments of the passes over them.
    pub fn record_find(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        groups: &EdgeGroups,
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let e = groups.edges;
        encoder.clear_buffer(&e.count, 0, None);
        let mut pass = Self::begin(encoder, groups, 0, timestamps);
        pass.set_pipeline(&self.specialized(&self.find, "find_edges", Self::reads(groups.variant)));
        pass.dispatch_workgroups(e.width.div_ceil(8), e.height.div_ceil(8), 1);
        pass.set_pipeline(&self.args);
        pass.dispatch_workgroups(1, 1, 1);
        drop(pass);
        // A buffer written in a pass cannot be its indirect arguments: copy them out (the
        // dispatch's, then the mask's point draw's).
        encoder.copy_buffer_to_buffer(&e.args, 0, &e.indirect, 0, ARGS_BYTES);
        encoder.copy_buffer_to_buffer(&e.count, 0, &e.count_readback, 0, 4);
    }

    /// Keeps sub-pixel sample `sample` of the listed pixels from its G-buffer (`groups.gbuffer`).
    pub fn record_store(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        groups: &EdgeGroups,
        sample: u32,
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let mut pass = Self::begin(encoder, groups, sample, timestamps);
        pass.set_pipeline(&self.specialized(
            &self.store,
            "store_samples",
            Self::reads(groups.variant),
        ));
        pass.dispatch_workgroups_indirect(&groups.edges.indirect, 0);
    }

    /// Makes `depth` (a sub-pixel G-buffer's) the edge mask: 0 everywhere (no fragment
    /// passes a `less` test) but 1 at the listed pixels, the G-buffer pass's own clear
    /// value. A G-buffer pass that then keeps this depth
    /// ([`super::gbuffer::GBufferPass::record_over`] with `LoadOp::Load`) runs its fragment
    /// stage and writes its targets at the listed pixels alone, with the same values there
    /// as after a clear: [`Self::record_store`] reads no other pixel.
    pub fn record_mask(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        edges: &EdgeBuffers,
        depth: &wgpu::TextureView,
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let ops = (wgpu::LoadOp::Clear(0.0), wgpu::StoreOp::Store);
        let mut pass = super::depth_pass(encoder, "edge mask", depth, ops, timestamps);
        pass.set_pipeline(&self.mask);
        pass.set_bind_group(0, &edges.mask_group, &[]);
        pass.set_vertex_buffer(0, edges.edges.slice(..));
        pass.draw_indirect(&edges.indirect, DRAW_ARGS_OFFSET);
    }

    /// Entry point `entry` compiled for `variant` (once, kept in `cache`).
    fn specialized(
        &self,
        cache: &VariantCache<wgpu::ComputePipeline>,
        entry: &'static str,
        variant: DirectVariant,
    ) -> wgpu::ComputePipeline {
        cache.get(variant, |v| {
            let constants = v.constants();
            gpu::create_compute_pipeline(
                &self.device,
                &wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: Some(&self.pipeline_layout),
                    module: &self.module,
                    entry_point: Some(entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &constants,
                        ..Default::default()
                    },
                    cache: None,
                },
            )
        })
    }

    /// What of `variant` finding edges and keeping samples depend on: whether the
    /// G-buffer's emission is read (compared between neighbours, kept with the samples).
    fn reads(variant: DirectVariant) -> DirectVariant {
        DirectVariant {
            emission: variant.emission,
            ..DirectVariant::ALL
        }
    }

    /// Writes the mean direct light of the kept sub-pixel samples over the listed pixels.
    pub fn record_shade(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (groups, variant): (&EdgeGroups, DirectVariant),
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let shade = self.specialized(&self.shade, "shade_edges", variant);
        let mut pass = Self::begin(encoder, groups, 0, timestamps);
        pass.set_pipeline(&shade);
        pass.dispatch_workgroups_indirect(&groups.edges.indirect, 0);
    }
}

/// Bytes of the indirect arguments `edge_args` writes: the dispatch over the listed pixels
/// (3 words, padded to 4), then the mask's draw of one point per listed pixel (4 words).
const ARGS_BYTES: u64 = 32;
/// Where the draw's arguments start.
const DRAW_ARGS_OFFSET: u64 = 16;

/// The mask's pipeline (points at the listed pixels writing depth 1) and its group's layout.
fn mask_pipeline(device: &wgpu::Device) -> (wgpu::RenderPipeline, wgpu::BindGroupLayout) {
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("edge mask bind group layout"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: wgpu::BufferSize::new(16),
            },
            count: None,
        }],
    });
    let pipeline_layout = pipeline_layout(device, "edge mask pipeline layout", &[&layout]);
    let module = shaders::module(device, "edge mask shader", &[wgsl::EDGE_MASK]);
    let pipeline = RenderSpec {
        buffers: &[Some(wgpu::VertexBufferLayout {
            array_stride: 4,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Uint32],
        })],
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::PointList,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: super::gbuffer::DEPTH,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        ..RenderSpec::new(
            "edge mask",
            &pipeline_layout,
            &module,
            "mask_vs",
            Some("mask_fs"),
        )
    }
    .create(device);
    (pipeline, layout)
}

/// `EdgeParams` of `direct_edges.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ParamsRaw {
    sample: u32,
    samples: u32,
    capacity: u32,
    width: u32,
    height: u32,
    _pad: [u32; 3],
}

const PARAMS_BYTES: u64 = std::mem::size_of::<ParamsRaw>() as u64;

/// The edge list, its count, the kept sub-pixel samples and the per-sample parameters, for
/// one image size and sample count.
pub struct EdgeBuffers {
    width: u32,
    height: u32,
    /// Listed pixels the buffers hold.
    pub capacity: u32,
    edges: wgpu::Buffer,
    count: wgpu::Buffer,
    count_readback: wgpu::Buffer,
    args: wgpu::Buffer,
    indirect: wgpu::Buffer,
    _params: wgpu::Buffer,
    params_stride: u32,
    group: wgpu::BindGroup,
    _mask_params: wgpu::Buffer,
    mask_group: wgpu::BindGroup,
}

/// The most listed pixels of `spp` samples: one dispatch dimension of workgroups, and the
/// kept samples within `MAX_CACHE_BYTES` and the adapter's storage-binding limit.
pub fn max_capacity(ctx: &GpuContext, spp: u32) -> u32 {
    let limit = ctx
        .device
        .limits()
        .max_storage_buffer_binding_size
        .min(MAX_CACHE_BYTES);
    let by_memory = limit / (spp.max(1) as u64 * SAMPLE_BYTES);
    (by_memory.min((GROUP * 65_535) as u64) as u32).max(1)
}

/// Environment variable overriding the initial edge capacity (a fraction of the pixels),
/// for testing the regrowth.
pub const CAPACITY_ENV: &str = "GI_EDGE_CAPACITY";

/// Environment variable that turns the edge mask of the sub-pixel G-buffer passes off
/// (`0`), for comparing the images and costs with and without it.
pub const MASK_ENV: &str = "GI_EDGE_MASK";

/// Whether the sub-pixel G-buffer passes are masked to the listed pixels
/// ([`EdgePass::record_mask`]; on unless [`MASK_ENV`] is `0`).
pub fn mask_enabled() -> bool {
    std::env::var(MASK_ENV).map_or(true, |v| v != "0")
}

/// The listed pixels an image of `pixels` starts with: a quarter of the image (edge pixels
/// measured 2.9% of `cornell` at 640×480) and at least 16384 (small images: all of them),
/// or the fraction in [`CAPACITY_ENV`].
pub fn initial_capacity(pixels: u32) -> u32 {
    let wanted = match std::env::var(CAPACITY_ENV)
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
    {
        Some(fraction) => (pixels as f64 * fraction).ceil() as u32,
        None => (pixels / 4).max(16_384),
    };
    wanted.clamp(1, pixels.max(1))
}

impl EdgeBuffers {
    /// Buffers for `capacity` listed pixels of `spp` samples; `accum` is the direct light's
    /// accumulation target (written as storage).
    pub fn new(
        ctx: &GpuContext,
        pass: &EdgePass,
        (width, height, spp): (u32, u32, u32),
        capacity: u32,
        accum: &wgpu::TextureView,
    ) -> Result<Self> {
        let capacity = capacity.clamp(1, max_capacity(ctx, spp));
        let cache_bytes = capacity as u64 * spp as u64 * SAMPLE_BYTES;
        ctx.check_buffer("the edge samples of the direct light", cache_bytes)?;
        let device = &ctx.device;
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            gpu::create_buffer(
                device,
                &wgpu::BufferDescriptor {
                    label: Some(label),
                    size: size.max(16),
                    usage,
                    mapped_at_creation: false,
                },
            )
        };
        use wgpu::BufferUsages as U;
        let edges = buffer("edge pixels", capacity as u64 * 4, U::STORAGE | U::VERTEX);
        let count = buffer("edge count", 16, U::STORAGE | U::COPY_DST | U::COPY_SRC);
        let count_readback = buffer("edge count readback", 16, U::MAP_READ | U::COPY_DST);
        let args = buffer("edge dispatch", ARGS_BYTES, U::STORAGE | U::COPY_SRC);
        let indirect = buffer("edge dispatch args", ARGS_BYTES, U::INDIRECT | U::COPY_DST);
        let cache = buffer("edge samples", cache_bytes, U::STORAGE);
        let align = device.limits().min_uniform_buffer_offset_alignment;
        let params_stride = (PARAMS_BYTES as u32).div_ceil(align) * align;
        let mut bytes = vec![0u8; (params_stride * spp.max(1)) as usize];
        for s in 0..spp.max(1) {
            let raw = ParamsRaw {
                sample: s,
                samples: spp,
                capacity,
                width,
                height,
                _pad: [0; 3],
            };
            let at = (s * params_stride) as usize;
            bytes[at..at + PARAMS_BYTES as usize].copy_from_slice(bytemuck::bytes_of(&raw));
        }
        let params = super::buffer_init(ctx, "edge parameters", &bytes, U::UNIFORM | U::COPY_DST);
        fn entire(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            }
        }
        let group = gpu::create_bind_group(
            device,
            &wgpu::BindGroupDescriptor {
                label: Some("edge bind group"),
                layout: &pass.layout,
                entries: &[
                    entire(0, &edges),
                    entire(1, &count),
                    entire(2, &cache),
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::TextureView(accum),
                    },
                    entire(4, &args),
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &params,
                            offset: 0,
                            size: wgpu::BufferSize::new(PARAMS_BYTES),
                        }),
                    },
                ],
            },
        );
        let size = [width, height, 0, 0];
        let mask_params = super::buffer_init(
            ctx,
            "edge mask parameters",
            bytemuck::cast_slice(&size),
            U::UNIFORM,
        );
        let mask_group = gpu::create_bind_group(
            device,
            &wgpu::BindGroupDescriptor {
                label: Some("edge mask bind group"),
                layout: &pass.mask_layout,
                entries: &[entire(0, &mask_params)],
            },
        );
        Ok(EdgeBuffers {
            width,
            height,
            capacity,
            edges,
            count,
            count_readback,
            args,
            indirect,
            _params: params,
            params_stride,
            group,
            _mask_params: mask_params,
            mask_group,
        })
    }

    fn params_offset(&self, sample: u32) -> u32 {
        sample * self.params_stride
    }

    /// The edge pixels found by the last [`EdgePass::record_find`] (after its submission
    /// is done), listed or not.
    pub fn found(&self, ctx: &GpuContext) -> Result<u32> {
        let bytes = ctx.read_buffers(&[&self.count_readback], None)?.remove(0);
        Ok(u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]))
    }
}

impl crate::gpu::Pipelines for EdgePass {
    fn create(ctx: &crate::gpu::GpuContext) -> Self {
        let direct = super::direct::DirectPass::get(ctx);
        EdgePass::new(&ctx.device, &direct.scene_layout, &direct.gbuffer_layout)
    }
}
