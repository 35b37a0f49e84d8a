//! The composite pass: direct (accumulated supersamples) + specular + indirect into the
//! frame's radiance target, on the GPU, so that only the images asked for are read back.

use super::wgsl;
use crate::gpu::layout::texture_entry;
use crate::gpu::shaders;

/// The radiance target (rgb; alpha 1).
pub const RADIANCE: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

pub struct CompositePass {
    pub pipeline: wgpu::RenderPipeline,
    /// Group 0: the direct accumulation, the specular and the indirect textures.
    pub layout: wgpu::BindGroupLayout,
}

impl CompositePass {
    pub fn new(device: &wgpu::Device) -> Self {
        let texture = |binding| texture_entry(binding, wgpu::ShaderStages::FRAGMENT);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("composite bind group layout"),
            entries: &[texture(0), texture(1), texture(2)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("composite pipeline layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = shaders::module(
            device,
            "composite shader",
            &[shaders::FULLSCREEN, wgsl::COMPOSITE],
        );
        let pipeline = crate::gpu::create_fullscreen_pipeline(
            device,
            "composite pipeline",
            &pipeline_layout,
            &module,
            "fs_main",
            RADIANCE.into(),
        );
        CompositePass { pipeline, layout }
    }

    /// Records the pass into `target`.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        group: &wgpu::BindGroup,
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("composite pass"),
            color_attachments: &[Some(crate::gpu::cleared(target))],
            depth_stencil_attachment: None,
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
    }
}

impl crate::gpu::Pipelines for CompositePass {
    fn create(ctx: &crate::gpu::GpuContext) -> Self {
        CompositePass::new(&ctx.device)
    }
}
