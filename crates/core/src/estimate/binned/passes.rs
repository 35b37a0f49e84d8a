//! The binding layout the binned estimators share, and each estimator's pipelines,
//! compiled on first use (a pipeline costs 20-360 ms on lavapipe): [`super::tiled`]'s, and
//! [`super::cluster`]'s (with [`super::directional`]'s shading, from the same module).

use super::cluster::ClusterPipelines;
use super::tiled::TiledPipelines;
use crate::estimate::wgsl;
use crate::gpu::layout::{
    storage_rw_entry, storage_texture_entry, texture_entry, uint_texture_entry, uniform_entry_sized,
};
use crate::gpu::{self, shaders};
use std::sync::OnceLock;

/// The WGSL every binned estimator's module starts with (the tiled binning's, which the
/// cluster hierarchy's reuses).
pub(super) const TILED_PARTS: [&str; 7] = [
    shaders::COMMON,
    shaders::BSDF,
    shaders::MODELS,
    crate::raster::wgsl::EXACT_MODELS,
    wgsl::PHOTON_VOLUME,
    shaders::FIXED_SUM,
    wgsl::TILED,
];

/// The binding layout and the pipelines (see the module).
pub struct BinnedPasses {
    pub(super) layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    pub(super) tiled: OnceLock<TiledPipelines>,
    pub(super) cluster: OnceLock<ClusterPipelines>,
}

impl BinnedPasses {
    fn new(device: &wgpu::Device) -> Self {
        let compute = wgpu::ShaderStages::COMPUTE;
        let float = |binding| texture_entry(binding, compute);
        let storage = |binding| storage_rw_entry(binding, compute);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("binned bind group layout"),
            entries: &[
                uniform_entry_sized(0, compute, false, 0),
                float(1),
                float(2),
                float(3),
                float(4),
                float(5),
                storage(6),
                storage(7),
                storage(8),
                storage(9),
                storage(10),
                uint_texture_entry(11, compute),
                storage_texture_entry(12, compute, crate::estimate::target::TARGET),
                storage(13),
                storage(14),
                float(15),
                storage(16),
                float(17),
                crate::gpu::layout::storage_entry(18, compute),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("binned pipeline layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        BinnedPasses {
            layout,
            pipeline_layout,
            tiled: OnceLock::new(),
            cluster: OnceLock::new(),
        }
    }

    /// The compute pipelines of `entry_points` in the module of WGSL `parts`.
    pub(super) fn pipelines<const N: usize>(
        &self,
        device: &wgpu::Device,
        label: &str,
        parts: &[&str],
        entry_points: [&str; N],
    ) -> [wgpu::ComputePipeline; N] {
        let module = shaders::module(device, label, parts);
        entry_points.map(|entry_point| {
            gpu::create_compute_pipeline(
                device,
                &wgpu::ComputePipelineDescriptor {
                    label: Some(entry_point),
                    layout: Some(&self.pipeline_layout),
                    module: &module,
                    entry_point: Some(entry_point),
                    compilation_options: Default::default(),
                    cache: None,
                },
            )
        })
    }
}

impl crate::gpu::Pipelines for BinnedPasses {
    fn create(ctx: &crate::gpu::GpuContext) -> Self {
        BinnedPasses::new(&ctx.device)
    }
}
