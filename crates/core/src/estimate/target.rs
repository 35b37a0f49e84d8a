//! The indirect-light target every estimator writes: one texel per G-buffer sample at the
//! centre of a `subsample` × `subsample` block, and its joint bilateral upsampling to full
//! resolution (ISPM section 5.2) when `subsample` > 1, to which the upsampling adds the light
//! of another target estimated at full resolution where one is set
//! ([`IndirectTarget::set_full_resolution`]: the frame's caustic photons).

use super::wgsl;
use crate::gpu::layout::{buffer, buffer_init, texture as tex, texture_entry, uniform_entry};
use crate::gpu::pipeline::{bind_group_layout, draw_fullscreen, pipeline_layout};
use crate::gpu::raw::UpsampleParamsRaw;
use crate::gpu::timer::Timer;
use crate::gpu::{self, shaders, GpuContext, Pipelines};
use crate::raster::camera_view;
use crate::raster::gbuffer::GBuffer;
use crate::scene::Scene;
use glam::{Mat4, Vec2, Vec3};

const FRAGMENT: wgpu::ShaderStages = wgpu::ShaderStages::FRAGMENT;

/// Format of the indirect-light targets.
pub(crate) const TARGET: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// The joint bilateral upsampling pipeline (ISPM section 5.2).
pub struct UpsamplePass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl Pipelines for UpsamplePass {
    fn create(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let upsample_layout = bind_group_layout(
            device,
            "upsample bind group layout",
            &[
                uniform_entry(0),
                texture_entry(1, FRAGMENT),
                texture_entry(2, FRAGMENT),
                texture_entry(3, FRAGMENT),
                texture_entry(4, FRAGMENT),
                texture_entry(5, FRAGMENT),
                texture_entry(6, FRAGMENT),
            ],
        );
        let module = shaders::module(
            device,
            "upsample shader",
            &[
                shaders::COMMON,
                shaders::BSDF,
                shaders::FULLSCREEN,
                wgsl::UPSAMPLE,
            ],
        );
        let upsample = crate::gpu::create_fullscreen_pipeline(
            device,
            "upsample pipeline",
            &pipeline_layout(device, "upsample pipeline layout", &[&upsample_layout]),
            &module,
            "fs_main",
            TARGET.into(),
        );
        UpsamplePass {
            pipeline: upsample,
            layout: upsample_layout,
        }
    }
}

pub struct IndirectTarget {
    pub subsample: u32,
    /// Low-resolution size (texels).
    pub low_size: [u32; 2],
    pub low: wgpu::Texture,
    pub low_view: wgpu::TextureView,
    /// Full-resolution output of the upsampling (`None` when `subsample` is 1).
    full: Option<(wgpu::Texture, wgpu::TextureView)>,
    up_params: wgpu::Buffer,
    last_eye: Option<[f32; 3]>,
    upsample_group: Option<wgpu::BindGroup>,
    /// Where in its pixel the eye G-buffer is sampled: the centre, but in progressive passes
    /// (`frame::progressive`), whose sub-pixel samples move per pass.
    centre: Vec2,
}

/// An `Rgba32Float` texture the estimators render to, write as storage, read and copy.
pub(crate) fn float_target(ctx: &GpuContext, label: &str, w: u32, h: u32) -> wgpu::Texture {
    gpu::texture_2d(
        &ctx.device,
        label,
        w,
        h,
        TARGET,
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST,
    )
}

/// The upsampling's bind group: parameters, the G-buffer, the low-resolution estimate and
/// the full-resolution light it adds.
fn upsample_group(
    ctx: &GpuContext,
    gbuf: &GBuffer,
    params: &wgpu::Buffer,
    low: &wgpu::TextureView,
    full: &wgpu::TextureView,
) -> wgpu::BindGroup {
    let inputs = gbuf.lighting_inputs();
    gpu::create_bind_group(
        &ctx.device,
        &wgpu::BindGroupDescriptor {
            label: Some("upsample bind group"),
            layout: &UpsamplePass::get(ctx).layout,
            entries: &[
                buffer(0, params),
                tex(1, &inputs[0]),
                tex(2, &inputs[1]),
                tex(3, low),
                tex(4, &inputs[2]),
                tex(5, &inputs[3]),
                tex(6, full),
            ],
        },
    )
}

impl IndirectTarget {
    pub fn new(ctx: &GpuContext, gbuf: &GBuffer, width: u32, height: u32, subsample: u32) -> Self {
        let k = subsample.max(1);
        let low_size = [width.div_ceil(k), height.div_ceil(k)];
        let low = float_target(ctx, "indirect (subsampled)", low_size[0], low_size[1]);
        let low_view = low.create_view(&Default::default());
        let up_params = buffer_init(
            ctx,
            "upsample params",
            bytemuck::bytes_of(&bytemuck::Zeroable::zeroed() as &UpsampleParamsRaw),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let (full, upsample_group) = if k > 1 {
            let full = float_target(ctx, "indirect", width, height);
            let full_view = full.create_view(&Default::default());
            // Until a full-resolution estimate is set, a 1×1 texture: nothing is added.
            let none = float_target(ctx, "indirect at full resolution (none)", 1, 1);
            let none = none.create_view(&Default::default());
            let group = upsample_group(ctx, gbuf, &up_params, &low_view, &none);
            (Some((full, full_view)), Some(group))
        } else {
            (None, None)
        };
        IndirectTarget {
            subsample: k,
            low_size,
            low,
            low_view,
            full,
            up_params,
            last_eye: None,
            upsample_group,
            centre: Vec2::splat(0.5),
        }
    }

    /// Has the upsampling add `full`, a full-resolution estimate of the same size as the
    /// G-buffer (nothing at subsample 1, which has no upsampling: its one estimate holds
    /// all the light).
    pub fn set_full_resolution(
        &mut self,
        ctx: &GpuContext,
        gbuf: &GBuffer,
        full: &wgpu::TextureView,
    ) {
        if self.upsample_group.is_some() {
            self.upsample_group = Some(upsample_group(
                ctx,
                gbuf,
                &self.up_params,
                &self.low_view,
                full,
            ));
        }
    }

    /// The estimate at full resolution.
    pub fn output(&self) -> (&wgpu::Texture, &wgpu::TextureView) {
        match &self.full {
            Some((t, v)) => (t, v),
            None => (&self.low, &self.low_view),
        }
    }

    /// World → clip of the low-resolution target. Low-res texel i shades full-res pixel
    /// i·k + ⌊k/2⌋, whose centre is half a full-res pixel off the low-res sample position
    /// when k is even: the view is shifted to match, so that coverage is tested where the
    /// G-buffer sample lies.
    pub fn view_proj(&self, scene: &Scene) -> Mat4 {
        let (w, h, k) = (scene.camera.width, scene.camera.height, self.subsample);
        let eye = camera_view(scene, self.centre, 0.0);
        let half = if k % 2 == 0 { 1.0 } else { 0.0 };
        let shift = Mat4::from_translation(Vec3::new(-half / w as f32, half / h as f32, 0.0));
        shift * Mat4::from_cols_array_2d(&eye.view_proj)
    }

    /// Sets where in its pixel the eye G-buffer is sampled; the estimators' view follows.
    pub fn set_sample_centre(&mut self, centre: Vec2) {
        self.centre = centre;
    }

    /// Uploads the upsampling parameters when the eye moved.
    pub fn write_params(&mut self, ctx: &GpuContext, scene: &Scene) {
        let eye: [f32; 3] = scene.camera.position.into();
        if self.last_eye == Some(eye) {
            return;
        }
        let up = UpsampleParamsRaw {
            eye,
            subsample: self.subsample,
        };
        gpu::write_buffer(
            &ctx.queue,
            "upsample params",
            &self.up_params,
            0,
            bytemuck::bytes_of(&up),
        );
        self.last_eye = Some(eye);
    }

    /// Records the upsampling (nothing at subsample 1).
    pub fn record_upsample(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut Timer,
    ) {
        let (Some((_, full_view)), Some(group)) = (&self.full, &self.upsample_group) else {
            return;
        };
        draw_fullscreen(
            encoder,
            "upsample pass",
            full_view,
            &UpsamplePass::get(ctx).pipeline,
            &[group],
            timer.pass("upsample"),
        );
    }
}
