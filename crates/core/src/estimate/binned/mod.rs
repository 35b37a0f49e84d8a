//! The compute estimators that bin photons into lists before shading the view samples, over
//! the same photons, kernels, BSDF and normal test as the raster photon volumes
//! ([`super::Volumes`]), so the same image up to the order of the float sums; the work runs
//! on compute units instead of the rasterizer. One module per estimator over the shared
//! binning (`bins`), resources (`resources`) and pipelines (`passes`):
//! - `tiled`: the photons binned to screen tiles, every view sample summing its tile's list;
//! - `cluster`: a hierarchy of view-sample clusters per tile walked by each photon, with
//!   trivial acceptance of whole nodes;
//! - `directional`: the cluster hierarchy with per-node octant flux buckets.
//!
//! The photon lists are sized when photons are uploaded, from a CPU estimate of the tiles
//! under each photon's projected kernel (usually 2–4× what the GPU writes); a frame whose
//! lists overflow anyway is detected at readback ([`Binned::overflowed`]) and splatted again
//! with room for them.

mod bins;
mod cluster;
mod directional;
mod passes;
mod resources;
mod tiled;

use super::target::IndirectTarget;
use crate::error::{Error, Result};
use crate::estimate::volume_shape::projected_radius;
use crate::gpu::timer::Timer;
use crate::gpu::{self, GpuContext, Pipelines};
use crate::photon::radius::VolumeRadius;
use crate::photon::radius::Z_RATIO;
use crate::photon::Photon;
use crate::raster::gbuffer::GBuffer;
use crate::scene::{Camera, Scene};
pub use bins::TILE;
use bins::{Capacity, Grid, LIST_ROW, NODE_ROW, PHOTON_ROW};
use bytemuck::{Pod, Zeroable};
pub use passes::BinnedPasses;
use resources::Resources;

/// Threads of the per-photon passes' workgroups.
const PHOTON_GROUP: u32 = 64;
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

/// Workgroups of a pass over `n` photons or nodes: x (at most the adapter's limit), y, and
/// whether there are any.
#[derive(Clone, Copy, Debug)]
struct Dispatch {
    gx: u32,
    gy: u32,
    any: bool,
}

impl Dispatch {
    fn of(n: u32, max: u32) -> Self {
        let groups = n.div_ceil(PHOTON_GROUP);
        Dispatch {
            gx: groups.min(max),
            gy: groups.div_ceil(max).max(1),
            any: groups > 0,
        }
    }
}

/// A binned estimator (see the module).
pub struct Binned {
    mode: Mode,
    pub(super) target: IndirectTarget,
    grid: Grid,
    res: Resources,
    group: wgpu::BindGroup,
    last_params: Option<TiledParamsRaw>,
    capacity: Capacity,
    /// Photons uploaded for this frame.
    count: u32,
    /// The materials' exact models (`raster::exact_models`), bound beside the G-buffer.
    models: wgpu::Buffer,
    /// List entries of the last estimate: all, and those of trivially accepted photons.
    entries: (u64, u64),
}

impl Binned {
    /// Resources for a `width × height` image over the G-buffer `gbuf`.
    pub fn new(
        ctx: &GpuContext,
        (gbuf, models): (&GBuffer, &wgpu::Buffer),
        mode: Mode,
        size: [u32; 2],
        subsample: u32,
    ) -> Self {
        let target = IndirectTarget::new(ctx, gbuf, size[0], size[1], subsample);
        let grid = Grid::new(target.low_size, mode);
        let capacity = Capacity::initial(mode);
        let res = Resources::new(ctx, &target, &grid, mode, capacity);
        let group = res.bind_group(ctx, (gbuf, models), &target);
        Binned {
            mode,
            target,
            grid,
            res,
            group,
            last_params: None,
            capacity,
            count: 0,
            entries: (0, 0),
            models: models.clone(),
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
        let capacity = want.max(self.capacity);
        if capacity == self.capacity {
            return Ok(());
        }
        // The photon texture keeps its contents unless it grows (then the caller uploads).
        self.res.grow(ctx, self.capacity, capacity);
        self.group = self.res.bind_group(ctx, (gbuf, &self.models), &self.target);
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
        let grid = &self.grid;
        let params = TiledParamsRaw {
            view_proj: self.target.view_proj(scene).to_cols_array_2d(),
            eye: scene.camera.position.into(),
            r_max: radius.r_max,
            low_size: self.target.low_size,
            tiles: grid.tiles,
            subsample: self.target.subsample,
            photons: self.count,
            capacity: self.capacity.entries,
            z_ratio: Z_RATIO,
            l1: grid.l1,
            l2: grid.l2,
            level_first: grid.level_first(),
            nodes: grid.nodes,
            slots: grid.slots,
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
            &self.res.params,
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
        self.grow(
            ctx,
            gbuf,
            Capacity::for_photons(self.mode, n, entries, jobs),
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
            self.res.photons.as_image_copy(),
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

    /// [`Self::write_photons`] from `n` photon records already on the GPU (`buffer`, e.g.
    /// GPU-traced photons: `gpu::photon::resident`), copied into the photon texture on the
    /// GPU. With no photons on the CPU to estimate the lists from, they are sized from the
    /// last frame's lists (scaled by the photon count) and, on a first frame, grown after an
    /// overflow ([`Self::overflowed`]).
    pub fn copy_photons(
        &mut self,
        ctx: &GpuContext,
        gbuf: &GBuffer,
        buffer: &wgpu::Buffer,
        n: u32,
    ) -> Result<()> {
        let scale = |v: u64| match self.count {
            0 => 0,
            c => (v as f64 * n as f64 / c as f64) as u64,
        };
        let (entries, jobs) = (scale(self.entries.0), scale(self.capacity.jobs as u64));
        self.grow(
            ctx,
            gbuf,
            Capacity::for_photons(self.mode, n, entries, jobs),
        )?;
        self.count = n;
        if n == 0 {
            return Ok(());
        }
        let record = std::mem::size_of::<Photon>() as u64;
        let (rows, rest) = (n / PHOTON_ROW, n % PHOTON_ROW);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let mut copy = |first_row: u32, width: u32, height: u32| {
            let source = wgpu::TexelCopyBufferInfo {
                buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: first_row as u64 * PHOTON_ROW as u64 * record,
                    bytes_per_row: Some(4 * PHOTON_ROW * 16),
                    rows_per_image: Some(height),
                },
            };
            let mut target = self.res.photons.as_image_copy();
            target.origin.y = first_row;
            let size = wgpu::Extent3d {
                width: 4 * width,
                height,
                depth_or_array_layers: 1,
            };
            encoder.copy_buffer_to_texture(source, target, size);
        };
        if rows > 0 {
            copy(0, PHOTON_ROW, rows);
        }
        if rest > 0 {
            copy(rows, rest, 1);
        }
        ctx.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// List entries and walk jobs (per job list) the photons will need, estimated on the
    /// CPU from the tiles and the level-1 nodes under each photon's projected kernel
    /// ([`Grid::photon_bins`]): lists sized from it are rarely redone
    /// ([`Binned::overflowed`]), which matters for one-shot renders, whose first frame is
    /// their only one.
    fn estimate_entries(&self, photons: &[Photon], camera: &Camera) -> (u64, u64) {
        let subsample = self.target.subsample;
        let (tiles, jobs) = photons
            .iter()
            .map(|p| {
                let r = projected_radius(camera, subsample, p.position(), p.footprint_radius);
                self.grid.photon_bins(r)
            })
            .fold((0, 0), |(a, b), (t, j)| (a + t, b + j));
        let entries = Grid::list_entries(self.mode, tiles);
        let lists = (entries as f64 * estimate_scale(LIST_ESTIMATE_ENV)) as u64;
        let jobs = (jobs as f64 * estimate_scale(JOB_ESTIMATE_ENV)) as u64;
        (lists, jobs)
    }

    /// Records the binning and the shading of the uploaded photons (the upsampling:
    /// [`super::target::IndirectTarget::record_upsample`]).
    pub fn record(&self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder, timer: &mut Timer) {
        let passes = BinnedPasses::get(ctx);
        let device = &ctx.device;
        encoder.clear_buffer(&self.res.counts, 0, None);
        let max = device.limits().max_compute_workgroups_per_dimension;
        let photons = Dispatch::of(self.count, max);
        match self.mode {
            Mode::Tiled => tiled::record_binning(self, &passes, device, encoder, timer, photons),
            Mode::Cluster | Mode::Directional => {
                cluster::record_binning(self, &passes, device, encoder, timer, photons)
            }
        }
        self.record_list_copy(encoder);
        let nodes = Dispatch::of(self.grid.nodes, max);
        match self.mode {
            Mode::Tiled => tiled::record_shading(self, &passes, device, encoder, timer),
            Mode::Cluster => {
                let p = cluster::shading(passes.cluster_pipelines(device));
                let stage = "cluster shading";
                cluster::record_node_shading(self, p, encoder, timer, stage, nodes)
            }
            Mode::Directional => {
                let p = directional::shading(passes.cluster_pipelines(device));
                let stage = "directional shading";
                cluster::record_node_shading(self, p, encoder, timer, stage, nodes)
            }
        }
        self.record_totals_copy(encoder);
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
        let rows = self.res.node_texels.height();
        encoder.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: &self.res.node_data,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(3 * NODE_ROW * 16),
                    rows_per_image: Some(rows),
                },
            },
            self.res.node_texels.as_image_copy(),
            wgpu::Extent3d {
                width: 3 * NODE_ROW,
                height: rows,
                depth_or_array_layers: 1,
            },
        );
    }

    /// Copies the filled lists into the list texture the shading reads.
    fn record_list_copy(&self, encoder: &mut wgpu::CommandEncoder) {
        let rows = self.capacity.entries / LIST_ROW;
        encoder.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: &self.res.list,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(LIST_ROW * 4),
                    rows_per_image: Some(rows),
                },
            },
            self.res.list_texels.as_image_copy(),
            wgpu::Extent3d {
                width: LIST_ROW,
                height: rows,
                depth_or_array_layers: 1,
            },
        );
    }

    /// Copies what [`Binned::overflowed`] reads into the read-back buffer: the lists' total
    /// entries and, in the hierarchy modes, where the leaves' test lists start (the entries
    /// of the accept lists) and the two job counts.
    fn record_totals_copy(&self, encoder: &mut wgpu::CommandEncoder) {
        let (r, slots) = (&self.res, self.grid.slots as u64);
        encoder.copy_buffer_to_buffer(&r.counts, slots * 4, &r.total, 0, 4);
        if self.mode != Mode::Tiled {
            let nodes = self.grid.nodes as u64;
            encoder.copy_buffer_to_buffer(&r.offsets, nodes * 4, &r.total, 4, 4);
            encoder.copy_buffer_to_buffer(&r.counts, (slots + 1) * 4, &r.total, 8, 8);
        }
    }

    /// After the frame's submission: whether the lists overflowed (the estimate missed
    /// photons). If so the lists have grown to hold them and the caller records again.
    pub fn overflowed(&mut self, ctx: &GpuContext, gbuf: &GBuffer) -> Result<bool> {
        let bytes = ctx.read_buffer(&self.res.total)?;
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
        self.grow(ctx, gbuf, self.capacity.after_overflow(total, jobs))?;
        Ok(true)
    }

    /// Bytes of GPU memory the estimator holds beyond its targets, by part (for the stats).
    pub fn memory(&self) -> Vec<(&'static str, u64)> {
        let slots = self.grid.slots as u64;
        let mut parts = vec![
            (
                "node bounds and cones (buffer + texture)",
                2 * self.res.node_data.size(),
            ),
            ("list counts, offsets, cursors", slots * 12 + 4),
            ("photon texture", self.capacity.photons as u64 * 64),
            (
                "photon lists (buffer + texture)",
                self.capacity.entries as u64 * 8,
            ),
        ];
        if self.mode != Mode::Tiled {
            parts.push(("walk job lists", self.res.jobs.size()));
            parts.push(("node quadratics or octant fluxes", self.res.coeffs.size()));
            parts.push(("sample leaves", self.res.cluster_of.size()));
        }
        parts
    }
}
