//! Deferred direct lighting: a full-screen pass over the G-buffer that evaluates the uber
//! BSDF for every light with PCF shadow-map visibility, either adding one weighted sub-pixel
//! sample into an `Rgba32Float` accumulation target (additive blending; needs
//! `FLOAT32_BLENDABLE`) or writing the pixel-centre sample (edge-adaptive supersampling,
//! [`super::edges`]). The layouts are visible to compute too: the edge passes share them.

use super::wgsl;
use crate::gpu::layout::texture_entry;
use crate::gpu::shaders;

/// The accumulation target: radiance·weight in rgb, the sum of weights in alpha.
pub const ACCUM: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

pub struct DirectPass {
    /// Adds one weighted sub-pixel sample.
    pub pipeline: wgpu::RenderPipeline,
    /// Writes the pixel-centre sample with weight 1.
    pub centre: wgpu::RenderPipeline,
    /// Group 0: view, lights, shadow matrices, shadow maps, comparison sampler, and the
    /// penumbra taps per axis of the pixel-centre pass ([`penumbra_taps`]).
    pub scene_layout: wgpu::BindGroupLayout,
    /// Group 1: the G-buffer's position, normals, diffuse and specular textures.
    pub gbuffer_layout: wgpu::BindGroupLayout,
    pub shadow_sampler: wgpu::Sampler,
}

/// Visibility taps per axis of the pixel-centre pass in shadow penumbrae: the grid of `spp`
/// sub-pixel samples (its side rounded), 1 for a single sample.
pub fn penumbra_taps(spp: u32) -> u32 {
    ((spp as f64).sqrt().round() as u32).max(1)
}

impl DirectPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let frag = wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let mut view = super::view_entry(0);
        view.visibility |= wgpu::ShaderStages::COMPUTE;
        let scene_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("direct scene bind group layout"),
            entries: &[
                view,
                super::storage_entry(1, frag),
                super::storage_entry(2, frag),
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: frag,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Depth,
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 4,
                    visibility: frag,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 5,
                    visibility: frag,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(16),
                    },
                    count: None,
                },
            ],
        });
        let texture = |binding| texture_entry(binding, frag);
        let gbuffer_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("direct gbuffer bind group layout"),
            entries: &[texture(0), texture(1), texture(2), texture(3)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("direct pipeline layout"),
            bind_group_layouts: &[Some(&scene_layout), Some(&gbuffer_layout)],
            immediate_size: 0,
        });
        let module = shaders::module(
            device,
            "direct shader",
            &[
                shaders::COMMON,
                shaders::BSDF,
                wgsl::SHADOW_LOOKUP,
                wgsl::DIRECT_SHADE,
                shaders::FULLSCREEN,
                wgsl::DIRECT,
            ],
        );
        let add = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let blend = wgpu::BlendState {
            color: add,
            alpha: add,
        };
        let pipeline = |entry: &str, blend: Option<wgpu::BlendState>| {
            let target = wgpu::ColorTargetState {
                format: ACCUM,
                blend,
                write_mask: wgpu::ColorWrites::ALL,
            };
            crate::gpu::create_fullscreen_pipeline(
                device,
                entry,
                &pipeline_layout,
                &module,
                entry,
                target,
            )
        };
        let (centre, pipeline) = (
            pipeline("fs_centre", None),
            pipeline("fs_main", Some(blend)),
        );
        let shadow_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow comparison sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        DirectPass {
            pipeline,
            centre,
            scene_layout,
            gbuffer_layout,
            shadow_sampler,
        }
    }

    /// Records the pass, adding into `accum` (cleared first when `clear`), or writing the
    /// pixel-centre sample when `centre`. The bind groups are those of `scene_layout` and
    /// `gbuffer_layout`.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        accum: &wgpu::TextureView,
        clear: bool,
        centre: bool,
        [scene_group, gbuffer_group]: [&wgpu::BindGroup; 2],
        view_offset: u32,
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let load = if clear {
            wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
        } else {
            wgpu::LoadOp::Load
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("direct light pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: accum,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(if centre { &self.centre } else { &self.pipeline });
        pass.set_bind_group(0, scene_group, &[view_offset]);
        pass.set_bind_group(1, gbuffer_group, &[]);
        pass.draw(0..3, 0..1);
    }
}

impl crate::gpu::Pipelines for DirectPass {
    fn create(ctx: &crate::gpu::GpuContext) -> Self {
        DirectPass::new(&ctx.device)
    }
}
