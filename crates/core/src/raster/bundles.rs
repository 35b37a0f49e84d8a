//! Global ray bundles (Sbert 1996; Tokuyoshi & Ogaki 2012 §3.2) for method `bidir`: per
//! bundle a global direction ω, the scene rasterized under a parallel projection along ω
//! (covering its bounding sphere) into per-pixel linked lists of fragments (`bundles.wgsl`:
//! one atomic counter, atomic exchange of the head pointers). The lighting pass walks a
//! pixel's list to find the nearest fragment along ±ω from a visible point.
//!
//! Memory: `res`² head pointers per bundle and one node buffer for all bundles of a frame;
//! fragments beyond its capacity are dropped and counted ([`BundleBuffers::fragments`]).

use super::wgsl;
use super::{buffer_init, gbuffer, Geometry};
use crate::error::{Error, Result};
use crate::gpu::layout::{buffer, dynamic_buffer, uniform_entry_sized};
use crate::gpu::pipeline::{bind_group_layout, pipeline_layout};
use crate::gpu::timer::Timer;
use crate::gpu::{self, shaders, GpuContext};
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};

/// `BundleView` of `common/bundle_types.wgsl`: 256 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct BundleViewRaw {
    pub view_proj: [[f32; 4]; 4],
    pub dir: [f32; 3],
    pub depth_range: f32,
    pub index: u32,
    pub res: u32,
    pub capacity: u32,
    /// 1 / (the frame's bundle-direction density at ±`dir` over a hemisphere, all bundles).
    pub inv_density: f32,
    pub _pad1: [f32; 40],
}

/// Bytes of one fragment node (`Node` of `common/bundle_types.wgsl`).
pub const NODE_BYTES: u64 = 40;
const VIEW_BYTES: u64 = std::mem::size_of::<BundleViewRaw>() as u64;

/// The orthographic view of a bundle along `dir` over the sphere (`centre`, `radius`).
pub fn bundle_view(
    dir: Vec3,
    centre: Vec3,
    radius: f32,
    index: u32,
    res: u32,
    capacity: u32,
) -> BundleViewRaw {
    let r = radius.max(1e-6) * 1.01;
    let up = if dir.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
    let view = crate::scene::light_views::look_to(centre - dir * r, dir, up);
    // Orthographic, view-space x, y in [−r, r] and depth −z in [0, 2r] to clip z in [0, 1].
    let proj = Mat4::from_cols(
        Vec4::new(1.0 / r, 0.0, 0.0, 0.0),
        Vec4::new(0.0, 1.0 / r, 0.0, 0.0),
        Vec4::new(0.0, 0.0, -0.5 / r, 0.0),
        Vec4::W,
    );
    BundleViewRaw {
        view_proj: (proj * view).to_cols_array_2d(),
        dir: dir.into(),
        depth_range: 2.0 * r,
        index,
        res,
        capacity,
        inv_density: 0.0,
        _pad1: [0.0; 40],
    }
}

/// The bundle pipelines (one per [`super::textures::Variant`]) and their group-0 layout.
pub struct BundlePass {
    pub pipelines: Vec<wgpu::RenderPipeline>,
    /// Group 0: view (uniform, dynamic offset), materials, heads, nodes, counter.
    pub layout: wgpu::BindGroupLayout,
}

fn rw_storage(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: false },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl BundlePass {
    pub fn new(device: &wgpu::Device, textures: &wgpu::BindGroupLayout) -> Self {
        let layout = bind_group_layout(
            device,
            "bundle bind group layout",
            &[
                uniform_entry_sized(0, wgpu::ShaderStages::VERTEX_FRAGMENT, true, VIEW_BYTES),
                super::storage_entry(1, wgpu::ShaderStages::FRAGMENT),
                rw_storage(2),
                rw_storage(3),
                rw_storage(4),
            ],
        );
        let module = shaders::module(
            device,
            "bundle shader",
            &[
                shaders::COMMON,
                shaders::BSDF,
                shaders::TEXTURE,
                wgsl::BUNDLE_TYPES,
                shaders::SCENE_VERTEX,
                wgsl::BUNDLES,
            ],
        );
        let pipeline_layout =
            pipeline_layout(device, "bundle pipeline layout", &[&layout, textures]);
        let pipelines = gbuffer::scene_pipelines(
            device,
            "bundle pipeline",
            &pipeline_layout,
            &module,
            &[],
            false,
        );
        BundlePass { pipelines, layout }
    }
}

/// The buffers of a frame's bundles: views, head pointers, fragment nodes, the counter and
/// its readback.
pub struct BundleBuffers {
    pub bundles: u32,
    pub res: u32,
    pub capacity: u32,
    pub views: wgpu::Buffer,
    pub heads: wgpu::Buffer,
    pub nodes: wgpu::Buffer,
    counter: wgpu::Buffer,
    counter_readback: wgpu::Buffer,
    depth: wgpu::TextureView,
    group: wgpu::BindGroup,
}

impl BundleBuffers {
    /// Buffers for `bundles` bundles of `res`² pixels and `memory` bytes of nodes.
    pub fn new(
        ctx: &GpuContext,
        pass: &BundlePass,
        materials: &wgpu::Buffer,
        bundles: u32,
        res: u32,
        memory: u64,
    ) -> Result<Self> {
        let device = &ctx.device;
        let max_dim = device.limits().max_texture_dimension_2d;
        if res > max_dim {
            return Err(Error::setting(
                "bundle_resolution",
                format!("the GPU allows at most {max_dim}"),
            ));
        }
        let bundles = bundles.max(1);
        let head_bytes = bundles as u64 * res as u64 * res as u64 * 4;
        let capacity = (memory / NODE_BYTES).clamp(1, u32::MAX as u64) as u32;
        let node_bytes = capacity as u64 * NODE_BYTES;
        // Each list is one storage binding: past the GPU's binding size the bind group would
        // fail validation (an untyped GPU error) where the setting is what is wrong.
        let max_bind = device.limits().max_storage_buffer_binding_size;
        if node_bytes > max_bind {
            return Err(Error::setting(
                "bundle_memory_mb",
                format!(
                    "the GPU binds at most {} of fragment lists",
                    crate::error::human(max_bind)
                ),
            ));
        }
        if head_bytes > max_bind {
            return Err(Error::setting(
                "bundle_resolution",
                format!(
                    "{bundles} bundles of {res}² need {} of list heads; the GPU binds at most {}",
                    crate::error::human(head_bytes),
                    crate::error::human(max_bind)
                ),
            ));
        }
        ctx.check_buffer("bundle head pointers", head_bytes)?;
        ctx.check_buffer("bundle fragments", node_bytes)?;
        crate::memory::check(
            || "the ray-bundle lists".to_string(),
            head_bytes + node_bytes,
        )?;
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let views = buffer_init(
            ctx,
            "bundle views",
            &vec![0u8; (bundles as u64 * VIEW_BYTES) as usize],
            wgpu::BufferUsages::UNIFORM | storage,
        );
        let make = |label, size| {
            gpu::create_buffer(
                device,
                &wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage: storage | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                },
            )
        };
        let heads = make("bundle heads", head_bytes);
        let nodes = make("bundle nodes", node_bytes);
        let counter = make("bundle counter", 4);
        let counter_readback = gpu::readback_buffer(device, "bundle counter readback", 4);
        let depth = gpu::texture_2d(
            device,
            "bundle depth",
            res,
            res,
            gbuffer::DEPTH,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        )
        .create_view(&Default::default());
        let group = gpu::create_bind_group(
            device,
            &wgpu::BindGroupDescriptor {
                label: Some("bundle bind group"),
                layout: &pass.layout,
                entries: &[
                    dynamic_buffer(0, &views, VIEW_BYTES),
                    buffer(1, materials),
                    buffer(2, &heads),
                    buffer(3, &nodes),
                    buffer(4, &counter),
                ],
            },
        );
        Ok(BundleBuffers {
            bundles,
            res,
            capacity,
            views,
            heads,
            nodes,
            counter,
            counter_readback,
            depth,
            group,
        })
    }

    /// Uploads the views of the frame's bundles.
    pub fn write_views(&self, ctx: &GpuContext, views: &[BundleViewRaw]) {
        gpu::write_buffer(
            &ctx.queue,
            "bundle views",
            &self.views,
            0,
            bytemuck::cast_slice(views),
        );
    }

    /// Records the lists of `count` bundles (heads and counter cleared first) and the copy of
    /// the counter.
    pub fn record(
        &self,
        pass: &BundlePass,
        encoder: &mut wgpu::CommandEncoder,
        count: u32,
        geometry: &Geometry,
        textures: (&wgpu::BindGroup, super::textures::Variant),
        timer: &mut Timer,
    ) {
        encoder.clear_buffer(&self.heads, 0, None);
        encoder.clear_buffer(&self.counter, 0, None);
        for i in 0..count.min(self.bundles) {
            let ops = (wgpu::LoadOp::Clear(1.0), wgpu::StoreOp::Discard);
            let ts = timer.pass("ray bundles");
            let mut rp = super::depth_pass(encoder, "bundle pass", &self.depth, ops, ts);
            rp.set_pipeline(&pass.pipelines[textures.1 as usize]);
            rp.set_bind_group(0, &self.group, &[(i as u64 * VIEW_BYTES) as u32]);
            rp.set_bind_group(1, textures.0, &[]);
            geometry.draw(&mut rp, None);
        }
        encoder.copy_buffer_to_buffer(&self.counter, 0, &self.counter_readback, 0, 4);
    }

    /// Fragments written and dropped (beyond the capacity) by the last recorded bundles,
    /// once submission `after` is done.
    pub fn fragments(
        &self,
        ctx: &GpuContext,
        after: Option<wgpu::SubmissionIndex>,
    ) -> Result<(u64, u64)> {
        let bytes = ctx.read_buffers(&[&self.counter_readback], after)?;
        let b = bytes
            .first()
            .filter(|b| b.len() >= 4)
            .ok_or_else(|| Error::Gpu("bundle counter readback".into()))?;
        let n = u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u64;
        Ok((n, n.saturating_sub(self.capacity as u64)))
    }
}

impl crate::gpu::Pipelines for BundlePass {
    fn create(ctx: &crate::gpu::GpuContext) -> Self {
        BundlePass::new(
            &ctx.device,
            &super::textures::TexturesLayout::get(ctx).layout,
        )
    }
}
