//! The photon-volume estimator of ISPM (McGuire & Luebke 2009, section 5): one instanced
//! icosahedron or screen-aligned quad per photon, splatted with additive blending over the
//! eye G-buffer at 1/`subsample` resolution, then joint bilateral upsampling (section 5.2).
//!
//! Its GPU resources live as long as the image size: the low- and full-resolution targets,
//! the parameter buffers and bind groups, the icosahedron, and a photon buffer that grows
//! geometrically (a frame rewrites only the photons in it).

use super::target::{IndirectTarget, TARGET};
use super::wgsl;
use crate::gpu::layout::{buffer, buffer_init, texture as tex, texture_entry, uniform_entry};
use crate::gpu::pipeline::{additive_target, bind_group_layout, pipeline_layout, RenderSpec};
use crate::gpu::raw::VolumeParamsRaw;
use crate::gpu::timer::Timer;
use crate::gpu::{self, shaders, GpuContext, Pipelines};
use crate::photon::radius::{VolumeRadius, Z_RATIO};
use crate::photon::Photon;
use crate::raster::gbuffer::GBuffer;
use crate::scene::Scene;

const FRAGMENT: wgpu::ShaderStages = wgpu::ShaderStages::FRAGMENT;

/// The photon-volume pipelines: both bounding shapes ([`super::volume_shape`]) share the
/// fragment stage and differ in the vertex stage and topology.
pub struct VolumePass {
    /// Photon volumes as icosahedra.
    volume: wgpu::RenderPipeline,
    /// Photon volumes as screen-aligned quads.
    volume_quad: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

/// The photon attributes of [`Photon`] as an instance-rate vertex buffer (locations 1..=5).
const PHOTON_ATTRIBUTES: [wgpu::VertexAttribute; 6] = wgpu::vertex_attr_array![
    1 => Float32x3, 2 => Float32x3, 3 => Float32, 4 => Float32x3, 5 => Float32x3, 6 => Float32
];

fn photon_attributes() -> [wgpu::VertexAttribute; 6] {
    // Offsets inside `Photon`: position 0, incident 16, path_density 28, power 32, normal 48,
    // footprint radius 60.
    let mut a = PHOTON_ATTRIBUTES;
    for (attr, offset) in a.iter_mut().zip([0u64, 16, 28, 32, 48, 60]) {
        attr.offset = offset;
    }
    a
}

impl Pipelines for VolumePass {
    fn create(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let volume_layout = bind_group_layout(
            device,
            "volume bind group layout",
            &[
                uniform_entry(0),
                texture_entry(1, FRAGMENT),
                texture_entry(2, FRAGMENT),
                texture_entry(3, FRAGMENT),
                texture_entry(4, FRAGMENT),
                texture_entry(5, FRAGMENT),
                crate::gpu::layout::storage_entry(6, FRAGMENT),
            ],
        );
        let module = shaders::module(
            device,
            "volume shader",
            &[
                shaders::COMMON,
                shaders::BSDF,
                shaders::MODELS,
                crate::raster::wgsl::EXACT_MODELS,
                wgsl::PHOTON_VOLUME,
                wgsl::VOLUME,
            ],
        );
        let corner_attr = wgpu::vertex_attr_array![0 => Float32x3];
        let photon_attr = photon_attributes();
        let photon_buffer = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<Photon>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &photon_attr,
        };
        let volume_pipeline_layout =
            pipeline_layout(device, "volume pipeline layout", &[&volume_layout]);
        let targets = [Some(additive_target(TARGET))];
        let volume_pipeline =
            |label, entry, buffers: &[Option<wgpu::VertexBufferLayout>], primitive| {
                RenderSpec {
                    buffers,
                    primitive,
                    targets: &targets,
                    ..RenderSpec::new(
                        label,
                        &volume_pipeline_layout,
                        &module,
                        entry,
                        Some("fs_main"),
                    )
                }
                .create(device)
            };
        let volume = volume_pipeline(
            "volume pipeline (icosahedron)",
            "vs_icosahedron",
            &[
                Some(wgpu::VertexBufferLayout {
                    array_stride: 12,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &corner_attr,
                }),
                Some(photon_buffer.clone()),
            ],
            wgpu::PrimitiveState {
                cull_mode: Some(wgpu::Face::Front),
                ..Default::default()
            },
        );
        // Corners from the vertex index; the photons are vertex buffer 0. Not culled: the
        // rectangle faces the camera by construction.
        let volume_quad = volume_pipeline(
            "volume pipeline (quad)",
            "vs_quad",
            &[Some(photon_buffer)],
            wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleStrip,
                ..Default::default()
            },
        );

        VolumePass {
            volume,
            volume_quad,
            layout: volume_layout,
        }
    }
}

/// A regular icosahedron circumscribing the unit sphere, as 20 outward-facing (counter-
/// clockwise seen from outside) triangles.
pub fn icosahedron() -> Vec<[f32; 3]> {
    let phi = (1.0 + 5f32.sqrt()) / 2.0;
    // Inradius of the unit-circumradius icosahedron.
    let inradius = (phi * phi / (3.0f32.sqrt() * (1.0 + phi * phi).sqrt())).min(1.0);
    // The scene's geodesic sphere at 0 subdivisions is that icosahedron, wound outwards.
    let ico = crate::scene::primitives::sphere(1.0, 0);
    ico.indices
        .iter()
        .flat_map(|t| t.map(|i| (ico.positions[i as usize] / inradius).to_array()))
        .collect()
}

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
    /// `models`: the materials' exact models (`raster::exact_models`).
    pub fn new(
        ctx: &GpuContext,
        (gbuf, models): (&GBuffer, &wgpu::Buffer),
        width: u32,
        height: u32,
        subsample: u32,
    ) -> Self {
        let passes = VolumePass::get(ctx);
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
                layout: &passes.layout,
                entries: &[
                    buffer(0, &params),
                    tex(1, &inputs[0]),
                    tex(2, &inputs[1]),
                    tex(3, &inputs[2]),
                    tex(4, &inputs[3]),
                    tex(5, gbuf.emission()),
                    buffer(6, models),
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
        let passes = VolumePass::get(ctx);
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn icosahedron_contains_the_unit_sphere() {
        let tris = icosahedron();
        assert_eq!(tris.len(), 60);
        for t in tris.chunks(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(Vec3::from);
            let n = (b - a).cross(c - a).normalize();
            // Outward and at distance >= 1 from the centre.
            assert!(n.dot(a) >= 1.0 - 1e-4, "{}", n.dot(a));
        }
    }
}
