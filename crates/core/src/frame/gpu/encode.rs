//! The radiance encoded on the GPU before its readback ([`crate::frame::readout`]): the
//! tone-mapped 8-bit sRGB display image (4 bytes a pixel read back instead of 16) and the
//! half-float radiance (8 bytes). One full-screen pass each over the composite's radiance
//! target, into a target of its own; each pipeline is compiled when a frame first asks for
//! its encoding, each target made at the first frame of its size that does.

use crate::frame::readout::Display;
use crate::gpu::layout::{buffer, buffer_init, texture, texture_entry, uniform_entry_sized};
use crate::gpu::pipeline::draw_fullscreen;
use crate::gpu::timer::Timer;
use crate::gpu::{self, shaders, GpuContext, Pipelines};

const ENCODE: &str = include_str!("shaders/encode.wgsl");

/// Bytes of the pass's uniform (`Encode` in the shader).
const UNIFORM_SIZE: u64 = 16;

/// The texture format of an encoding's target (read back as it is).
pub(crate) const DISPLAY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
pub(crate) const HALF_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The pass's bind-group layout: the radiance texture and the uniform.
fn layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("encode bind group layout"),
        entries: &[
            texture_entry(0, wgpu::ShaderStages::FRAGMENT),
            uniform_entry_sized(1, wgpu::ShaderStages::FRAGMENT, false, UNIFORM_SIZE),
        ],
    })
}

/// The pipeline of one encoding: fragment entry `entry` into `format`.
fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    entry: &str,
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("encode pipeline layout"),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    let module = shaders::module(device, "encode shader", &[shaders::FULLSCREEN, ENCODE]);
    gpu::create_fullscreen_pipeline(
        device,
        entry,
        &pipeline_layout,
        &module,
        entry,
        format.into(),
    )
}

/// An encoding of the radiance: its fragment entry point and target format.
pub(crate) trait Encoding: Send + Sync + 'static {
    const ENTRY: &'static str;
    const FORMAT: wgpu::TextureFormat;
    /// Its stage name (GPU timestamps).
    const STAGE: &'static str;
}

/// The tone-mapped 8-bit sRGB display image.
pub(crate) struct DisplayEncoding;

impl Encoding for DisplayEncoding {
    const ENTRY: &'static str = "fs_display";
    const FORMAT: wgpu::TextureFormat = DISPLAY_FORMAT;
    const STAGE: &'static str = "display encode";
}

/// The radiance in half floats.
pub(crate) struct HalfEncoding;

impl Encoding for HalfEncoding {
    const ENTRY: &'static str = "fs_half";
    const FORMAT: wgpu::TextureFormat = HALF_FORMAT;
    const STAGE: &'static str = "half encode";
}

/// The pipeline of encoding `E`, compiled when a frame first asks for it.
pub(crate) struct EncodePass<E: Encoding> {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
    encoding: std::marker::PhantomData<E>,
}

impl<E: Encoding> Pipelines for EncodePass<E> {
    fn create(ctx: &GpuContext) -> Self {
        let layout = layout(&ctx.device);
        let pipeline = pipeline(&ctx.device, &layout, E::ENTRY, E::FORMAT);
        EncodePass {
            layout,
            pipeline,
            encoding: std::marker::PhantomData,
        }
    }
}

/// One encoding's target at the frame's size, and the bind group that reads the radiance.
pub(crate) struct EncodeTarget {
    pub texture: wgpu::Texture,
    view: wgpu::TextureView,
    group: wgpu::BindGroup,
}

/// The encodings' targets of one image size (made when first asked for) and the uniform.
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

    /// The target of an encoding into `format` over `radiance`, with the group of
    /// `layout`.
    fn target(
        &self,
        ctx: &GpuContext,
        radiance: &wgpu::TextureView,
        format: wgpu::TextureFormat,
        layout: &wgpu::BindGroupLayout,
    ) -> EncodeTarget {
        let (w, h) = (self.width, self.height);
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let tex = gpu::texture_2d(&ctx.device, "encoded radiance", w, h, format, usage);
        let view = tex.create_view(&Default::default());
        let group = gpu::create_bind_group(
            &ctx.device,
            &wgpu::BindGroupDescriptor {
                label: Some("encode bind group"),
                layout,
                entries: &[texture(0, radiance), buffer(1, &self.uniform)],
            },
        );
        EncodeTarget {
            texture: tex,
            view,
            group,
        }
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

    /// Records encoding `E` of `radiance` into the target in `slot` (made if empty).
    fn record<E: Encoding>(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        radiance: &wgpu::TextureView,
        slot: &mut Option<EncodeTarget>,
        timer: &mut Timer,
    ) {
        let pass = EncodePass::<E>::get(ctx);
        let t = slot.get_or_insert_with(|| self.target(ctx, radiance, E::FORMAT, &pass.layout));
        let ts = timer.pass(E::STAGE);
        draw_fullscreen(encoder, E::STAGE, &t.view, &pass.pipeline, &[&t.group], ts);
    }
}
