//! The binned estimators' GPU resources: the parameters, the photon texture, the hierarchy's
//! nodes (a buffer the passes write, copied to a texture the later passes read), the lists'
//! counts, offsets and cursors, the lists themselves (buffer and texture), the cluster
//! walk's job lists and the read-back totals; and the bind group over them and the eye
//! G-buffer ([`Resources::bind_group`]). The photon texture, the lists and the job lists
//! grow ([`Capacity`]).

use super::bins::{Capacity, Grid, LIST_ROW, NODE_ROW, PHOTON_ROW};
use super::passes::BinnedPasses;
use super::{Mode, TiledParamsRaw};
use crate::estimate::target::{IndirectTarget, TARGET};
use crate::gpu::layout::{buffer as buf, buffer_init, texture as tex};
use crate::gpu::{self, GpuContext, Pipelines};
use crate::raster::gbuffer::GBuffer;
use bytemuck::Zeroable;

/// Words of `counts` after the lists' counts: their total, the two job counts, a spare,
/// and the two job passes' (x, y, z) dispatch arguments (cluster.wgsl).
pub(super) const COUNTS_TAIL: u64 = 10;
/// vec4s of a node's quadratic or octant buckets, and its centroid (`COEFFS`).
const COEFFS: u64 = 17;

/// The resources (see the module).
pub(super) struct Resources {
    pub params: wgpu::Buffer,
    pub photons: wgpu::Texture,
    pub node_data: wgpu::Buffer,
    pub node_texels: wgpu::Texture,
    pub coeffs: wgpu::Buffer,
    pub cluster_of: wgpu::Buffer,
    pub counts: wgpu::Buffer,
    pub offsets: wgpu::Buffer,
    pub cursor: wgpu::Buffer,
    pub list: wgpu::Buffer,
    pub list_texels: wgpu::Texture,
    pub jobs: wgpu::Buffer,
    pub job_args: wgpu::Buffer,
    pub total: wgpu::Buffer,
}

/// A texture the passes read and the CPU or a copy writes.
fn texture_2d(
    ctx: &GpuContext,
    label: &str,
    size: [u32; 2],
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
    gpu::texture_2d(&ctx.device, label, size[0], size[1], format, usage)
}

/// A buffer of `size` bytes (at least 16: zero-sized bindings are invalid).
fn buffer(ctx: &GpuContext, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    gpu::create_buffer(
        &ctx.device,
        &wgpu::BufferDescriptor {
            label: Some(label),
            size: size.max(16),
            usage,
            mapped_at_creation: false,
        },
    )
}

impl Resources {
    /// The resources of `grid` in `mode` at `capacity`, for `target`'s low-resolution size.
    pub fn new(
        ctx: &GpuContext,
        target: &IndirectTarget,
        grid: &Grid,
        mode: Mode,
        capacity: Capacity,
    ) -> Self {
        let [lw, lh] = target.low_size;
        let rw = wgpu::BufferUsages::STORAGE;
        let photons = photon_texture(ctx, capacity.photons);
        let (list, list_texels) = lists(ctx, capacity.entries);
        let jobs = job_lists(ctx, capacity.jobs);
        let params = buffer_init(
            ctx,
            "tiled params",
            bytemuck::bytes_of(&TiledParamsRaw::zeroed()),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let cluster = mode != Mode::Tiled;
        // Whole rows, for the copy into the node texture.
        let node_rows = grid.nodes.div_ceil(NODE_ROW);
        let node_data = buffer(
            ctx,
            "hierarchy nodes",
            (node_rows * NODE_ROW) as u64 * 48,
            rw | wgpu::BufferUsages::COPY_SRC,
        );
        let node_texels = texture_2d(
            ctx,
            "hierarchy node texels",
            [3 * NODE_ROW, node_rows],
            TARGET,
        );
        let coeffs_size = if cluster {
            grid.nodes as u64 * COEFFS * 16
        } else {
            16
        };
        let coeffs = buffer(ctx, "node quadratics", coeffs_size, rw);
        let leaves_size = if cluster { (lw * lh) as u64 * 4 } else { 16 };
        let cluster_of = buffer(ctx, "sample leaves", leaves_size, rw);
        let slots64 = grid.slots as u64;
        // The lists' counts, their total, the job counts and the job passes' indirect
        // dispatch arguments (cluster.wgsl).
        let counts = buffer(
            ctx,
            "list counts",
            (slots64 + COUNTS_TAIL) * 4,
            rw | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        // The job passes' dispatch arguments, copied out of `counts` (a buffer cannot be
        // bound for writing and read as indirect arguments by the same dispatch).
        let job_args = buffer(
            ctx,
            "cluster job dispatch",
            24,
            wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
        );
        let offsets = buffer(
            ctx,
            "list offsets",
            slots64 * 4,
            rw | wgpu::BufferUsages::COPY_SRC,
        );
        let cursor = buffer(ctx, "list cursors", slots64 * 4, rw);
        let total = buffer(
            ctx,
            "list total",
            16,
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        Resources {
            params,
            photons,
            node_data,
            node_texels,
            coeffs,
            cluster_of,
            counts,
            offsets,
            cursor,
            list,
            list_texels,
            jobs,
            job_args,
            total,
        }
    }

    /// Grows the photon texture, the lists and the job lists from `old` to `new` sizes
    /// (the photon texture loses its contents, which the caller uploads again; the caller
    /// binds them anew).
    pub fn grow(&mut self, ctx: &GpuContext, old: Capacity, new: Capacity) {
        if new.photons > old.photons {
            self.photons = photon_texture(ctx, new.photons);
        }
        if new.entries > old.entries {
            (self.list, self.list_texels) = lists(ctx, new.entries);
        }
        if new.jobs > old.jobs {
            self.jobs = job_lists(ctx, new.jobs);
        }
    }

    /// The bind group over the resources, the G-buffer's lighting inputs and emission, the
    /// materials' exact models (`models`, `raster::exact_models`) and the target.
    pub fn bind_group(
        &self,
        ctx: &GpuContext,
        (gbuf, models): (&GBuffer, &wgpu::Buffer),
        target: &IndirectTarget,
    ) -> wgpu::BindGroup {
        let inputs = gbuf.lighting_inputs();
        let [photons, list_texels, node_texels] =
            [&self.photons, &self.list_texels, &self.node_texels]
                .map(|t| t.create_view(&Default::default()));
        gpu::create_bind_group(
            &ctx.device,
            &wgpu::BindGroupDescriptor {
                label: Some("binned bind group"),
                layout: &BinnedPasses::get(ctx).layout,
                entries: &[
                    buf(0, &self.params),
                    tex(1, &inputs[0]),
                    tex(2, &inputs[1]),
                    tex(3, &inputs[2]),
                    tex(4, &inputs[3]),
                    tex(5, &photons),
                    buf(6, &self.node_data),
                    buf(7, &self.counts),
                    buf(8, &self.offsets),
                    buf(9, &self.cursor),
                    buf(10, &self.list),
                    tex(11, &list_texels),
                    tex(12, &target.low_view),
                    buf(13, &self.coeffs),
                    buf(14, &self.cluster_of),
                    tex(15, &node_texels),
                    buf(16, &self.jobs),
                    tex(17, gbuf.emission()),
                    buf(18, models),
                ],
            },
        )
    }
}

/// The photon texture for `photons` photons.
fn photon_texture(ctx: &GpuContext, photons: u32) -> wgpu::Texture {
    texture_2d(
        ctx,
        "tiled photons",
        [4 * PHOTON_ROW, photons / PHOTON_ROW],
        TARGET,
    )
}

/// The list buffer and the list texture for `entries` entries.
fn lists(ctx: &GpuContext, entries: u32) -> (wgpu::Buffer, wgpu::Texture) {
    let list = buffer(
        ctx,
        "tile lists",
        entries as u64 * 4,
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    );
    let list_texels = texture_2d(
        ctx,
        "tile list texels",
        [LIST_ROW, entries / LIST_ROW],
        wgpu::TextureFormat::R32Uint,
    );
    (list, list_texels)
}

/// The two job lists of the cluster walk, `jobs` (photon, node) pairs each.
fn job_lists(ctx: &GpuContext, jobs: u32) -> wgpu::Buffer {
    buffer(
        ctx,
        "cluster job lists",
        2 * jobs as u64 * 8,
        wgpu::BufferUsages::STORAGE,
    )
}
