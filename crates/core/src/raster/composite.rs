//! The composite pass: direct (accumulated supersamples) + specular + indirect into the
//! frame's radiance target, on the GPU, so that only the images asked for are read back.

use super::wgsl;
use crate::gpu::layout::texture_entry;
use crate::gpu::pipeline::draw_fullscreen;
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
        let pipeline = &self.pipeline;
        draw_fullscreen(
            encoder,
            "composite pass",
            target,
            pipeline,
            &[group],
            timestamps,
        );
    }
}

impl crate::gpu::Pipelines for CompositePass {
    fn create(ctx: &crate::gpu::GpuContext) -> Self {
        CompositePass::new(&ctx.device)
    }
}
