//! The compute estimators that bin photons into lists before shading the view samples
//! (`estimate/shaders/tiled.wgsl` and `cluster.wgsl`), over the same photons, kernels, BSDF and
//! normal test as the raster photon volumes ([`super::Volumes`]), so the same image up to
//! the order of the float sums; the work runs on compute units instead of the rasterizer.
//! - [`Mode::Tiled`] (Mara et al. 2013, as Moreau et al. 2016 section 3.2 describe it): the
//!   photons are binned to screen tiles (counting, prefix sum, list build; each tile bounded
//!   by the world-space box of its view samples) and every view sample sums its tile's list.
//! - [`Mode::Cluster`] (Moreau et al. 2016 section 4): the view samples of each tile are
//!   split into clusters by depth and normal, a 3-level hierarchy of boxes and normal cones is built over
//!   them, each photon walks it top-down (rejecting by bounds and cone, *trivially accepting*
//!   nodes wholly inside its kernel), and accepted photons are summed per node exactly as a
//!   quadratic in the sample position, so a sample pays for the photons that only overlap
//!   its leaf.
//!
//! The photon lists are sized when photons are uploaded, from a CPU estimate of the tiles
//! under each photon's projected kernel (usually 2–4× what the GPU writes); a frame whose
//! lists overflow anyway is detected at readback ([`Binned::overflowed`]) and splatted again
//! with room for them.

use super::target::IndirectTarget;
use super::wgsl;
use crate::error::{Error, Result};
use crate::estimate::volume_shape::projected_radius;
use crate::gpu::layout::texture as tex;
use crate::gpu::timer::Timer;
use crate::gpu::Pipelines;
use crate::gpu::{self, shaders, GpuContext};
use crate::photon::radius::VolumeRadius;
use crate::photon::radius::Z_RATIO;
use crate::photon::Photon;
use crate::raster::buffer_init;
use crate::raster::gbuffer::GBuffer;
use crate::scene::{Camera, Scene};
use bytemuck::{Pod, Zeroable};
use std::sync::OnceLock;

/// Tile side in low-resolution texels (`TILE` of tiled.wgsl).
pub const TILE: u32 = 8;
/// Photons per row of the photon texture (`PHOTON_ROW`), 4 texels each.
const PHOTON_ROW: u32 = 1024;
/// List entries per row of the list texture (`LIST_ROW`).
const LIST_ROW: u32 = 4096;
/// Nodes per row of the node texture (`NODE_ROW`), 3 texels each.
const NODE_ROW: u32 = 1024;
/// Threads of the per-photon passes' workgroups.
const PHOTON_GROUP: u32 = 64;
/// Leaf clusters and accept lists per tile a photon's rectangle covers, on average, in the
/// first list estimate of the hierarchy modes ([`Binned::estimate_entries`]). Measured: the
/// walk writes about a sixth of twice the tiles (cornell, 1280×720, 200k photons), so one
/// per tile still leaves 3× room.
const HIERARCHY_ENTRIES_PER_TILE: u64 = 1;
/// Environment variable scaling the first list estimate (default 1): small values force the
/// overflow-regrow-redo path, which tests exercise with it.
pub const LIST_ESTIMATE_ENV: &str = "GI_LIST_ESTIMATE";
/// The same for the cluster walk's job lists alone.
pub const JOB_ESTIMATE_ENV: &str = "GI_JOB_ESTIMATE";

/// A test knob: the positive number in environment variable `name`, else 1.
fn estimate_scale(name: &str) -> f64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v > 0.0)
        .unwrap_or(1.0)
}

/// Words of `counts` after the lists' counts: their total, the two job counts, a spare,
/// and the two job passes' (x, y, z) dispatch arguments (cluster.wgsl).
const COUNTS_TAIL: u64 = 10;
/// Smallest capacity of each job list.
const MIN_JOBS: u32 = 64;
/// Leaf clusters per tile (`CLUSTERS_PER_TILE` of cluster.wgsl).
const CLUSTERS_PER_TILE: u32 = 8;
/// Children per side of a hierarchy node (`FANOUT`).
const FANOUT: u32 = 4;
/// vec4s of a node's quadratic or octant buckets, and its centroid (`COEFFS`).
const COEFFS: u64 = 17;

/// Which binning estimator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Tiled,
    Cluster,
    /// The cluster hierarchy with per-node octant flux buckets (Moreau et al. 4.7).
    Directional,
}

/// `TiledParams` of tiled.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct TiledParamsRaw {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 3],
    r_max: f32,
    low_size: [u32; 2],
    tiles: [u32; 2],
    subsample: u32,
    photons: u32,
    capacity: u32,
    z_ratio: f32,
    l1: [u32; 2],
    l2: [u32; 2],
    level_first: [u32; 4],
    nodes: u32,
    slots: u32,
    jobs: u32,
    _pad: u32,
}

/// The binding layout shared by both modes, and each mode's pipelines, compiled on first
/// use (a pipeline costs 20-360 ms on lavapipe).
pub struct BinnedPasses {
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    tiled: OnceLock<TiledPipelines>,
    cluster: OnceLock<ClusterPipelines>,
}

struct TiledPipelines {
    tile_bounds: wgpu::ComputePipeline,
    bin_count: wgpu::ComputePipeline,
    scan: wgpu::ComputePipeline,
    bin_fill: wgpu::ComputePipeline,
    shade: wgpu::ComputePipeline,
}

struct ClusterPipelines {
    leaves: wgpu::ComputePipeline,
    parents1: wgpu::ComputePipeline,
    parents2: wgpu::ComputePipeline,
    top_count: wgpu::ComputePipeline,
    jobs0: wgpu::ComputePipeline,
    mid_count: wgpu::ComputePipeline,
    jobs1: wgpu::ComputePipeline,
    low_count: wgpu::ComputePipeline,
    scan: wgpu::ComputePipeline,
    top_fill: wgpu::ComputePipeline,
    mid_fill: wgpu::ComputePipeline,
    low_fill: wgpu::ComputePipeline,
    accumulate: wgpu::ComputePipeline,
    shade: wgpu::ComputePipeline,
    directional_accumulate: wgpu::ComputePipeline,
    directional_shade: wgpu::ComputePipeline,
}

fn entry(binding: u32, ty: wgpu::BindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty,
        count: None,
    }
}

fn texture(sample_type: wgpu::TextureSampleType) -> wgpu::BindingType {
    wgpu::BindingType::Texture {
        sample_type,
        view_dimension: wgpu::TextureViewDimension::D2,
        multisampled: false,
    }
}

fn storage() -> wgpu::BindingType {
    wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Storage { read_only: false },
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

impl BinnedPasses {
    fn new(device: &wgpu::Device) -> Self {
        let float = texture(wgpu::TextureSampleType::Float { filterable: false });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("binned bind group layout"),
            entries: &[
                entry(
                    0,
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                ),
                entry(1, float),
                entry(2, float),
                entry(3, float),
                entry(4, float),
                entry(5, float),
                entry(6, storage()),
                entry(7, storage()),
                entry(8, storage()),
                entry(9, storage()),
                entry(10, storage()),
                entry(11, texture(wgpu::TextureSampleType::Uint)),
                entry(
                    12,
                    wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: super::target::TARGET,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                ),
                entry(13, storage()),
                entry(14, storage()),
                entry(15, float),
                entry(16, storage()),
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

    fn pipelines<const N: usize>(
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

    fn tiled(&self, device: &wgpu::Device) -> &TiledPipelines {
        self.tiled.get_or_init(|| {
            let [tile_bounds, bin_count, scan, bin_fill, shade] = self.pipelines(
                device,
                "tiled shader",
                &[
                    shaders::COMMON,
                    shaders::BSDF,
                    wgsl::PHOTON_VOLUME,
                    shaders::FIXED_SUM,
                    wgsl::TILED,
                ],
                ["tile_bounds", "bin_count", "scan", "bin_fill", "shade"],
            );
            TiledPipelines {
                tile_bounds,
                bin_count,
                scan,
                bin_fill,
                shade,
            }
        })
    }

    fn cluster(&self, device: &wgpu::Device) -> &ClusterPipelines {
        self.cluster.get_or_init(|| {
            let [
                leaves,
                parents1,
                parents2,
                top_count,
                jobs0,
                mid_count,
                jobs1,
                low_count,
                scan,
                top_fill,
                mid_fill,
                low_fill,
                accumulate,
                shade,
                directional_accumulate,
                directional_shade,
            ] = self
                .pipelines(
                    device,
                    "cluster shader",
                    &[
                        shaders::COMMON,
                        shaders::BSDF,
                        wgsl::PHOTON_VOLUME,
                        shaders::FIXED_SUM,
                        wgsl::TILED,
                        wgsl::CLUSTER,
                    ],
                    [
                        "cluster_leaves",
                        "cluster_parents1",
                        "cluster_parents2",
                        "cluster_top_count",
                        "cluster_jobs0",
                        "cluster_mid_count",
                        "cluster_jobs1",
                        "cluster_low_count",
                        "scan",
                        "cluster_top_fill",
                        "cluster_mid_fill",
                        "cluster_low_fill",
                        "cluster_accumulate",
                        "cluster_shade",
                        "directional_accumulate",
                        "directional_shade",
                    ],
                );
            ClusterPipelines {
                leaves,
                parents1,
                parents2,
                top_count,
                jobs0,
                mid_count,
                jobs1,
                low_count,
                scan,
                top_fill,
                mid_fill,
                low_fill,
                accumulate,
                shade,
                directional_accumulate,
                directional_shade,
            }
        })
    }
}

/// Sizes of the growable resources.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Capacity {
    /// Photons the photon texture holds (a multiple of `PHOTON_ROW`).
    photons: u32,
    /// List entries (a multiple of `LIST_ROW`).
    entries: u32,
    /// Jobs of each of the cluster walk's two job lists.
    jobs: u32,
}

pub struct Binned {
    mode: Mode,
    pub(super) target: IndirectTarget,
    tiles: [u32; 2],
    /// Nodes per row and rows of hierarchy levels 1 and 2 (cluster mode).
    l1: [u32; 2],
    l2: [u32; 2],
    /// Hierarchy nodes (tiled: one per tile) and photon lists.
    nodes: u32,
    slots: u32,
    params: wgpu::Buffer,
    last_params: Option<TiledParamsRaw>,
    photons: wgpu::Texture,
    node_data: wgpu::Buffer,
    node_texels: wgpu::Texture,
    coeffs: wgpu::Buffer,
    cluster_of: wgpu::Buffer,
    counts: wgpu::Buffer,
    offsets: wgpu::Buffer,
    cursor: wgpu::Buffer,
    list: wgpu::Buffer,
    list_texels: wgpu::Texture,
    jobs: wgpu::Buffer,
    job_args: wgpu::Buffer,
    total: wgpu::Buffer,
    group: wgpu::BindGroup,
    capacity: Capacity,
    /// Photons uploaded for this frame.
    count: u32,
    /// List entries of the last estimate: all, and those of trivially accepted photons.
    entries: (u64, u64),
}

fn texture_2d(
    ctx: &GpuContext,
    label: &str,
    size: [u32; 2],
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    gpu::texture_2d(
        &ctx.device,
        label,
        size[0],
        size[1],
        format,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    )
}

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

impl Binned {
    /// Resources for a `width × height` image over the G-buffer `gbuf`.
    pub fn new(
        ctx: &GpuContext,
        gbuf: &GBuffer,
        mode: Mode,
        size: [u32; 2],
        subsample: u32,
    ) -> Self {
        let target = IndirectTarget::new(ctx, gbuf, size[0], size[1], subsample);
        let [lw, lh] = target.low_size;
        let tiles = [lw.div_ceil(TILE), lh.div_ceil(TILE)];
        let l1 = [tiles[0].div_ceil(FANOUT), tiles[1].div_ceil(FANOUT)];
        let l2 = [l1[0].div_ceil(FANOUT), l1[1].div_ceil(FANOUT)];
        let n0 = tiles[0] * tiles[1];
        let (nodes, slots) = match mode {
            Mode::Tiled => (n0, n0),
            Mode::Cluster | Mode::Directional => {
                let leaves = n0 * CLUSTERS_PER_TILE;
                let nodes = leaves + l1[0] * l1[1] + l2[0] * l2[1];
                (nodes, nodes + leaves)
            }
        };
        let rw = wgpu::BufferUsages::STORAGE;
        let capacity = Capacity {
            photons: PHOTON_ROW,
            entries: LIST_ROW,
            jobs: if mode == Mode::Tiled { 0 } else { MIN_JOBS },
        };
        let photons = Self::photon_texture(ctx, capacity.photons);
        let (list, list_texels) = Self::lists(ctx, capacity.entries);
        let jobs = Self::job_lists(ctx, capacity.jobs);
        let params = buffer_init(
            ctx,
            "tiled params",
            bytemuck::bytes_of(&TiledParamsRaw::zeroed()),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let cluster = mode != Mode::Tiled;
        // Whole rows, for the copy into the node texture.
        let node_rows = nodes.div_ceil(NODE_ROW);
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
            super::target::TARGET,
        );
        let coeffs = buffer(
            ctx,
            "node quadratics",
            if cluster {
                nodes as u64 * COEFFS * 16
            } else {
                16
            },
            rw,
        );
        let cluster_of = buffer(
            ctx,
            "sample leaves",
            if cluster { (lw * lh) as u64 * 4 } else { 16 },
            rw,
        );
        let slots64 = slots as u64;
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
        let group = Self::bind_group(
            ctx,
            gbuf,
            &target,
            [
                &params,
                &node_data,
                &counts,
                &offsets,
                &cursor,
                &list,
                &coeffs,
                &cluster_of,
                &jobs,
            ],
            [&photons, &list_texels, &node_texels],
        );
        Binned {
            mode,
            target,
            tiles,
            l1,
            l2,
            nodes,
            slots,
            params,
            last_params: None,
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
            group,
            capacity,
            count: 0,
            entries: (0, 0),
        }
    }

    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// List entries of the last estimate (after [`Binned::overflowed`] read them): all, and
    /// those that trivially accepted a photon for a whole node.
    pub fn entries(&self) -> (u64, u64) {
        self.entries
    }

    /// The photon texture for `photons` photons.
    fn photon_texture(ctx: &GpuContext, photons: u32) -> wgpu::Texture {
        texture_2d(
            ctx,
            "tiled photons",
            [4 * PHOTON_ROW, photons / PHOTON_ROW],
            super::target::TARGET,
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

    fn bind_group(
        ctx: &GpuContext,
        gbuf: &GBuffer,
        target: &IndirectTarget,
        buffers: [&wgpu::Buffer; 9],
        textures: [&wgpu::Texture; 3],
    ) -> wgpu::BindGroup {
        let inputs = gbuf.lighting_inputs();
        let [photons, list_texels, node_texels] =
            textures.map(|t| t.create_view(&Default::default()));
        let [params, nodes, counts, offsets, cursor, list, coeffs, cluster_of, jobs] = buffers;
        fn buf(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            }
        }
        gpu::create_bind_group(
            &ctx.device,
            &wgpu::BindGroupDescriptor {
                label: Some("binned bind group"),
                layout: &BinnedPasses::get(ctx).layout,
                entries: &[
                    buf(0, params),
                    tex(1, &inputs[0]),
                    tex(2, &inputs[1]),
                    tex(3, &inputs[2]),
                    tex(4, &inputs[3]),
                    tex(5, &photons),
                    buf(6, nodes),
                    buf(7, counts),
                    buf(8, offsets),
                    buf(9, cursor),
                    buf(10, list),
                    tex(11, &list_texels),
                    tex(12, &target.low_view),
                    buf(13, coeffs),
                    buf(14, cluster_of),
                    tex(15, &node_texels),
                    buf(16, jobs),
                ],
            },
        )
    }

    /// Grows the photon texture or the lists to `want` (never shrinks).
    fn grow(&mut self, ctx: &GpuContext, gbuf: &GBuffer, want: Capacity) -> Result<()> {
        let limits = ctx.device.limits();
        let max_rows = limits.max_texture_dimension_2d as u64;
        let max_entries = (max_rows * LIST_ROW as u64)
            .min(limits.max_storage_buffer_binding_size / 4)
            .min(limits.max_buffer_size / 4);
        if want.entries as u64 > max_entries {
            return Err(Error::Gpu(format!(
                "the binned estimator's photon lists need {} entries; the adapter holds at \
                 most {max_entries} (use a smaller kernel_scale, fewer photons, or \
                 estimator \"volumes\")",
                want.entries
            )));
        }
        if (want.photons / PHOTON_ROW) as u64 > max_rows {
            return Err(Error::Gpu(format!(
                "the binned estimators hold at most {} photons on this adapter",
                max_rows * PHOTON_ROW as u64
            )));
        }
        let capacity = Capacity {
            photons: want.photons.max(self.capacity.photons),
            entries: want.entries.max(self.capacity.entries),
            jobs: want.jobs.max(self.capacity.jobs),
        };
        if capacity == self.capacity {
            return Ok(());
        }
        // The photon texture keeps its contents unless it grows (then the caller uploads).
        if capacity.photons > self.capacity.photons {
            self.photons = Self::photon_texture(ctx, capacity.photons);
        }
        if capacity.entries > self.capacity.entries {
            (self.list, self.list_texels) = Self::lists(ctx, capacity.entries);
        }
        if capacity.jobs > self.capacity.jobs {
            self.jobs = Self::job_lists(ctx, capacity.jobs);
        }
        self.group = Self::bind_group(
            ctx,
            gbuf,
            &self.target,
            [
                &self.params,
                &self.node_data,
                &self.counts,
                &self.offsets,
                &self.cursor,
                &self.list,
                &self.coeffs,
                &self.cluster_of,
                &self.jobs,
            ],
            [&self.photons, &self.list_texels, &self.node_texels],
        );
        self.capacity = capacity;
        self.last_params = None;
        Ok(())
    }

    /// The estimate at full resolution.
    pub fn output(&self) -> (&wgpu::Texture, &wgpu::TextureView) {
        self.target.output()
    }

    /// Uploads the parameters when they changed.
    pub fn write_params(&mut self, ctx: &GpuContext, scene: &Scene, radius: VolumeRadius) {
        self.target.write_params(ctx, scene);
        let params = TiledParamsRaw {
            view_proj: self.target.view_proj(scene).to_cols_array_2d(),
            eye: scene.camera.position.into(),
            r_max: radius.r_max,
            low_size: self.target.low_size,
            tiles: self.tiles,
            subsample: self.target.subsample,
            photons: self.count,
            capacity: self.capacity.entries,
            z_ratio: Z_RATIO,
            l1: self.l1,
            l2: self.l2,
            level_first: [
                0,
                self.tiles[0] * self.tiles[1] * CLUSTERS_PER_TILE,
                self.tiles[0] * self.tiles[1] * CLUSTERS_PER_TILE + self.l1[0] * self.l1[1],
                self.nodes,
            ],
            nodes: self.nodes,
            slots: self.slots,
            jobs: self.capacity.jobs,
            _pad: 0,
        };
        if self
            .last_params
            .is_some_and(|p| bytemuck::bytes_of(&p) == bytemuck::bytes_of(&params))
        {
            return;
        }
        gpu::write_buffer(
            &ctx.queue,
            "tiled params",
            &self.params,
            0,
            bytemuck::bytes_of(&params),
        );
        self.last_params = Some(params);
    }

    /// Uploads the photons to splat, growing the photon texture (and, before the first
    /// frame has measured them, the lists) when they don't fit.
    pub fn write_photons(
        &mut self,
        ctx: &GpuContext,
        gbuf: &GBuffer,
        photons: &[Photon],
        camera: &Camera,
    ) -> Result<()> {
        let n = photons.len() as u32;
        let rows = n.div_ceil(PHOTON_ROW).max(1);
        let (entries, jobs) = self.estimate_entries(photons, camera);
        let entries = entries.min(u32::MAX as u64) as u32;
        let jobs = match self.mode {
            Mode::Tiled => 0,
            Mode::Cluster | Mode::Directional => jobs.min(u32::MAX as u64) as u32,
        }
        .max(MIN_JOBS);
        self.grow(
            ctx,
            gbuf,
            Capacity {
                photons: (2 * rows).next_power_of_two() * PHOTON_ROW,
                entries: entries.div_ceil(LIST_ROW).max(1) * LIST_ROW,
                jobs,
            },
        )?;
        self.count = n;
        if n == 0 {
            return Ok(());
        }
        // Whole rows: the last one padded with zero-power photons beyond `count` (never read).
        let mut texels = bytemuck::cast_slice::<Photon, u8>(photons).to_vec();
        texels.resize(
            (rows * PHOTON_ROW) as usize * std::mem::size_of::<Photon>(),
            0,
        );
        gpu::alloc::note_upload("tiled photons", texels.len() as u64);
        ctx.queue.write_texture(
            self.photons.as_image_copy(),
            &texels,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * PHOTON_ROW * 16),
                rows_per_image: Some(rows),
            },
            wgpu::Extent3d {
                width: 4 * PHOTON_ROW,
                height: rows,
                depth_or_array_layers: 1,
            },
        );
        Ok(())
    }

    /// List entries and walk jobs (per job list) the photons will need, estimated on the
    /// CPU from the tiles and the level-1 nodes under each photon's projected kernel (before
    /// the box and cone tests, so usually an overestimate): lists sized from it are rarely
    /// redone ([`Binned::overflowed`]), which matters for one-shot renders, whose first
    /// frame is their only one.
    fn estimate_entries(&self, photons: &[Photon], camera: &Camera) -> (u64, u64) {
        let all = (self.tiles[0] * self.tiles[1]) as u64;
        let all_l1 = (self.l1[0] * self.l1[1]) as u64;
        let tile = TILE as f32;
        let per_photon = |p: &Photon| {
            let r = projected_radius(
                camera,
                self.target.subsample,
                p.position(),
                p.footprint_radius,
            );
            if !r.is_finite() {
                return (all, all_l1);
            }
            // The shader's rectangle spans 2r + 2 texels; its tiles per axis ≤ that / TILE + 2,
            // its level-1 nodes per axis ≤ that / (TILE·FANOUT) + 2 (a job per photon and
            // level-2 or level-1 node it descends into: the level-1 count bounds both lists).
            let span = (2.0 * r + 2.0) / tile;
            let side = (span + 2.0).min(1e6) as u64;
            let side1 = (span / FANOUT as f32 + 2.0).min(1e6) as u64;
            ((side * side).min(all), (side1 * side1).min(all_l1))
        };
        let (tiles, jobs) = photons
            .iter()
            .map(per_photon)
            .fold((0, 0), |(a, b), (t, j)| (a + t, b + j));
        let entries = match self.mode {
            Mode::Tiled => tiles,
            Mode::Cluster | Mode::Directional => tiles * HIERARCHY_ENTRIES_PER_TILE,
        };
        let lists = (entries as f64 * estimate_scale(LIST_ESTIMATE_ENV)) as u64;
        let jobs = (jobs as f64 * estimate_scale(JOB_ESTIMATE_ENV)) as u64;
        (lists, jobs)
    }

    /// Records the binning and the shading of the uploaded photons (the upsampling:
    /// [`super::target::IndirectTarget::record_upsample`]).
    pub fn record(&self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder, timer: &mut Timer) {
        let passes = BinnedPasses::get(ctx);
        let [tx, ty] = self.tiles;
        encoder.clear_buffer(&self.counts, 0, None);
        let max = ctx.device.limits().max_compute_workgroups_per_dimension;
        let grid = |n: u32| {
            let groups = n.div_ceil(PHOTON_GROUP);
            (groups.min(max), groups.div_ceil(max).max(1), groups > 0)
        };
        let (gx, gy, any) = grid(self.count);
        match self.mode {
            Mode::Tiled => {
                let p = passes.tiled(&ctx.device);
                let mut pass = self.compute_pass(encoder, timer, "tile bounds", "tiled binning");
                pass.set_pipeline(&p.tile_bounds);
                pass.dispatch_workgroups(tx, ty, 1);
                drop(pass);
                self.record_node_copy(encoder);
                let mut pass = self.compute_pass(encoder, timer, "tiled binning", "tiled binning");
                if any {
                    pass.set_pipeline(&p.bin_count);
                    pass.dispatch_workgroups(gx, gy, 1);
                }
                pass.set_pipeline(&p.scan);
                pass.dispatch_workgroups(1, 1, 1);
                if any {
                    pass.set_pipeline(&p.bin_fill);
                    pass.dispatch_workgroups(gx, gy, 1);
                }
            }
            Mode::Cluster | Mode::Directional => {
                let p = passes.cluster(&ctx.device);
                let mut pass =
                    self.compute_pass(encoder, timer, "cluster hierarchy", "cluster hierarchy");
                pass.set_pipeline(&p.leaves);
                pass.dispatch_workgroups(tx, ty, 1);
                pass.set_pipeline(&p.parents1);
                pass.dispatch_workgroups((self.l1[0] * self.l1[1]).div_ceil(64), 1, 1);
                pass.set_pipeline(&p.parents2);
                pass.dispatch_workgroups((self.l2[0] * self.l2[1]).div_ceil(64), 1, 1);
                drop(pass);
                self.record_node_copy(encoder);
                // The walk in sub-passes over job lists, counting then filling; the job
                // passes' sizes come from the GPU (indirect dispatch, arguments copied out
                // of `counts` between passes).
                if any {
                    for (level, count, args) in
                        [(0, &p.top_count, &p.jobs0), (1, &p.mid_count, &p.jobs1)]
                    {
                        let mut pass =
                            self.compute_pass(encoder, timer, "cluster walk", "cluster binning");
                        pass.set_pipeline(count);
                        if level == 0 {
                            pass.dispatch_workgroups(gx, gy, 1);
                        } else {
                            pass.dispatch_workgroups_indirect(&self.job_args, 0);
                        }
                        pass.set_pipeline(args);
                        pass.dispatch_workgroups(1, 1, 1);
                        drop(pass);
                        let from = (self.slots as u64 + 4 + 3 * level) * 4;
                        encoder.copy_buffer_to_buffer(
                            &self.counts,
                            from,
                            &self.job_args,
                            12 * level,
                            12,
                        );
                    }
                }
                let mut pass =
                    self.compute_pass(encoder, timer, "cluster binning", "cluster binning");
                if any {
                    pass.set_pipeline(&p.low_count);
                    pass.dispatch_workgroups_indirect(&self.job_args, 12);
                }
                pass.set_pipeline(&p.scan);
                pass.dispatch_workgroups(1, 1, 1);
                if any {
                    pass.set_pipeline(&p.top_fill);
                    pass.dispatch_workgroups(gx, gy, 1);
                    pass.set_pipeline(&p.mid_fill);
                    pass.dispatch_workgroups_indirect(&self.job_args, 0);
                    pass.set_pipeline(&p.low_fill);
                    pass.dispatch_workgroups_indirect(&self.job_args, 12);
                }
            }
        }
        let rows = self.capacity.entries / LIST_ROW;
        encoder.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: &self.list,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(LIST_ROW * 4),
                    rows_per_image: Some(rows),
                },
            },
            self.list_texels.as_image_copy(),
            wgpu::Extent3d {
                width: LIST_ROW,
                height: rows,
                depth_or_array_layers: 1,
            },
        );
        match self.mode {
            Mode::Tiled => {
                let p = passes.tiled(&ctx.device);
                let mut pass = self.compute_pass(encoder, timer, "tiled shading", "tiled shading");
                pass.set_pipeline(&p.shade);
                pass.dispatch_workgroups(tx, ty, 1);
            }
            Mode::Cluster => {
                let p = passes.cluster(&ctx.device);
                let mut pass =
                    self.compute_pass(encoder, timer, "cluster shading", "cluster shading");
                let (nx, ny, _) = grid(self.nodes);
                pass.set_pipeline(&p.accumulate);
                pass.dispatch_workgroups(nx, ny, 1);
                pass.set_pipeline(&p.shade);
                pass.dispatch_workgroups(tx, ty, 1);
            }
            Mode::Directional => {
                let p = passes.cluster(&ctx.device);
                let mut pass =
                    self.compute_pass(encoder, timer, "directional shading", "directional shading");
                let (nx, ny, _) = grid(self.nodes);
                pass.set_pipeline(&p.directional_accumulate);
                pass.dispatch_workgroups(nx, ny, 1);
                pass.set_pipeline(&p.directional_shade);
                pass.dispatch_workgroups(tx, ty, 1);
            }
        }
        encoder.copy_buffer_to_buffer(&self.counts, self.slots as u64 * 4, &self.total, 0, 4);
        if self.mode != Mode::Tiled {
            // Where the leaves' test lists start: the entries of the accept lists; the two
            // job counts.
            encoder.copy_buffer_to_buffer(&self.offsets, self.nodes as u64 * 4, &self.total, 4, 4);
            encoder.copy_buffer_to_buffer(
                &self.counts,
                (self.slots as u64 + 1) * 4,
                &self.total,
                8,
                8,
            );
        }
    }

    /// A compute pass with the estimator's bind group set, timed under stage `stage`.
    fn compute_pass<'e>(
        &'e self,
        encoder: &'e mut wgpu::CommandEncoder,
        timer: &'e mut Timer,
        label: &str,
        stage: &'static str,
    ) -> wgpu::ComputePass<'e> {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: timer.compute_pass(stage),
        });
        pass.set_bind_group(0, &self.group, &[]);
        pass
    }

    /// Copies the built nodes into the node texture the later passes read.
    fn record_node_copy(&self, encoder: &mut wgpu::CommandEncoder) {
        let rows = self.node_texels.height();
        encoder.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: &self.node_data,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(3 * NODE_ROW * 16),
                    rows_per_image: Some(rows),
                },
            },
            self.node_texels.as_image_copy(),
            wgpu::Extent3d {
                width: 3 * NODE_ROW,
                height: rows,
                depth_or_array_layers: 1,
            },
        );
    }

    /// After the frame's submission: whether the lists overflowed (the estimate missed
    /// photons). If so the lists have grown to hold them and the caller records again.
    pub fn overflowed(&mut self, ctx: &GpuContext, gbuf: &GBuffer) -> Result<bool> {
        let bytes = ctx.read_buffer(&self.total)?;
        let word =
            |i: usize| u32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
        let total = word(0);
        let (accepted, jobs) = match self.mode {
            Mode::Tiled => (0, 0),
            Mode::Cluster | Mode::Directional => (word(4), word(8).max(word(12))),
        };
        self.entries = (total as u64, accepted as u64);
        if total <= self.capacity.entries && jobs <= self.capacity.jobs {
            return Ok(false);
        }
        // Room for a little growth, so that a slowly changing view does not redo every frame.
        let room = |n: u32| (n as u64 + n as u64 / 4).min(u32::MAX as u64) as u32;
        self.grow(
            ctx,
            gbuf,
            Capacity {
                photons: self.capacity.photons,
                entries: room(total).div_ceil(LIST_ROW) * LIST_ROW,
                jobs: room(jobs),
            },
        )?;
        Ok(true)
    }

    /// Bytes of GPU memory the estimator holds beyond its targets, by part (for the stats).
    pub fn memory(&self) -> Vec<(&'static str, u64)> {
        let slots = self.slots as u64;
        let mut parts = vec![
            (
                "node bounds and cones (buffer + texture)",
                2 * self.node_data.size(),
            ),
            ("list counts, offsets, cursors", slots * 12 + 4),
            ("photon texture", self.capacity.photons as u64 * 64),
            (
                "photon lists (buffer + texture)",
                self.capacity.entries as u64 * 8,
            ),
        ];
        if self.mode != Mode::Tiled {
            parts.push(("walk job lists", self.jobs.size()));
            parts.push(("node quadratics or octant fluxes", self.coeffs.size()));
            parts.push(("sample leaves", self.cluster_of.size()));
        }
        parts
    }
}

impl crate::gpu::Pipelines for BinnedPasses {
    fn create(ctx: &crate::gpu::GpuContext) -> Self {
        BinnedPasses::new(&ctx.device)
    }
}
