//! The radiance encoded on the GPU before its readback ([`crate::frame::readout`]): the
//! tone-mapped 8-bit sRGB display image (4 bytes a pixel read back instead of 16) and the
//! half-float radiance (8 bytes). One compute pass each over the composite's radiance
//! target, into a storage buffer of its own (rows unpadded, copied buffer to buffer: no
//! texture format conversion in the copy); each pipeline is compiled when a frame first
//! asks for its encoding, each buffer made at the first frame of its size that does.

use crate::frame::readout::Display;
use crate::gpu::layout::uniform_entry_sized;
use crate::gpu::layout::{buffer, buffer_init, storage_rw_entry, texture, texture_entry};
use crate::gpu::timer::Timer;
use crate::gpu::{self, shaders, GpuContext, Pipelines};

const ENCODE: &str = include_str!("shaders/encode.wgsl");

/// Bytes of the pass's uniform (`Encode` in the shader).
const UNIFORM_SIZE: u64 = 16;

/// Threads of a workgroup a side (`@workgroup_size(8, 8)`).
const GROUP: u32 = 8;

/// The pass's bind-group layout: the radiance texture, the uniform and the output.
fn layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let stage = wgpu::ShaderStages::COMPUTE;
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("encode bind group layout"),
        entries: &[
            texture_entry(0, stage),
            uniform_entry_sized(1, stage, false, UNIFORM_SIZE),
            storage_rw_entry(2, stage),
        ],
    })
}

/// The pipeline of one encoding: compute entry `entry`.
fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    entry: &str,
) -> wgpu::ComputePipeline {
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("encode pipeline layout"),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    let module = shaders::module(device, "encode shader", &[ENCODE]);
    gpu::create_compute_pipeline(
        device,
        &wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        },
    )
}

/// An encoding of the radiance: its entry point and bytes a pixel.
pub(crate) trait Encoding: Send + Sync + 'static {
    const ENTRY: &'static str;
    const BYTES: u64;
    /// Its stage name (GPU timestamps).
    const STAGE: &'static str;
}

/// The tone-mapped 8-bit sRGB display image (RGBA8 words).
pub(crate) struct DisplayEncoding;

impl Encoding for DisplayEncoding {
    const ENTRY: &'static str = "cs_display";
    const BYTES: u64 = 4;
    const STAGE: &'static str = "display encode";
}

/// The radiance in half floats (RGBA).
pub(crate) struct HalfEncoding;

impl Encoding for HalfEncoding {
    const ENTRY: &'static str = "cs_half";
    const BYTES: u64 = 8;
    const STAGE: &'static str = "half encode";
}

/// The pipeline of encoding `E`, compiled when a frame first asks for it.
pub(crate) struct EncodePass<E: Encoding> {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    encoding: std::marker::PhantomData<E>,
}

impl<E: Encoding> Pipelines for EncodePass<E> {
    fn create(ctx: &GpuContext) -> Self {
        let layout = layout(&ctx.device);
        let pipeline = pipeline(&ctx.device, &layout, E::ENTRY);
        EncodePass {
            layout,
            pipeline,
            encoding: std::marker::PhantomData,
        }
    }
}

/// One encoding's output at the frame's size, and the bind group that writes it.
pub(crate) struct EncodeTarget {
    pub buffer: wgpu::Buffer,
    group: wgpu::BindGroup,
}

/// The encodings' outputs of one image size (made when first asked for) and the uniform.
pub(crate) struct Encodings {
    width: u32,
    height: u32,
    uniform: wgpu::Buffer,
    pub display: Option<EncodeTarget>,
    pub half: Option<EncodeTarget>,
}

impl Encodings {
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let uniform = buffer_init(
            ctx,
            "encode uniform",
            &[0u8; UNIFORM_SIZE as usize],
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        Encodings {
            width,
            height,
            uniform,
            display: None,
            half: None,
        }
    }

    /// The output of encoding `E` of `radiance`, with the group of `layout`.
    fn target<E: Encoding>(
        &self,
        ctx: &GpuContext,
        radiance: &wgpu::TextureView,
        layout: &wgpu::BindGroupLayout,
    ) -> EncodeTarget {
        let size = self.width as u64 * self.height as u64 * E::BYTES;
        let out = gpu::create_buffer(
            &ctx.device,
            &wgpu::BufferDescriptor {
                label: Some("encoded radiance"),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            },
        );
        let group = gpu::create_bind_group(
            &ctx.device,
            &wgpu::BindGroupDescriptor {
                label: Some("encode bind group"),
                layout,
                entries: &[
                    texture(0, radiance),
                    buffer(1, &self.uniform),
                    buffer(2, &out),
                ],
            },
        );
        EncodeTarget { buffer: out, group }
    }

    /// Records the display encoding of `radiance` with `d`'s tone map and exposure (the
    /// uniform written now, before the frame's submission).
    pub fn record_display(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        radiance: &wgpu::TextureView,
        d: Display,
        timer: &mut Timer,
    ) {
        let uniform: [u32; 4] = [2f32.powf(d.exposure).to_bits(), d.tonemap.code(), 0, 0];
        let bytes: &[u8] = bytemuck::cast_slice(&uniform);
        gpu::write_buffer(&ctx.queue, "encode uniform", &self.uniform, 0, bytes);
        let mut slot = self.display.take();
        self.record::<DisplayEncoding>(ctx, encoder, radiance, &mut slot, timer);
        self.display = slot;
    }

    /// Records the half-float encoding of `radiance`.
    pub fn record_half(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        radiance: &wgpu::TextureView,
        timer: &mut Timer,
    ) {
        let mut slot = self.half.take();
        self.record::<HalfEncoding>(ctx, encoder, radiance, &mut slot, timer);
        self.half = slot;
    }

    /// Records encoding `E` of `radiance` into the output in `slot` (made if empty).
    fn record<E: Encoding>(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        radiance: &wgpu::TextureView,
        slot: &mut Option<EncodeTarget>,
        timer: &mut Timer,
    ) {
        let p = EncodePass::<E>::get(ctx);
        let t = slot.get_or_insert_with(|| self.target::<E>(ctx, radiance, &p.layout));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(E::STAGE),
            timestamp_writes: timer.compute_pass(E::STAGE),
        });
        pass.set_pipeline(&p.pipeline);
        pass.set_bind_group(0, &t.group, &[]);
        pass.dispatch_workgroups(self.width.div_ceil(GROUP), self.height.div_ceil(GROUP), 1);
    }
}
