//! The photon-volume estimator of ISPM (McGuire & Luebke 2009, section 5): one instanced
//! icosahedron or screen-aligned quad per photon, splatted with additive blending over the
//! eye G-buffer at 1/`subsample` resolution, then joint bilateral upsampling (section 5.2).
//!
//! Its GPU resources live as long as the image size: the low- and full-resolution targets,
//! the parameter buffers and bind groups, the icosahedron, and a photon buffer that grows
//! geometrically (a frame rewrites only the photons in it).

use crate::gpu::{self, GpuContext};
use crate::photon::Photon;
use crate::raster::gbuffer::GBuffer;
use crate::raster::ispm::{
    icosahedron, tex, IspmPasses, UpsampleParamsRaw, VolumeParamsRaw, TARGET, Z_RATIO,
};
use crate::raster::timer::Timer;
use crate::raster::volume_shape::VolumeRadius;
use crate::raster::{buffer_init, camera_view};
use crate::scene::Scene;
use glam::Vec2;

/// Photons the buffer holds before it first grows.
const MIN_CAPACITY: usize = 1 << 16;

pub struct Volumes {
    subsample: u32,
    low: wgpu::Texture,
    low_view: wgpu::TextureView,
    /// Full-resolution output of the upsampling (`None` when `subsample` is 1).
    full: Option<(wgpu::Texture, wgpu::TextureView)>,
    params: wgpu::Buffer,
    last_params: Option<VolumeParamsRaw>,
    up_params: wgpu::Buffer,
    volume_group: wgpu::BindGroup,
    upsample_group: Option<wgpu::BindGroup>,
    ico: wgpu::Buffer,
    ico_vertices: u32,
    photons: wgpu::Buffer,
    capacity: usize,
    /// Where in its pixel the eye G-buffer was sampled (0.5, 0.5 but in progressive passes).
    centre: Vec2,
}

fn target(ctx: &GpuContext, label: &str, w: u32, h: u32) -> wgpu::Texture {
    gpu::create_texture(
        &ctx.device,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: TARGET,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        },
    )
}

fn photon_buffer(ctx: &GpuContext, capacity: usize) -> wgpu::Buffer {
    gpu::create_buffer(
        &ctx.device,
        &wgpu::BufferDescriptor {
            label: Some("photons"),
            size: (capacity * std::mem::size_of::<Photon>()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        },
    )
}

impl Volumes {
    /// Targets for a `width × height` image over the G-buffer `gbuf`.
    pub fn new(ctx: &GpuContext, gbuf: &GBuffer, width: u32, height: u32, subsample: u32) -> Self {
        let passes = IspmPasses::get(ctx);
        let device = &ctx.device;
        let k = subsample.max(1);
        let low = target(
            ctx,
            "indirect (subsampled)",
            width.div_ceil(k),
            height.div_ceil(k),
        );
        let low_view = low.create_view(&Default::default());
        let uniform = wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST;
        let params = buffer_init(
            ctx,
            "volume params",
            bytemuck::bytes_of(&bytemuck::Zeroable::zeroed() as &VolumeParamsRaw),
            uniform,
        );
        let up_params = buffer_init(
            ctx,
            "upsample params",
            bytemuck::bytes_of(&bytemuck::Zeroable::zeroed() as &UpsampleParamsRaw),
            uniform,
        );
        let inputs = gbuf.lighting_inputs();
        let volume_group = gpu::create_bind_group(
            device,
            &wgpu::BindGroupDescriptor {
                label: Some("volume bind group"),
                layout: &passes.volume_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: params.as_entire_binding(),
                    },
                    tex(1, &inputs[0]),
                    tex(2, &inputs[1]),
                    tex(3, &inputs[2]),
                    tex(4, &inputs[3]),
                ],
            },
        );
        let (full, upsample_group) = if k > 1 {
            let full = target(ctx, "indirect", width, height);
            let full_view = full.create_view(&Default::default());
            let group = gpu::create_bind_group(
                device,
                &wgpu::BindGroupDescriptor {
                    label: Some("upsample bind group"),
                    layout: &passes.upsample_layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: up_params.as_entire_binding(),
                        },
                        tex(1, &inputs[0]),
                        tex(2, &inputs[1]),
                        tex(3, &low_view),
                    ],
                },
            );
            (Some((full, full_view)), Some(group))
        } else {
            (None, None)
        };
        let ico = icosahedron();
        Volumes {
            subsample: k,
            low,
            low_view,
            full,
            params,
            last_params: None,
            centre: Vec2::splat(0.5),
            up_params,
            volume_group,
            upsample_group,
            ico: buffer_init(
                ctx,
                "icosahedron",
                bytemuck::cast_slice(&ico),
                wgpu::BufferUsages::VERTEX,
            ),
            ico_vertices: ico.len() as u32,
            photons: photon_buffer(ctx, MIN_CAPACITY),
            capacity: MIN_CAPACITY,
        }
    }

    /// The estimate at full resolution.
    pub fn output(&self) -> (&wgpu::Texture, &wgpu::TextureView) {
        match &self.full {
            Some((t, v)) => (t, v),
            None => (&self.low, &self.low_view),
        }
    }

    /// Sets where in its pixel the eye G-buffer is sampled (the volumes are rasterized with
    /// the same jitter, so coverage is tested where the G-buffer sample lies).
    pub fn set_sample_centre(&mut self, centre: Vec2) {
        self.centre = centre;
    }

    /// Uploads the view-dependent parameters when they changed.
    pub fn write_params(&mut self, ctx: &GpuContext, scene: &Scene, radius: VolumeRadius) {
        let (w, h, k) = (scene.camera.width, scene.camera.height, self.subsample);
        let eye = camera_view(scene, self.centre, 0.0);
        // Low-res texel i shades full-res pixel i·k + ⌊k/2⌋, whose centre is half a full-res
        // pixel off the low-res sample position when k is even: shift the volumes to match,
        // so that coverage is tested where the G-buffer sample lies.
        let half = if k % 2 == 0 { 1.0 } else { 0.0 };
        let shift =
            glam::Mat4::from_translation(glam::Vec3::new(-half / w as f32, half / h as f32, 0.0));
        let params = VolumeParamsRaw {
            view_proj: (shift * glam::Mat4::from_cols_array_2d(&eye.view_proj)).to_cols_array_2d(),
            eye: scene.camera.position.into(),
            r_base: radius.r_base,
            r_max: radius.r_max,
            z_ratio: Z_RATIO,
            subsample: k,
            _pad: 0.0,
        };
        let same = self
            .last_params
            .is_some_and(|p| bytemuck::bytes_of(&p) == bytemuck::bytes_of(&params));
        if same {
            return;
        }
        gpu::write_buffer(
            &ctx.queue,
            "volume params",
            &self.params,
            0,
            bytemuck::bytes_of(&params),
        );
        let up = UpsampleParamsRaw {
            eye: scene.camera.position.into(),
            subsample: k,
        };
        gpu::write_buffer(
            &ctx.queue,
            "upsample params",
            &self.up_params,
            0,
            bytemuck::bytes_of(&up),
        );
        self.last_params = Some(params);
    }

    /// Uploads the photons to splat (quads first), growing the buffer to twice what is
    /// needed when it is too small.
    pub fn write_photons(&mut self, ctx: &GpuContext, ordered: &[Photon]) {
        if ordered.len() > self.capacity {
            self.capacity = (2 * ordered.len()).next_power_of_two();
            self.photons = photon_buffer(ctx, self.capacity);
        }
        gpu::write_buffer(
            &ctx.queue,
            "photons",
            &self.photons,
            0,
            bytemuck::cast_slice(ordered),
        );
    }

    /// Records the splat of the uploaded photons (`quads` quads, then icosahedra up to
    /// `count`) and the upsampling.
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        count: u32,
        quads: u32,
        timer: &mut Timer,
    ) {
        let passes = IspmPasses::get(ctx);
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("volume pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.low_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: timer.pass("photon volumes"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, &self.volume_group, &[]);
            let bytes = (count as usize * std::mem::size_of::<Photon>()) as u64;
            if quads > 0 {
                pass.set_pipeline(&passes.volume_quad);
                pass.set_vertex_buffer(0, self.photons.slice(..bytes));
                pass.draw(0..4, 0..quads);
            }
            if quads < count {
                pass.set_pipeline(&passes.volume);
                pass.set_vertex_buffer(0, self.ico.slice(..));
                pass.set_vertex_buffer(1, self.photons.slice(..bytes));
                pass.draw(0..self.ico_vertices, quads..count);
            }
        }
        if let (Some((_, full_view)), Some(group)) = (&self.full, &self.upsample_group) {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("upsample pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: full_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: timer.pass("upsample"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&passes.upsample);
            pass.set_bind_group(0, group, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}
