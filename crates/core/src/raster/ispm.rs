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

use super::layers::{LayerKind, LayerTargets};
use super::timer::Timer;
use super::{buffer_init, gbuffer, Geometry};
use crate::error::{Error, Result};
use crate::gpu::{self, shaders, GpuContext};
use crate::image::Image;
use crate::photon::{Photon, PhotonRay};
use crate::render::Settings;
use crate::scene::{Light, Scene};
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};
use std::time::Instant;

/// r_z / r_xy of the photon volumes.
pub(crate) const Z_RATIO: f32 = 0.5;
/// Largest bounce-map side (texels).
const MAX_BOUNCE_RES: u32 = 4096;
/// Widest spot cone the bounce map covers (tan of the half angle, about 84°).
const MAX_SPOT_TAN: f32 = 10.0;

pub(crate) const TARGET: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// `BounceView` of `bounce.wgsl`, padded to 256 bytes for dynamic offsets.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct BounceViewRaw {
    pub view_proj: [[f32; 4]; 4],
    pub light_position: [f32; 3],
    pub texel_area: f32,
    pub forward: [f32; 3],
    pub kind: u32,
    pub intensity: [f32; 3],
    pub cos_inner: f32,
    pub spot_direction: [f32; 3],
    pub cos_outer: f32,
    /// Random seed of the frame (low 32 bits of `Settings::seed`, hashed with the high ones).
    pub seed: u32,
    /// Index of this layer among all bounce-map layers.
    pub layer: u32,
    pub _pad: [f32; 30],
}

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

/// One bounce-map layer: a light's view and its resolution.
#[derive(Clone, Debug)]
pub struct BounceLayer {
    pub light: usize,
    pub res: u32,
    pub view: BounceViewRaw,
}

/// The bounce-map layers of a scene for a photon budget: resolution per light proportional
/// to its share of the total power, texel areas corrected so that each light's texels sum
/// to its power.
pub fn bounce_layers(scene: &Scene, photons: u64) -> Vec<BounceLayer> {
    let (lo, hi) = super::shadow::bounds(scene);
    let total: f32 = scene.lights.iter().map(|l| l.power().element_sum()).sum();
    let mut layers = Vec::new();
    for (li, light) in scene.lights.iter().enumerate() {
        let power = light.power().element_sum();
        if !(power > 0.0 && total > 0.0) {
            continue;
        }
        let raw = light.to_raw();
        let p = light.position();
        let far = super::shadow::corners(lo, hi)
            .map(|c| (c - p).length())
            .into_iter()
            .fold(0.0f32, f32::max)
            * 1.01
            + 1e-3;
        let near = (far * 1e-4).max(1e-6);
        let views: Vec<(Vec3, Vec3, f32)> = match *light {
            Light::Point { .. } => super::shadow::CUBE_FACES
                .iter()
                .map(|&(f, u)| (f, u, 1.0))
                .collect(),
            Light::Spot {
                direction,
                cos_outer,
                ..
            } => {
                let t = cos_outer.clamp(-1.0, 1.0).acos().tan();
                let t = if t.is_finite() && t > 0.0 {
                    t.clamp(1e-3, MAX_SPOT_TAN)
                } else {
                    MAX_SPOT_TAN
                };
                let up = if direction.y.abs() < 0.99 {
                    Vec3::Y
                } else {
                    Vec3::X
                };
                vec![(direction, up, t)]
            }
        };
        let texels = photons as f64 * (power / total) as f64 / views.len() as f64;
        let res = (texels.sqrt().round() as u32).clamp(1, MAX_BOUNCE_RES);
        // Σ over texel centres of falloff·A·cos³θ, for the round-off correction.
        let mut grid = 0.0f64;
        for &(_, _, t) in &views {
            let area = (2.0 * t as f64 / res as f64).powi(2);
            for j in 0..res {
                for i in 0..res {
                    let x = (2.0 * (i as f64 + 0.5) / res as f64 - 1.0) * t as f64;
                    let y = (2.0 * (j as f64 + 0.5) / res as f64 - 1.0) * t as f64;
                    let c = 1.0 / (1.0 + x * x + y * y).sqrt();
                    let falloff = match *light {
                        Light::Point { .. } => 1.0,
                        Light::Spot { .. } => {
                            spot_falloff(c as f32, raw.cos_inner, raw.cos_outer) as f64
                        }
                    };
                    grid += falloff * area * c * c * c;
                }
            }
        }
        let intensity = Vec3::from(raw.intensity).element_sum() as f64;
        let correction = if grid > 0.0 && intensity > 0.0 {
            power as f64 / (intensity * grid)
        } else {
            0.0
        };
        for (forward, up, t) in views {
            let view_proj =
                super::shadow::perspective(t, near, far) * super::look_to(p, forward, up);
            let area = (2.0 * t / res as f32).powi(2);
            layers.push(BounceLayer {
                light: li,
                res,
                view: BounceViewRaw {
                    view_proj: view_proj.to_cols_array_2d(),
                    light_position: p.into(),
                    texel_area: (area as f64 * correction) as f32,
                    forward: forward.normalize().into(),
                    kind: raw.kind,
                    intensity: raw.intensity,
                    cos_inner: raw.cos_inner,
                    spot_direction: raw.direction,
                    cos_outer: raw.cos_outer,
                    seed: 0,
                    layer: layers.len() as u32,
                    _pad: [0.0; 30],
                },
            });
        }
    }
    layers
}

fn spot_falloff(cos: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if cos >= cos_inner {
        return 1.0;
    }
    if cos <= cos_outer {
        return 0.0;
    }
    let t = (cos - cos_outer) / (cos_inner - cos_outer);
    t * t * (3.0 - 2.0 * t)
}

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
    pub fn get(ctx: &GpuContext) -> &IspmPasses {
        ctx.ispm_passes
            .get_or_init(|| IspmPasses::new(&ctx.device, &super::Passes::get(ctx).textures))
    }

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

/// The bounce map's result: first-scatter rays and the bookkeeping of the power.
#[derive(Clone, Debug, Default)]
pub struct BounceMap {
    /// Photons that survived the first scatter, as rays for the CPU tracer (bounce 1).
    pub rays: Vec<PhotonRay>,
    /// Texels of all layers.
    pub texels: u64,
    /// Texels that hit the scene.
    pub covered: u64,
    /// Total power of the covered texels before the first scatter (W).
    pub incident_power: DVec3,
    /// Total power of the surviving rays (W).
    pub scattered_power: DVec3,
    /// Σ over covered texels of power × scatter probability (the expected scattered power).
    pub expected_scattered_power: DVec3,
    /// Seconds: rasterizing the bounce maps with the first scatter (until the GPU is done),
    /// reading them back, and converting the survivors to rays.
    pub raster_seconds: f64,
    pub readback_seconds: f64,
    pub scatter_seconds: f64,
    /// The light of each ray (index into `Scene::lights`).
    pub ray_lights: Vec<u32>,
    /// Whether each ray's first hit was on a material with a delta lobe (mirror, glass).
    pub first_delta: Vec<bool>,
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
        let layers = bounce_layers(scene, settings.photons);
        let textures =
            super::textures::GpuTextures::new(&ctx, scene, &super::Passes::get(&ctx).textures)?;
        let Some(targets) = BounceTargets::new(&ctx, &layers, &materials)? else {
            return Ok(BounceMap::default());
        };
        targets.write_views(&ctx, &layers, settings.seed);
        let mut timer = Timer::new(&ctx, layers.len() as u32);
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("bounce maps"),
            });
        targets.record(
            IspmPasses::get(&ctx),
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

/// The bounce maps' five targets.
const BOUNCE_MAPS: LayerKind = LayerKind {
    name: "bounce map",
    setting: "photons",
    targets: &[
        "bounce origin",
        "bounce direction",
        "bounce power",
        "bounce incident",
        "bounce expected",
    ],
};

/// A setting error when bounce maps of `layers` would outgrow their memory bound. Traced
/// maps ([`crate::photon::bounce`]) keep the same bound, so that `photons` means the same
/// on every device.
pub(crate) fn check_bounce_size(layers: &[BounceLayer]) -> Result<()> {
    super::layers::check_size(layers, &BOUNCE_MAPS)
}

impl BounceTargets {
    /// Resources for `layers` (`None` when there are none: no light emits).
    pub fn new(
        ctx: &GpuContext,
        layers: &[BounceLayer],
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
    pub fn fits(&self, layers: &[BounceLayer]) -> bool {
        self.layers.fits(layers)
    }

    /// Uploads the layers' views with the frame's random seed.
    pub fn write_views(&self, ctx: &GpuContext, layers: &[BounceLayer], seed: u64) {
        let seed32 = (seed ^ (seed >> 32)) as u32;
        let views: Vec<BounceViewRaw> = layers
            .iter()
            .map(|l| BounceViewRaw {
                seed: seed32,
                ..l.view
            })
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
        layers: &[BounceLayer],
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
        layers: &[BounceLayer],
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

    /// Cornell (one point light): six faces of √(budget / 6) texels a side whose texel
    /// solid angles, with the round-off correction, add up to 4π.
    #[test]
    fn bounce_layers_follow_budget_and_power() {
        let scene = crate::scene::builtin::load("cornell").expect("scene");
        let layers = bounce_layers(&scene, 10_000);
        assert_eq!(layers.len(), 6);
        let mut solid_angle = 0.0f64;
        for l in &layers {
            assert_eq!(l.res, 41);
            for j in 0..l.res {
                for i in 0..l.res {
                    let x = 2.0 * (i as f64 + 0.5) / l.res as f64 - 1.0;
                    let y = 2.0 * (j as f64 + 0.5) / l.res as f64 - 1.0;
                    let c = 1.0 / (1.0 + x * x + y * y).sqrt();
                    solid_angle += l.view.texel_area as f64 * c * c * c;
                }
            }
        }
        assert!((solid_angle / (4.0 * std::f64::consts::PI) - 1.0).abs() < 1e-5);
    }
}
