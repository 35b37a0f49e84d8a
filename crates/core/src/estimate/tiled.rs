//! Tiled photon splatting in compute (Mara et al. 2013, as Moreau et al. 2016 section 3.2
//! describe it): the photons are binned to screen tiles (counting, prefix sum, list build,
//! each tile bounded by the world-space box of its view samples) and every view sample sums
//! the photons of its tile with the photon volumes' kernel, BSDF and normal test
//! (`gpu/shaders/tiled.wgsl`). Same photons, same image as [`super::Volumes`], up to the
//! order of the float sums; the work runs on compute units instead of the rasterizer.
//!
//! The photon lists are sized from the last frame's total: a frame whose lists overflow is
//! detected at readback ([`Tiled::overflowed`]) and splatted again with room for them.

use super::target::IndirectTarget;
use crate::error::{Error, Result};
use crate::gpu::{self, shaders, GpuContext};
use crate::photon::Photon;
use crate::raster::buffer_init;
use crate::raster::gbuffer::GBuffer;
use crate::raster::ispm::{tex, Z_RATIO};
use crate::raster::timer::Timer;
use crate::raster::volume_shape::VolumeRadius;
use crate::scene::Scene;
use bytemuck::{Pod, Zeroable};

/// Tile side in low-resolution texels (`TILE` of tiled.wgsl).
pub const TILE: u32 = 8;
/// Photons per row of the photon texture (`PHOTON_ROW`), 4 texels each.
const PHOTON_ROW: u32 = 1024;
/// List entries per row of the list texture (`LIST_ROW`).
const LIST_ROW: u32 = 4096;
/// Threads of the per-photon passes' workgroups.
const PHOTON_GROUP: u32 = 64;
/// List entries per photon allocated before the first frame has measured them.
const ENTRIES_PER_PHOTON: u64 = 4;

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
}

/// The compute pipelines of the tiled estimator, compiled once per device.
pub struct TiledPasses {
    layout: wgpu::BindGroupLayout,
    tile_bounds: wgpu::ComputePipeline,
    bin_count: wgpu::ComputePipeline,
    scan: wgpu::ComputePipeline,
    bin_fill: wgpu::ComputePipeline,
    shade: wgpu::ComputePipeline,
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

impl TiledPasses {
    pub fn get(ctx: &GpuContext) -> &TiledPasses {
        ctx.tiled_passes
            .get_or_init(|| TiledPasses::new(&ctx.device))
    }

    fn new(device: &wgpu::Device) -> Self {
        let float = texture(wgpu::TextureSampleType::Float { filterable: false });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tiled bind group layout"),
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
                        format: crate::raster::ispm::TARGET,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                ),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("tiled pipeline layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = shaders::module(
            device,
            "tiled shader",
            &[
                shaders::COMMON,
                shaders::BSDF,
                shaders::PHOTON_VOLUME,
                shaders::TILED,
            ],
        );
        let pipeline = |entry_point: &str| {
            gpu::create_compute_pipeline(
                device,
                &wgpu::ComputePipelineDescriptor {
                    label: Some(entry_point),
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some(entry_point),
                    compilation_options: Default::default(),
                    cache: None,
                },
            )
        };
        TiledPasses {
            tile_bounds: pipeline("tile_bounds"),
            bin_count: pipeline("bin_count"),
            scan: pipeline("scan"),
            bin_fill: pipeline("bin_fill"),
            shade: pipeline("shade"),
            layout,
        }
    }
}

/// Sizes of the growable resources.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Capacity {
    /// Photons the photon texture holds (a multiple of `PHOTON_ROW`).
    photons: u32,
    /// List entries (a multiple of `LIST_ROW`).
    entries: u32,
}

pub struct Tiled {
    pub(super) target: IndirectTarget,
    tiles: [u32; 2],
    params: wgpu::Buffer,
    last_params: Option<TiledParamsRaw>,
    photons: wgpu::Texture,
    bounds: wgpu::Buffer,
    counts: wgpu::Buffer,
    offsets: wgpu::Buffer,
    cursor: wgpu::Buffer,
    list: wgpu::Buffer,
    list_texels: wgpu::Texture,
    total: wgpu::Buffer,
    group: wgpu::BindGroup,
    capacity: Capacity,
    /// Photons uploaded for this frame.
    count: u32,
}

fn texture_2d(
    ctx: &GpuContext,
    label: &str,
    size: [u32; 2],
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    gpu::create_texture(
        &ctx.device,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: size[0],
                height: size[1],
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        },
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

impl Tiled {
    /// Resources for a `width × height` image over the G-buffer `gbuf`.
    pub fn new(ctx: &GpuContext, gbuf: &GBuffer, width: u32, height: u32, subsample: u32) -> Self {
        let target = IndirectTarget::new(ctx, gbuf, width, height, subsample);
        let tiles = [
            target.low_size[0].div_ceil(TILE),
            target.low_size[1].div_ceil(TILE),
        ];
        let n = (tiles[0] * tiles[1]) as u64;
        let rw = wgpu::BufferUsages::STORAGE;
        let capacity = Capacity {
            photons: PHOTON_ROW,
            entries: LIST_ROW,
        };
        let photons = Self::photon_texture(ctx, capacity.photons);
        let (list, list_texels) = Self::lists(ctx, capacity.entries);
        let params = buffer_init(
            ctx,
            "tiled params",
            bytemuck::bytes_of(&TiledParamsRaw::zeroed()),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let bounds = buffer(ctx, "tile bounds", n * 32, rw);
        let counts = buffer(
            ctx,
            "tile counts",
            (n + 1) * 4,
            rw | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        let offsets = buffer(ctx, "tile offsets", n * 4, rw);
        let cursor = buffer(ctx, "tile cursors", n * 4, rw);
        let total = buffer(
            ctx,
            "tile list total",
            4,
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        let group = Self::bind_group(
            ctx,
            gbuf,
            &target,
            [&params, &bounds, &counts, &offsets, &cursor, &list],
            &photons,
            &list_texels,
        );
        Tiled {
            target,
            tiles,
            params,
            last_params: None,
            photons,
            bounds,
            counts,
            offsets,
            cursor,
            list,
            list_texels,
            total,
            group,
            capacity,
            count: 0,
        }
    }

    /// The photon texture for `photons` photons.
    fn photon_texture(ctx: &GpuContext, photons: u32) -> wgpu::Texture {
        texture_2d(
            ctx,
            "tiled photons",
            [4 * PHOTON_ROW, photons / PHOTON_ROW],
            crate::raster::ispm::TARGET,
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

    fn bind_group(
        ctx: &GpuContext,
        gbuf: &GBuffer,
        target: &IndirectTarget,
        buffers: [&wgpu::Buffer; 6],
        photons: &wgpu::Texture,
        list_texels: &wgpu::Texture,
    ) -> wgpu::BindGroup {
        let inputs = gbuf.lighting_inputs();
        let photons = photons.create_view(&Default::default());
        let list_texels = list_texels.create_view(&Default::default());
        let [params, bounds, counts, offsets, cursor, list] = buffers;
        fn buf(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            }
        }
        gpu::create_bind_group(
            &ctx.device,
            &wgpu::BindGroupDescriptor {
                label: Some("tiled bind group"),
                layout: &TiledPasses::get(ctx).layout,
                entries: &[
                    buf(0, params),
                    tex(1, &inputs[0]),
                    tex(2, &inputs[1]),
                    tex(3, &inputs[2]),
                    tex(4, &inputs[3]),
                    tex(5, &photons),
                    buf(6, bounds),
                    buf(7, counts),
                    buf(8, offsets),
                    buf(9, cursor),
                    buf(10, list),
                    tex(11, &list_texels),
                    tex(12, &target.low_view),
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
                "the tiled estimator's photon lists need {} entries; the adapter holds at \
                 most {max_entries} (use a smaller kernel_scale, fewer photons, or \
                 estimator \"volumes\")",
                want.entries
            )));
        }
        if (want.photons / PHOTON_ROW) as u64 > max_rows {
            return Err(Error::Gpu(format!(
                "the tiled estimator holds at most {} photons on this adapter",
                max_rows * PHOTON_ROW as u64
            )));
        }
        let capacity = Capacity {
            photons: want.photons.max(self.capacity.photons),
            entries: want.entries.max(self.capacity.entries),
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
        self.group = Self::bind_group(
            ctx,
            gbuf,
            &self.target,
            [
                &self.params,
                &self.bounds,
                &self.counts,
                &self.offsets,
                &self.cursor,
                &self.list,
            ],
            &self.photons,
            &self.list_texels,
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
    ) -> Result<()> {
        let n = photons.len() as u32;
        let rows = n.div_ceil(PHOTON_ROW).max(1);
        let entries = (n as u64 * ENTRIES_PER_PHOTON).min(u32::MAX as u64) as u32;
        self.grow(
            ctx,
            gbuf,
            Capacity {
                photons: (2 * rows).next_power_of_two() * PHOTON_ROW,
                entries: entries.div_ceil(LIST_ROW).max(1) * LIST_ROW,
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

    /// Records the binning, the shading and the upsampling of the uploaded photons.
    pub fn record(&self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder, timer: &mut Timer) {
        let passes = TiledPasses::get(ctx);
        let [tx, ty] = self.tiles;
        encoder.clear_buffer(&self.counts, 0, None);
        let groups = self.count.div_ceil(PHOTON_GROUP);
        let max = ctx.device.limits().max_compute_workgroups_per_dimension;
        let (gx, gy) = (groups.min(max), groups.div_ceil(max).max(1));
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("tiled binning"),
                timestamp_writes: timer.compute_pass("tiled binning"),
            });
            pass.set_bind_group(0, &self.group, &[]);
            pass.set_pipeline(&passes.tile_bounds);
            pass.dispatch_workgroups(tx, ty, 1);
            if groups > 0 {
                pass.set_pipeline(&passes.bin_count);
                pass.dispatch_workgroups(gx, gy, 1);
            }
            pass.set_pipeline(&passes.scan);
            pass.dispatch_workgroups(1, 1, 1);
            if groups > 0 {
                pass.set_pipeline(&passes.bin_fill);
                pass.dispatch_workgroups(gx, gy, 1);
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
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("tiled shading"),
                timestamp_writes: timer.compute_pass("tiled shading"),
            });
            pass.set_bind_group(0, &self.group, &[]);
            pass.set_pipeline(&passes.shade);
            pass.dispatch_workgroups(tx, ty, 1);
        }
        let n = (tx * ty) as u64;
        encoder.copy_buffer_to_buffer(&self.counts, n * 4, &self.total, 0, 4);
        self.target.record_upsample(ctx, encoder, timer);
    }

    /// After the frame's submission: whether the lists overflowed (the estimate missed
    /// photons). If so the lists have grown to hold them and the caller records again.
    pub fn overflowed(&mut self, ctx: &GpuContext, gbuf: &GBuffer) -> Result<bool> {
        let bytes = ctx.read_buffer(&self.total)?;
        let total = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
        if total <= self.capacity.entries {
            return Ok(false);
        }
        // Room for a little growth, so that a slowly changing view does not redo every frame.
        let entries = (total as u64 + total as u64 / 4).min(u32::MAX as u64) as u32;
        self.grow(
            ctx,
            gbuf,
            Capacity {
                photons: self.capacity.photons,
                entries: entries.div_ceil(LIST_ROW) * LIST_ROW,
            },
        )?;
        Ok(true)
    }

    /// Bytes of GPU memory the estimator holds beyond its targets, by part (for the stats).
    pub fn memory(&self) -> Vec<(&'static str, u64)> {
        let n = (self.tiles[0] * self.tiles[1]) as u64;
        vec![
            ("tile bounds", n * 32),
            ("tile counts, offsets, cursors", n * 12 + 4),
            ("photon texture", self.capacity.photons as u64 * 64),
            (
                "photon lists (buffer + texture)",
                self.capacity.entries as u64 * 8,
            ),
        ]
    }
}
