//! The scene's BVH on the GPU: [`GpuBvh`] uploads the flattened two-level tree
//! ([`FlatBvh`]) as group 1 of the passes that trace rays, whose WGSL joins [`WGSL`]
//! (`bvh_closest`, `bvh_occluded`). [`query`] traces a batch of rays with it (the parity
//! tests and the rays/s measurement). Only passes that trace compile this code: no other
//! pipeline pays for it.

pub mod query;

use super::layout::{buffer, buffer_init, storage_entry, uniform_entry_sized};
use super::{GpuContext, Pipelines};
use crate::error::{Error, Result};
use crate::trace::bvh_flat::{FlatBvh, FlatInstance, FlatNode, FlatTri};
use crate::trace::SceneBvh;

/// The traversal (after the pass's own bindings of group 0, before its entry points).
pub const WGSL: &str = include_str!("../shaders/bvh/bvh.wgsl");

/// The group-1 layout every tracing pass shares: nodes, triangles, instances, info.
pub struct BvhLayout {
    pub layout: wgpu::BindGroupLayout,
}

impl Pipelines for BvhLayout {
    fn create(ctx: &GpuContext) -> Self {
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = super::pipeline::bind_group_layout(
            &ctx.device,
            "bvh bind group layout",
            &[
                storage_entry(0, compute),
                storage_entry(1, compute),
                storage_entry(2, compute),
                uniform_entry_sized(3, compute, false, 16),
            ],
        );
        BvhLayout { layout }
    }
}

/// The scene's BVH in GPU buffers and the bind group (group 1) that reads them.
pub struct GpuBvh {
    pub group: wgpu::BindGroup,
    /// Bytes of the nodes, triangles and instances.
    pub bytes: u64,
    _buffers: [wgpu::Buffer; 4],
}

impl GpuBvh {
    /// Uploads `bvh`; an error for a BVH with alpha masks (not traced on the GPU) or one
    /// larger than the adapter's buffers.
    pub fn upload(ctx: &GpuContext, bvh: &SceneBvh) -> Result<GpuBvh> {
        let flat = FlatBvh::new(bvh).ok_or_else(|| {
            Error::Gpu("the GPU traversal has no alpha masks; trace this scene on the CPU".into())
        })?;
        Self::from_flat(ctx, &flat)
    }

    /// Uploads a flattened BVH.
    pub fn from_flat(ctx: &GpuContext, flat: &FlatBvh) -> Result<GpuBvh> {
        let nodes: &[u8] = bytemuck::cast_slice::<FlatNode, u8>(&flat.nodes);
        let tris: &[u8] = bytemuck::cast_slice::<FlatTri, u8>(&flat.tris);
        let instances: &[u8] = bytemuck::cast_slice::<FlatInstance, u8>(&flat.instances);
        for (what, b) in [("BVH nodes", nodes), ("BVH triangles", tris)] {
            ctx.check_buffer(what, b.len() as u64)?;
        }
        let info = [flat.top_root, 0, 0, 0];
        let storage = wgpu::BufferUsages::STORAGE;
        let buffers = [
            buffer_init(ctx, "bvh nodes", nodes, storage),
            buffer_init(ctx, "bvh triangles", tris, storage),
            buffer_init(ctx, "bvh instances", instances, storage),
            buffer_init(
                ctx,
                "bvh info",
                bytemuck::cast_slice(&info),
                wgpu::BufferUsages::UNIFORM,
            ),
        ];
        let layout = BvhLayout::get(ctx);
        let group = super::create_bind_group(
            &ctx.device,
            &wgpu::BindGroupDescriptor {
                label: Some("bvh bind group"),
                layout: &layout.layout,
                entries: &[
                    buffer(0, &buffers[0]),
                    buffer(1, &buffers[1]),
                    buffer(2, &buffers[2]),
                    buffer(3, &buffers[3]),
                ],
            },
        );
        Ok(GpuBvh {
            group,
            bytes: (nodes.len() + tris.len() + instances.len()) as u64,
            _buffers: buffers,
        })
    }
}
