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

/// The encodings' pipeline (one entry point for both: one compile), compiled when a
/// frame first asks for an encoding.
pub(crate) struct EncodePass {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl Pipelines for EncodePass {
    fn create(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = layout(device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("encode pipeline layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = shaders::module(device, "encode shader", &[ENCODE]);
        let pipeline = gpu::compute_pipeline_of(device, &pipeline_layout, &module, "cs_encode");
        EncodePass { layout, pipeline }
    }
}

/// An encoding of the radiance: its bytes a pixel and its stage.
#[derive(Clone, Copy)]
enum Encoding {
    Display,
    Half,
}

impl Encoding {
    fn bytes(self) -> u64 {
        match self {
            Encoding::Display => 4,
            Encoding::Half => 8,
        }
    }

    /// Its stage name (GPU timestamps).
    fn stage(self) -> &'static str {
        match self {
            Encoding::Display => "display encode",
            Encoding::Half => "half encode",
        }
    }
}

/// One encoding's output at the frame's size, its uniform and the bind group of both.
pub(crate) struct EncodeTarget {
    pub buffer: wgpu::Buffer,
    uniform: wgpu::Buffer,
    group: wgpu::BindGroup,
}

/// The encodings' outputs of one image size (made when first asked for).
pub(crate) struct Encodings {
    width: u32,
    height: u32,
    pub display: Option<EncodeTarget>,
    pub half: Option<EncodeTarget>,
}

impl Encodings {
    pub fn new(width: u32, height: u32) -> Self {
        Encodings {
            width,
            height,
            display: None,
            half: None,
        }
    }

    /// The output of encoding `e` of `radiance`, with the group of `layout`.
    fn target(
        &self,
        ctx: &GpuContext,
        radiance: &wgpu::TextureView,
        e: Encoding,
        layout: &wgpu::BindGroupLayout,
    ) -> EncodeTarget {
        let size = self.width as u64 * self.height as u64 * e.bytes();
        let out = gpu::create_buffer(
            &ctx.device,
            &wgpu::BufferDescriptor {
                label: Some("encoded radiance"),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            },
        );
        let half = matches!(e, Encoding::Half) as u32;
        let uniform = buffer_init(
            ctx,
            "encode uniform",
            bytemuck::cast_slice(&[1f32.to_bits(), 0, half, 0]),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let entries = [texture(0, radiance), buffer(1, &uniform), buffer(2, &out)];
        let desc = wgpu::BindGroupDescriptor {
            label: Some("encode bind group"),
            layout,
            entries: &entries,
        };
        let group = gpu::create_bind_group(&ctx.device, &desc);
        EncodeTarget {
            buffer: out,
            uniform,
            group,
        }
    }

    /// Records the display encoding of `radiance` with `d`'s tone map and exposure (its
    /// uniform written now, before the frame's submission).
    pub fn record_display(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        radiance: &wgpu::TextureView,
        d: Display,
        timer: &mut Timer,
    ) {
        let mut slot = self.display.take();
        let t = self.record(ctx, encoder, radiance, Encoding::Display, &mut slot, timer);
        let uniform: [u32; 4] = [2f32.powf(d.exposure).to_bits(), d.tonemap.code(), 0, 0];
        let bytes: &[u8] = bytemuck::cast_slice(&uniform);
        gpu::write_buffer(&ctx.queue, "encode uniform", &t.uniform, 0, bytes);
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
        self.record(ctx, encoder, radiance, Encoding::Half, &mut slot, timer);
        self.half = slot;
    }

    /// Records encoding `e` of `radiance` into the output in `slot` (made if empty);
    /// returns that output.
    fn record<'s>(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        radiance: &wgpu::TextureView,
        e: Encoding,
        slot: &'s mut Option<EncodeTarget>,
        timer: &mut Timer,
    ) -> &'s EncodeTarget {
        let p = EncodePass::get(ctx);
        let t = slot.get_or_insert_with(|| self.target(ctx, radiance, e, &p.layout));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(e.stage()),
            timestamp_writes: timer.compute_pass(e.stage()),
        });
        pass.set_pipeline(&p.pipeline);
        pass.set_bind_group(0, &t.group, &[]);
        let (w, h) = (self.width, self.height);
        pass.dispatch_workgroups(w.div_ceil(GROUP), h.div_ceil(GROUP), 1);
        t
    }
}
