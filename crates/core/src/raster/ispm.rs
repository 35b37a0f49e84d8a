//! Method `ispm`: Image Space Photon Mapping (McGuire & Luebke 2009).
//!
//! 1. Direct light: the frame of method `direct` (shadow maps, eye G-buffers, deferred
//!    shading), unchanged.
//! 2. Bounce map (section 4.2): per light a light-space G-buffer (one perspective view per
//!    spot light, six exact cube faces per point light) whose texels are the photons leaving
//!    the light. Resolutions split `Settings::photons` between lights by power; a texel's
//!    power is I(ω)·A·cos³θ, corrected per light so that all texels sum to the light's power.
//!    The hits are direct light and are not stored. Their first scatter (importance sampling
//!    of the uber BSDF, Russian roulette, path density) is taken in the same fragment shader
//!    (`bounce.wgsl`, a port of `Material::sample`); surviving texels are read back as
//!    [`PhotonRay`]s.
//!    The bounce maps are submitted before the direct-light frame, with the copies of their
//!    targets into mappable buffers in the same submission, and mapped after it
//!    ([`PendingBounceMap`]): the readback does not stall the CPU.
//! 3. CPU photon tracing of the later bounces ([`crate::photon::continue_paths`], bounce
//!    index 1 for the first-bounce rays).
//! 4. Photon volumes (section 5): one instanced icosahedron or screen-aligned quad per stored
//!    photon ([`super::volume_shape`]), splatted into an `Rgba32Float` target with additive
//!    blending (`volume.wgsl`), at 1/`subsample` resolution, then joint bilateral upsampling
//!    (`upsample.wgsl`).
//! 5. Mirrors and glass seen by the camera: backward ray tracing on the CPU with a photon-map
//!    gather where the specular paths land (`specular.rs`).
//!
//! The final radiance is direct + specular + indirect (AOVs `direct`, `specular`,
//! `indirect`); `caustics` stays zero.

use crate::gpu::Pipelines;
use super::layers::LayerTargets;
use crate::gpu::timer::Timer;
use super::{buffer_init, gbuffer, Geometry};
use crate::error::{Error, Result};
use crate::gpu::{self, shaders, GpuContext};
use crate::image::Image;
use crate::photon::bounce::BounceMap;
use crate::photon::{Photon, PhotonRay};
use crate::render::Settings;
use crate::gpu::raw::BounceViewRaw;
use crate::scene::light_views::{light_views, LightView, BOUNCE_MAPS};
use crate::scene::Scene;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::time::Instant;

/// r_z / r_xy of the photon volumes.
pub(crate) const Z_RATIO: f32 = 0.5;

pub(crate) const TARGET: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// `VolumeParams` of `volume.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct VolumeParamsRaw {
    pub view_proj: [[f32; 4]; 4],
    pub eye: [f32; 3],
    pub r_base: f32,
    pub r_max: f32,
    pub z_ratio: f32,
    pub subsample: u32,
    pub _pad: f32,
}

/// `UpsampleParams` of `upsample.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct UpsampleParamsRaw {
    pub eye: [f32; 3],
    pub subsample: u32,
}

const BOUNCE_VIEW_SIZE: u64 = std::mem::size_of::<BounceViewRaw>() as u64;

/// Pipelines of method `ispm`, compiled once per device.
pub struct IspmPasses {
    /// One per [`super::textures::Variant`], in `Variant::ALL` order.
    pub(crate) bounce: Vec<wgpu::RenderPipeline>,
    pub(crate) bounce_layout: wgpu::BindGroupLayout,
    /// Photon volumes as icosahedra.
    pub(crate) volume: wgpu::RenderPipeline,
    /// Photon volumes as screen-aligned quads.
    pub(crate) volume_quad: wgpu::RenderPipeline,
    pub(crate) volume_layout: wgpu::BindGroupLayout,
    pub(crate) upsample: wgpu::RenderPipeline,
    pub(crate) upsample_layout: wgpu::BindGroupLayout,
}

fn texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
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

impl IspmPasses {
    fn new(device: &wgpu::Device, textures: &wgpu::BindGroupLayout) -> Self {
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries,
            })
        };
        let pipeline_layout = |bgl: &wgpu::BindGroupLayout| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("ispm pipeline layout"),
                bind_group_layouts: &[Some(bgl)],
                immediate_size: 0,
            })
        };

        // Bounce map.
        let bounce_layout = layout(
            "bounce bind group layout",
            &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(BOUNCE_VIEW_SIZE),
                    },
                    count: None,
                },
                super::storage_entry(1, wgpu::ShaderStages::FRAGMENT),
            ],
        );
        let module = shaders::module(
            device,
            "bounce shader",
            &[
                shaders::COMMON,
                shaders::BSDF,
                shaders::TEXTURE,
                shaders::LIGHT_VIEW,
                shaders::BOUNCE,
            ],
        );
        let bounce_pipeline_layout =
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("bounce pipeline layout"),
                bind_group_layouts: &[Some(&bounce_layout), Some(textures)],
                immediate_size: 0,
            });
        let targets: [_; 5] = std::array::from_fn(|_| Some(wgpu::ColorTargetState::from(TARGET)));
        let bounce_pipeline = |entry: &str| {
            crate::gpu::create_render_pipeline(
                device,
                &wgpu::RenderPipelineDescriptor {
                    label: Some("bounce pipeline"),
                    layout: Some(&bounce_pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_main"),
                        compilation_options: Default::default(),
                        buffers: &[Some(gbuffer::vertex_layout())],
                    },
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: gbuffer::DEPTH,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::Less),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        targets: &targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                },
            )
        };
        let bounce = super::textures::Variant::ALL
            .iter()
            .map(|v| bounce_pipeline(v.entry_point()))
            .collect();

        // Photon volumes.
        let volume_layout = layout(
            "volume bind group layout",
            &[
                uniform_entry(0),
                texture_entry(1),
                texture_entry(2),
                texture_entry(3),
                texture_entry(4),
            ],
        );
        let module = shaders::module(
            device,
            "volume shader",
            &[
                shaders::COMMON,
                shaders::BSDF,
                shaders::PHOTON_VOLUME,
                shaders::VOLUME,
            ],
        );
        let corner_attr = wgpu::vertex_attr_array![0 => Float32x3];
        let photon_attr = photon_attributes();
        let additive = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let photon_buffer = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<Photon>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &photon_attr,
        };
        // The two bounding shapes (`volume_shape`) share the fragment stage and differ in
        // the vertex stage and topology.
        let volume_pipeline =
            |label, entry_point, buffers: &[Option<wgpu::VertexBufferLayout>], primitive| {
                crate::gpu::create_render_pipeline(
                    device,
                    &wgpu::RenderPipelineDescriptor {
                        label: Some(label),
                        layout: Some(&pipeline_layout(&volume_layout)),
                        vertex: wgpu::VertexState {
                            module: &module,
                            entry_point: Some(entry_point),
                            compilation_options: Default::default(),
                            buffers,
                        },
                        primitive,
                        depth_stencil: None,
                        multisample: Default::default(),
                        fragment: Some(wgpu::FragmentState {
                            module: &module,
                            entry_point: Some("fs_main"),
                            compilation_options: Default::default(),
                            targets: &[Some(wgpu::ColorTargetState {
                                format: TARGET,
                                blend: Some(wgpu::BlendState {
                                    color: additive,
                                    alpha: additive,
                                }),
                                write_mask: wgpu::ColorWrites::ALL,
                            })],
                        }),
                        multiview_mask: None,
                        cache: None,
                    },
                )
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

        // Joint bilateral upsampling.
        let upsample_layout = layout(
            "upsample bind group layout",
            &[
                uniform_entry(0),
                texture_entry(1),
                texture_entry(2),
                texture_entry(3),
                texture_entry(4),
                texture_entry(5),
            ],
        );
        let module = shaders::module(
            device,
            "upsample shader",
            &[shaders::COMMON, shaders::BSDF, shaders::UPSAMPLE],
        );
        let upsample = crate::gpu::create_fullscreen_pipeline(
            device,
            "upsample pipeline",
            &pipeline_layout(&upsample_layout),
            &module,
            "fs_main",
            TARGET.into(),
        );
        IspmPasses {
            bounce,
            bounce_layout,
            volume,
            volume_quad,
            volume_layout,
            upsample,
            upsample_layout,
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

/// [`BounceTargets`] on the context of `settings.adapter`, for inspection and tests: the
/// bounce maps of `scene` rendered and read back once.
pub fn render_bounce_map(scene: &Scene, settings: &Settings) -> Result<BounceMap> {
    settings.validate()?;
    let ctx = gpu::context(settings.adapter.as_deref())?;
    ctx.scoped("bounce map", || {
        let geometry = Geometry::upload(&ctx, scene);
        let materials: Vec<_> = scene.materials.iter().map(|m| m.to_raw()).collect();
        let materials = buffer_init(
            &ctx,
            "materials",
            bytemuck::cast_slice(&materials),
            wgpu::BufferUsages::STORAGE,
        );
        let layers = light_views(scene, settings.photons);
        let textures =
            super::textures::GpuTextures::new(&ctx, scene, &super::textures::TexturesLayout::get(&ctx).layout)?;
        let Some(targets) = BounceTargets::new(&ctx, &layers, &materials)? else {
            return Ok(BounceMap::default());
        };
        targets.write_views(&ctx, scene, &layers, settings.seed);
        let mut timer = Timer::new(&ctx, layers.len() as u32);
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("bounce maps"),
            });
        targets.record(
            &IspmPasses::get(&ctx),
            &mut encoder,
            &layers,
            &geometry,
            &super::shadow::CullUnits::of(scene),
            (&textures.group, super::textures::Variant::of(scene)),
            &mut timer,
        );
        timer.resolve(&mut encoder);
        let index = ctx.queue.submit([encoder.finish()]);
        let mut bm = targets.finish(&ctx, &layers, Some(index))?;
        timer.collect(&ctx)?;
        bm.raster_seconds = timer.totals.iter().map(|(_, s)| s).sum();
        Ok(bm)
    })
}

/// The bounce maps' GPU resources for a number of layers and a resolution: five
/// `Rgba32Float` target arrays, depth, the views and the mappable copies of the targets.
/// Recorded into a frame's first submission and mapped after the direct light was
/// submitted (section 4.3's asynchronous readback): [`BounceTargets::finish`] waits only for
/// the bounce submission.
pub struct BounceTargets {
    layers: LayerTargets,
    views: wgpu::Buffer,
    group: wgpu::BindGroup,
}

impl BounceTargets {
    /// Resources for `layers` (`None` when there are none: no light emits).
    pub fn new(
        ctx: &GpuContext,
        layers: &[LightView],
        materials: &wgpu::Buffer,
    ) -> Result<Option<Self>> {
        if layers.is_empty() {
            return Ok(None);
        }
        let passes = IspmPasses::get(ctx);
        let targets = LayerTargets::new(ctx, layers, &BOUNCE_MAPS)?;
        let views = buffer_init(
            ctx,
            "bounce views",
            &vec![0u8; layers.len() * BOUNCE_VIEW_SIZE as usize],
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let group = crate::gpu::create_bind_group(
            &ctx.device,
            &wgpu::BindGroupDescriptor {
                label: Some("bounce bind group"),
                layout: &passes.bounce_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &views,
                            offset: 0,
                            size: wgpu::BufferSize::new(BOUNCE_VIEW_SIZE),
                        }),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: materials.as_entire_binding(),
                    },
                ],
            },
        );
        Ok(Some(BounceTargets {
            layers: targets,
            views,
            group,
        }))
    }

    /// Whether these resources serve `layers`.
    pub fn fits(&self, layers: &[LightView]) -> bool {
        self.layers.fits(layers)
    }

    /// Uploads the layers' views with the frame's random seed.
    pub fn write_views(&self, ctx: &GpuContext, scene: &Scene, layers: &[LightView], seed: u64) {
        let views: Vec<BounceViewRaw> = layers
            .iter()
            .enumerate()
            .map(|(i, l)| BounceViewRaw::new(i as u32, l, &scene.lights[l.light], seed))
            .collect();
        crate::gpu::write_buffer(
            &ctx.queue,
            "bounce views",
            &self.views,
            0,
            bytemuck::cast_slice(&views),
        );
    }

    /// Records the bounce passes of all layers and the copies of their targets.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        passes: &IspmPasses,
        encoder: &mut wgpu::CommandEncoder,
        layers: &[LightView],
        geometry: &Geometry,
        cull: &super::shadow::CullUnits,
        textures: (&wgpu::BindGroup, super::textures::Variant),
        timer: &mut Timer,
    ) {
        self.layers.record(
            encoder,
            "bounce maps",
            &passes.bounce[textures.1 as usize],
            (&self.group, BOUNCE_VIEW_SIZE),
            textures.0,
            geometry,
            layers,
            cull,
            timer,
        );
    }

    /// Maps the copies once submission `after` is done and turns the surviving texels into
    /// rays, grouped by light.
    pub fn finish(
        &self,
        ctx: &GpuContext,
        layers: &[LightView],
        after: Option<wgpu::SubmissionIndex>,
    ) -> Result<BounceMap> {
        let mut out = BounceMap::default();
        let max_res = self.layers.max_res;
        let t = Instant::now();
        let read = self.layers.read(ctx, after)?;
        let [origin, direction, power, incident, expected] = &read[..] else {
            return Err(Error::Gpu("bounce map readback".into()));
        };
        out.readback_seconds = t.elapsed().as_secs_f64();
        let t = Instant::now();

        // Surviving texels become rays for the CPU tracer.
        let per_layer = (max_res * max_res) as usize;
        for (li, layer) in layers.iter().enumerate() {
            for y in 0..layer.res as usize {
                for x in 0..layer.res as usize {
                    let i = li * per_layer + y * max_res as usize + x;
                    if incident[i].w <= 0.0 {
                        continue;
                    }
                    out.covered += 1;
                    out.incident_power += incident[i].truncate().as_dvec3();
                    out.expected_scattered_power += expected[i].truncate().as_dvec3();
                    if direction[i].w <= 0.0 {
                        continue;
                    }
                    let carried = power[i].truncate();
                    out.scattered_power += carried.as_dvec3();
                    out.rays.push(PhotonRay::new(
                        origin[i].truncate(),
                        direction[i].truncate(),
                        carried,
                        origin[i].w,
                        1,
                    ));
                    out.ray_lights.push(layer.light as u32);
                    out.first_delta.push(power[i].w > 0.5);
                }
            }
        }
        out.texels = layers.iter().map(|l| l.res as u64 * l.res as u64).sum();
        out.scatter_seconds = t.elapsed().as_secs_f64();
        Ok(out)
    }
}

pub(crate) fn tex(binding: u32, view: &wgpu::TextureView) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::TextureView(view),
    }
}

/// Radius (m) of a photon volume of path density 1: `kernel_scale`·√(scene area / photons).
pub fn base_radius(scene: &Scene, photons: u64, kernel_scale: f32) -> f32 {
    let area: f64 = (0..scene.triangles.len())
        .map(|t| {
            let [a, b, c] = scene.triangle(t);
            0.5 * (b - a).cross(c - a).length() as f64
        })
        .sum();
    (kernel_scale as f64 * (area / photons.max(1) as f64).sqrt()) as f32
}

/// Where the stored photons land, as seen from the camera: per pixel, the number of visible
/// photons of bounce 1 (green) and of later bounces (red).
pub(crate) fn photon_hits(scene: &Scene, position: &Image, photons: &[Photon]) -> Image {
    let cam = &scene.camera;
    let mut img = Image::new(cam.width, cam.height);
    for p in photons {
        let pos = p.position();
        let Some((x, y, _)) = cam.project(pos) else {
            continue;
        };
        let i = y as usize * cam.width as usize + x as usize;
        // Visible if the surface seen through the pixel is where the photon is.
        let seen = position.pixels[i];
        let dist = (pos - cam.position).length();
        if (seen - pos).length() > 0.02 * dist {
            continue;
        }
        img.pixels[i] += if p.bounce <= 1 { Vec3::Y } else { Vec3::X };
    }
    img
}


impl crate::gpu::Pipelines for IspmPasses {
    fn create(ctx: &GpuContext) -> Self {
        IspmPasses::new(&ctx.device, &super::textures::TexturesLayout::get(ctx).layout)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
