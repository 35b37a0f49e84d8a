//! The photon-volume estimator of ISPM (McGuire & Luebke 2009, section 5): one instanced
//! icosahedron or screen-aligned quad per photon, splatted with additive blending over the
//! eye G-buffer at 1/`subsample` resolution, then joint bilateral upsampling (section 5.2).
//!
//! Its GPU resources live as long as the image size: the low- and full-resolution targets,
//! the parameter buffers and bind groups, the icosahedron, and a photon buffer that grows
//! geometrically (a frame rewrites only the photons in it).

use crate::gpu::Pipelines;
use super::target::IndirectTarget;
use crate::gpu::{self, GpuContext};
use crate::photon::Photon;
use crate::raster::buffer_init;
use crate::raster::gbuffer::GBuffer;
use crate::raster::ispm::{icosahedron, tex, IspmPasses, VolumeParamsRaw, Z_RATIO};
use crate::gpu::timer::Timer;
use crate::raster::volume_shape::VolumeRadius;
use crate::scene::Scene;

/// Photons the buffer holds before it first grows.
const MIN_CAPACITY: usize = 1 << 16;

pub struct Volumes {
    pub(super) target: IndirectTarget,
    params: wgpu::Buffer,
    last_params: Option<VolumeParamsRaw>,
    volume_group: wgpu::BindGroup,
    ico: wgpu::Buffer,
    ico_vertices: u32,
    photons: wgpu::Buffer,
    capacity: usize,
    /// Photons to draw, the first `quads` of them as quads.
    count: u32,
    quads: u32,
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
        let target = IndirectTarget::new(ctx, gbuf, width, height, subsample);
        let params = buffer_init(
            ctx,
            "volume params",
            bytemuck::bytes_of(&bytemuck::Zeroable::zeroed() as &VolumeParamsRaw),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let inputs = gbuf.lighting_inputs();
        let volume_group = gpu::create_bind_group(
            &ctx.device,
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
        let ico = icosahedron();
        Volumes {
            target,
            params,
            last_params: None,
            volume_group,
            ico: buffer_init(
                ctx,
                "icosahedron",
                bytemuck::cast_slice(&ico),
                wgpu::BufferUsages::VERTEX,
            ),
            ico_vertices: ico.len() as u32,
            photons: photon_buffer(ctx, MIN_CAPACITY),
            capacity: MIN_CAPACITY,
            count: 0,
            quads: 0,
        }
    }

    /// The estimate at full resolution.
    pub fn output(&self) -> (&wgpu::Texture, &wgpu::TextureView) {
        self.target.output()
    }

    /// Uploads the view-dependent parameters when they changed.
    pub fn write_params(&mut self, ctx: &GpuContext, scene: &Scene, radius: VolumeRadius) {
        let params = VolumeParamsRaw {
            view_proj: self.target.view_proj(scene).to_cols_array_2d(),
            eye: scene.camera.position.into(),
            r_base: radius.r_base,
            r_max: radius.r_max,
            z_ratio: Z_RATIO,
            subsample: self.target.subsample,
            _pad: 0.0,
        };
        self.target.write_params(ctx, scene);
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

    /// Sets what [`Volumes::record`] draws: `count` uploaded photons, the first `quads` of
    /// them as quads, the rest as icosahedra.
    pub fn set_draw(&mut self, count: u32, quads: u32) {
        (self.count, self.quads) = (count, quads);
    }

    /// Bytes of GPU memory the estimator holds beyond its targets, by part.
    pub fn memory(&self) -> Vec<(&'static str, u64)> {
        vec![
            ("photon buffer", self.capacity as u64 * 64),
            ("icosahedron", self.ico_vertices as u64 * 12),
        ]
    }

    /// Records the splat of the uploaded photons (the upsampling:
    /// [`super::target::IndirectTarget::record_upsample`]).
    pub fn record(&self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder, timer: &mut Timer) {
        let (count, quads) = (self.count, self.quads);
        let passes = IspmPasses::get(ctx);
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("volume pass"),
                color_attachments: &[Some(crate::gpu::cleared(&self.target.low_view))],
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
    }
}
