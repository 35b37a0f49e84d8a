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

use super::timer::Timer;
use super::volume_shape::{partition, VolumeRadius};
use super::{buffer_init, camera_view, gbuffer, view_binding, Geometry};
use crate::error::{Error, Result};
use crate::gpu::{self, shaders, GpuContext};
use crate::image::Image;
use crate::photon::trace::Checked;
use crate::photon::{boundary, continue_paths_checked, Photon, PhotonRay, PhotonTraceSettings};
use crate::render::{Progress, RenderOutput, Settings};
use crate::scene::{Light, Scene};
use crate::trace::SceneBvh;
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec2, Vec3, Vec4};
use std::time::Instant;

/// r_z / r_xy of the photon volumes.
const Z_RATIO: f32 = 0.5;
/// Largest bounce-map side (texels).
const MAX_BOUNCE_RES: u32 = 4096;
/// Most GPU memory the bounce-map targets may take.
const MAX_BOUNCE_BYTES: u64 = 2 << 30;
/// Widest spot cone the bounce map covers (tan of the half angle, about 84°).
const MAX_SPOT_TAN: f32 = 10.0;

const TARGET: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

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
struct VolumeParamsRaw {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 3],
    r_base: f32,
    r_max: f32,
    z_ratio: f32,
    subsample: u32,
    _pad: f32,
}

/// `UpsampleParams` of `upsample.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct UpsampleParamsRaw {
    eye: [f32; 3],
    subsample: u32,
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
    bounce: wgpu::RenderPipeline,
    bounce_layout: wgpu::BindGroupLayout,
    /// Photon volumes as icosahedra.
    volume: wgpu::RenderPipeline,
    /// Photon volumes as screen-aligned quads.
    volume_quad: wgpu::RenderPipeline,
    volume_layout: wgpu::BindGroupLayout,
    upsample: wgpu::RenderPipeline,
    upsample_layout: wgpu::BindGroupLayout,
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
        ctx.ispm_passes.get_or_init(|| IspmPasses::new(&ctx.device))
    }

    fn new(device: &wgpu::Device) -> Self {
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
            &[shaders::COMMON, shaders::BSDF, shaders::BOUNCE],
        );
        let targets: [_; 5] = std::array::from_fn(|_| Some(wgpu::ColorTargetState::from(TARGET)));
        let bounce = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("bounce pipeline"),
            layout: Some(&pipeline_layout(&bounce_layout)),
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
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &targets,
            }),
            multiview_mask: None,
            cache: None,
        });

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
            &[shaders::COMMON, shaders::BSDF, shaders::VOLUME],
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
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
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
                })
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
            ],
        );
        let module = shaders::module(
            device,
            "upsample shader",
            &[shaders::COMMON, shaders::UPSAMPLE],
        );
        let upsample = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("upsample pipeline"),
            layout: Some(&pipeline_layout(&upsample_layout)),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState::from(TARGET))],
            }),
            multiview_mask: None,
            cache: None,
        });
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
}

/// [`bounce_map`] on the context of `settings.adapter`, for inspection and tests.
pub fn render_bounce_map(scene: &Scene, settings: &Settings) -> Result<BounceMap> {
    settings.validate()?;
    let ctx = gpu::context(settings.adapter.as_deref())?;
    ctx.scoped("bounce map", || {
        let geometry = Geometry::upload(&ctx, scene);
        bounce_map(&ctx, scene, &geometry, settings.photons, settings.seed)
    })
}

/// Renders the bounce maps of `scene` and takes the first scatter of every texel's photon.
pub fn bounce_map(
    ctx: &GpuContext,
    scene: &Scene,
    geometry: &Geometry,
    photons: u64,
    seed: u64,
) -> Result<BounceMap> {
    start_bounce_map(ctx, scene, geometry, photons, seed)?.finish(ctx)
}

/// Bounce maps submitted to the GPU together with the copies of their targets into
/// mappable buffers, not waited on: the readback runs on the GPU queue while the CPU goes on
/// submitting the eye passes (section 4.3's asynchronous readback), and
/// [`PendingBounceMap::finish`] maps the copies once that work is done.
pub struct PendingBounceMap {
    layers: Vec<BounceLayer>,
    max_res: u32,
    /// One buffer per bounce-map target, rows padded to `row` bytes.
    staging: Vec<wgpu::Buffer>,
    row: u32,
    timer: Timer,
    submit_seconds: f64,
}

/// Records and submits the bounce maps of `scene` with their readback copies.
pub fn start_bounce_map(
    ctx: &GpuContext,
    scene: &Scene,
    geometry: &Geometry,
    photons: u64,
    seed: u64,
) -> Result<PendingBounceMap> {
    let passes = IspmPasses::get(ctx);
    let device = &ctx.device;
    let layers = bounce_layers(scene, photons);
    if layers.is_empty() {
        return Ok(PendingBounceMap {
            layers,
            max_res: 0,
            staging: Vec::new(),
            row: 0,
            timer: Timer::new(ctx, 1),
            submit_seconds: 0.0,
        });
    }
    let max_res = layers.iter().map(|l| l.res).max().unwrap_or(1);
    let limits = device.limits();
    if max_res > limits.max_texture_dimension_2d {
        return Err(Error::setting(
            "photons",
            format!(
                "the bounce map needs {max_res} texels a side; the GPU allows {}",
                limits.max_texture_dimension_2d
            ),
        ));
    }
    let n_layers = layers.len() as u32;
    // Five Rgba32Float targets plus the readback copy: keep them within 2 GiB.
    let bytes = max_res as u64 * max_res as u64 * n_layers as u64 * 16 * 5;
    if bytes > MAX_BOUNCE_BYTES {
        return Err(Error::setting(
            "photons",
            format!(
                "the bounce maps would take {} MiB of GPU memory (at most {} MiB); use fewer photons",
                bytes >> 20,
                MAX_BOUNCE_BYTES >> 20
            ),
        ));
    }
    if n_layers > limits.max_texture_array_layers {
        return Err(Error::Gpu(format!(
            "{n_layers} bounce-map layers exceed the GPU's {}",
            limits.max_texture_array_layers
        )));
    }
    let seed32 = (seed ^ (seed >> 32)) as u32;
    let views: Vec<BounceViewRaw> = layers
        .iter()
        .map(|l| BounceViewRaw {
            seed: seed32,
            ..l.view
        })
        .collect();
    let materials: Vec<_> = scene.materials.iter().map(|m| m.to_raw()).collect();
    let material_buffer = buffer_init(
        ctx,
        "materials",
        bytemuck::cast_slice(&materials),
        wgpu::BufferUsages::STORAGE,
    );
    let view_buffer = buffer_init(
        ctx,
        "bounce views",
        bytemuck::cast_slice(&views),
        wgpu::BufferUsages::UNIFORM,
    );
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("bounce bind group"),
        layout: &passes.bounce_layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &view_buffer,
                    offset: 0,
                    size: wgpu::BufferSize::new(BOUNCE_VIEW_SIZE),
                }),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: material_buffer.as_entire_binding(),
            },
        ],
    });
    let size = wgpu::Extent3d {
        width: max_res,
        height: max_res,
        depth_or_array_layers: n_layers,
    };
    let make = |label, format, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
    let targets = [
        make("bounce origin", TARGET, usage),
        make("bounce direction", TARGET, usage),
        make("bounce power", TARGET, usage),
        make("bounce incident", TARGET, usage),
        make("bounce expected", TARGET, usage),
    ];
    let depth = make(
        "bounce depth",
        gbuffer::DEPTH,
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    );
    let layer_view = |t: &wgpu::Texture, i: u32| {
        t.create_view(&wgpu::TextureViewDescriptor {
            label: Some("bounce layer"),
            dimension: Some(wgpu::TextureViewDimension::D2),
            base_array_layer: i,
            array_layer_count: Some(1),
            ..Default::default()
        })
    };
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("bounce maps"),
    });
    let mut timer = Timer::new(ctx, n_layers);
    for (i, layer) in layers.iter().enumerate() {
        let i = i as u32;
        let views: Vec<_> = targets.iter().map(|t| layer_view(t, i)).collect();
        let depth_view = layer_view(&depth, i);
        let attachments: Vec<_> = views
            .iter()
            .map(|view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
            })
            .collect();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("bounce pass"),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.pass("bounce maps"),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&passes.bounce);
        pass.set_viewport(0.0, 0.0, layer.res as f32, layer.res as f32, 0.0, 1.0);
        pass.set_scissor_rect(0, 0, layer.res, layer.res);
        pass.set_bind_group(0, &group, &[(i as u64 * BOUNCE_VIEW_SIZE) as u32]);
        pass.set_vertex_buffer(0, geometry.vertices.slice(..));
        pass.draw(0..geometry.count, 0..1);
    }
    // Every target, all layers, into one mappable buffer each, in the same submission.
    let row = (max_res * 16).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let staging: Vec<wgpu::Buffer> = targets
        .iter()
        .map(|texture| {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("bounce readback"),
                size: row as u64 * max_res as u64 * n_layers as u64,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            encoder.copy_texture_to_buffer(
                texture.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: &buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(row),
                        rows_per_image: Some(max_res),
                    },
                },
                size,
            );
            buffer
        })
        .collect();
    timer.resolve(&mut encoder);
    let t = Instant::now();
    ctx.queue.submit([encoder.finish()]);
    Ok(PendingBounceMap {
        layers,
        max_res,
        staging,
        row,
        timer,
        submit_seconds: t.elapsed().as_secs_f64(),
    })
}

impl PendingBounceMap {
    /// Maps the copies (waiting for the GPU only if it is still busy) and turns the
    /// surviving texels into rays.
    pub fn finish(mut self, ctx: &GpuContext) -> Result<BounceMap> {
        let mut out = BounceMap::default();
        if self.layers.is_empty() {
            return Ok(out);
        }
        let (layers, max_res, row) = (&self.layers, self.max_res, self.row as usize);
        let t = Instant::now();
        let read = self
            .staging
            .iter()
            .map(|buffer| {
                let bytes = ctx.read_buffer(buffer)?;
                let width = max_res as usize * 16;
                Ok(bytes
                    .chunks_exact(row)
                    .flat_map(|r| bytemuck::cast_slice::<u8, Vec4>(&r[..width]).to_vec())
                    .collect::<Vec<Vec4>>())
            })
            .collect::<Result<Vec<_>>>()?;
        let [origin, direction, power, incident, expected] = &read[..] else {
            return Err(Error::Gpu("bounce map readback".into()));
        };
        out.readback_seconds = t.elapsed().as_secs_f64();
        self.timer.collect(ctx)?;
        // GPU time of the bounce passes when timestamps are available, else the submission.
        out.raster_seconds = self
            .timer
            .totals
            .iter()
            .map(|(_, s)| s)
            .sum::<f64>()
            .max(self.submit_seconds);
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
                }
            }
        }
        out.texels = layers.iter().map(|l| l.res as u64 * l.res as u64).sum();
        out.scatter_seconds = t.elapsed().as_secs_f64();
        Ok(out)
    }
}

fn tex(binding: u32, view: &wgpu::TextureView) -> wgpu::BindGroupEntry<'_> {
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

/// Method `ispm`.
pub fn render(scene: &Scene, settings: &Settings, progress: &dyn Progress) -> Result<RenderOutput> {
    let t0 = Instant::now();
    let ctx = gpu::context(settings.adapter.as_deref())?;
    ctx.scoped("ispm frame", || {
        // Bounce maps first: their readback runs on the GPU queue behind them while the
        // direct-light frame is recorded and rendered.
        let t = Instant::now();
        super::check_scene_buffers(&ctx, scene)?;
        let geometry = Geometry::upload(&ctx, scene);
        crate::cancel::check(progress)?;
        let pending = start_bounce_map(&ctx, scene, &geometry, settings.photons, settings.seed)?;
        let submit = t.elapsed().as_secs_f64();
        let mut out = super::frame(&ctx, scene, settings, Some(&geometry), progress, t0)?;
        let bm = pending.finish(&ctx)?;
        for (name, secs) in [
            ("bounce maps", bm.raster_seconds.max(submit)),
            ("bounce readback", bm.readback_seconds),
            ("bounce rays", bm.scatter_seconds),
        ] {
            out.stats.stages.push((name.to_string(), secs));
        }
        indirect(&ctx, scene, settings, progress, &mut out, &geometry, bm)?;
        out.stats.total_seconds = t0.elapsed().as_secs_f64();
        Ok(out)
    })
}

/// Adds the indirect light of the photon volumes to `out.radiance`.
fn indirect(
    ctx: &GpuContext,
    scene: &Scene,
    settings: &Settings,
    progress: &dyn Progress,
    out: &mut RenderOutput,
    geometry: &Geometry,
    bm: BounceMap,
) -> Result<()> {
    let passes = IspmPasses::get(ctx);
    let device = &ctx.device;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let k = settings.subsample.max(1);
    let (lw, lh) = (w.div_ceil(k), h.div_ceil(k));
    let stage = |out: &mut RenderOutput, name: &str, t: Instant| {
        out.stats
            .stages
            .push((name.to_string(), t.elapsed().as_secs_f64()))
    };

    out.stats.photons_emitted = bm.covered;
    out.stats.photons_first_bounce = bm.rays.len() as u64;
    if !progress.update("bounce maps", 1.0) {
        return Err(Error::Cancelled);
    }

    // Later bounces on the CPU.
    let t = Instant::now();
    let bvh = SceneBvh::try_build(scene)?;
    let photons: Vec<Photon> = if settings.max_depth >= 2 && !bm.rays.is_empty() {
        // Footprints from photon differentials size the volumes when asked for (issue 5);
        // otherwise the path-density heuristic of the paper does (section 5.1).
        let pts = if settings.footprint_volumes {
            PhotonTraceSettings {
                store_direct: false,
                ..crate::render::gather_trace_settings(scene, settings)
            }
        } else {
            PhotonTraceSettings {
                max_bounces: settings.max_depth - 1,
                store_direct: false,
                differentials: None,
            }
        };
        let control = Checked::new(progress, "cpu trace");
        continue_paths_checked(scene, &bvh, &bm.rays, &pts, settings.seed, &control)?.photons
    } else {
        Vec::new()
    };
    stage(out, "cpu trace", t);
    out.stats.photons_stored = photons.len() as u64;
    if !progress.update("cpu trace", 1.0) {
        return Err(Error::Cancelled);
    }

    // Mirrors and glass seen by the camera, traced backwards on the CPU. Their gather uses
    // the photons as traced: boundary compensation is for the splat's kernel only.
    let t = Instant::now();
    out.aovs.push(("direct".into(), out.radiance.clone()));
    let specular = super::specular::specular_paths(scene, &bvh, settings, &photons, progress)?;
    for (px, v) in out.radiance.pixels.iter_mut().zip(&specular.pixels) {
        *px += *v;
    }
    out.aovs.push(("specular".into(), specular));
    stage(out, "specular paths", t);

    // Volume radii are decided here, once (the splat reads `footprint_radius`).
    let mut photons = photons;
    let radius = VolumeRadius::of_scene(scene, settings.photons, settings.kernel_scale);
    for p in &mut photons {
        p.footprint_radius = radius.of(p);
    }
    if settings.boundary_compensation {
        let t = Instant::now();
        progress.update("boundary compensation", 0.0);
        boundary::compensate_until(
            scene,
            &bvh,
            &mut photons,
            |p| p.footprint_radius,
            Z_RATIO,
            settings.seed,
            &|| progress.cancelled(),
        );
        crate::cancel::check(progress)?;
        stage(out, "boundary compensation", t);
    }
    ctx.check_buffer("photon volumes", photons.len() as u64 * 64)?;
    if !progress.update("photon volumes", 0.0) {
        return Err(Error::Cancelled);
    }
    if photons.is_empty() {
        return Ok(());
    }

    // Photon volumes into the eye G-buffer at the pixel centres.
    let t = Instant::now();
    let gp = &super::Passes::get(ctx).gbuffer;
    let materials: Vec<_> = scene.materials.iter().map(|m| m.to_raw()).collect();
    let material_buffer = buffer_init(
        ctx,
        "materials",
        bytemuck::cast_slice(&materials),
        wgpu::BufferUsages::STORAGE,
    );
    let eye = camera_view(scene, Vec2::splat(0.5), 0.0);
    let eye_buffer = buffer_init(
        ctx,
        "eye view",
        bytemuck::bytes_of(&eye),
        wgpu::BufferUsages::UNIFORM,
    );
    let gbuf = gbuffer::GBuffer::new(device, w, h);
    let gbuffer_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("ispm gbuffer bind group"),
        layout: &gp.layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: view_binding(&eye_buffer),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: material_buffer.as_entire_binding(),
            },
        ],
    });
    let radius = VolumeRadius::of_scene(scene, settings.photons, settings.kernel_scale);
    // Low-res texel i shades full-res pixel i·k + ⌊k/2⌋, whose centre is half a full-res
    // pixel off the low-res sample position when k is even: shift the volumes to match, so
    // that coverage is tested where the G-buffer sample lies.
    let half = if k % 2 == 0 { 1.0 } else { 0.0 };
    let shift =
        glam::Mat4::from_translation(glam::Vec3::new(-half / w as f32, half / h as f32, 0.0));
    let volume_view = shift * glam::Mat4::from_cols_array_2d(&eye.view_proj);
    let params = VolumeParamsRaw {
        view_proj: volume_view.to_cols_array_2d(),
        eye: scene.camera.position.into(),
        r_base: radius.r_base,
        r_max: radius.r_max,
        z_ratio: Z_RATIO,
        subsample: k,
        _pad: 0.0,
    };
    let params_buffer = buffer_init(
        ctx,
        "volume params",
        bytemuck::bytes_of(&params),
        wgpu::BufferUsages::UNIFORM,
    );
    let inputs = gbuf.lighting_inputs();
    let volume_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("volume bind group"),
        layout: &passes.volume_layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: params_buffer.as_entire_binding(),
            },
            tex(1, &inputs[0]),
            tex(2, &inputs[1]),
            tex(3, &inputs[2]),
            tex(4, &inputs[3]),
        ],
    });
    let target = |label, width, height| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
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
        })
    };
    let low = target("indirect (subsampled)", lw, lh);
    let low_view = low.create_view(&Default::default());
    let ico = icosahedron();
    let ico_buffer = buffer_init(
        ctx,
        "icosahedron",
        bytemuck::cast_slice(&ico),
        wgpu::BufferUsages::VERTEX,
    );
    // Small volumes first (quads), the rest after (icosahedra): one buffer, two draws.
    let (ordered, quads) = partition(settings.volume_shape, &photons, &scene.camera, k, radius);
    out.stats.volume_quads = quads as u64;
    let photon_buffer = buffer_init(
        ctx,
        "photons",
        bytemuck::cast_slice(&ordered),
        wgpu::BufferUsages::VERTEX,
    );
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("photon volumes"),
    });
    gp.record(&mut encoder, &gbuf, &gbuffer_group, 0, geometry, None);
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("volume pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &low_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &volume_group, &[]);
        let (n, quads) = (ordered.len() as u32, quads as u32);
        if quads > 0 {
            pass.set_pipeline(&passes.volume_quad);
            pass.set_vertex_buffer(0, photon_buffer.slice(..));
            pass.draw(0..4, 0..quads);
        }
        if quads < n {
            pass.set_pipeline(&passes.volume);
            pass.set_vertex_buffer(0, ico_buffer.slice(..));
            pass.set_vertex_buffer(1, photon_buffer.slice(..));
            pass.draw(0..ico.len() as u32, quads..n);
        }
    }
    ctx.queue.submit([encoder.finish()]);
    ctx.wait()?;
    stage(out, "photon volumes", t);

    // Joint bilateral upsampling.
    let result = if k > 1 {
        let t = Instant::now();
        let full = target("indirect", w, h);
        let full_view = full.create_view(&Default::default());
        let up = UpsampleParamsRaw {
            eye: scene.camera.position.into(),
            subsample: k,
        };
        let up_buffer = buffer_init(
            ctx,
            "upsample params",
            bytemuck::bytes_of(&up),
            wgpu::BufferUsages::UNIFORM,
        );
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("upsample bind group"),
            layout: &passes.upsample_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: up_buffer.as_entire_binding(),
                },
                tex(1, &inputs[0]),
                tex(2, &inputs[1]),
                tex(3, &low_view),
            ],
        });
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("upsample"),
        });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("upsample pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &full_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&passes.upsample);
            pass.set_bind_group(0, &group, &[]);
            pass.draw(0..3, 0..1);
        }
        ctx.queue.submit([encoder.finish()]);
        ctx.wait()?;
        stage(out, "upsample", t);
        full
    } else {
        low
    };
    let t = Instant::now();
    let indirect = super::read_texture(ctx, &result)?;
    let mut indirect_image = Image::new(w, h);
    for (dst, v) in indirect_image.pixels.iter_mut().zip(&indirect) {
        *dst = v.truncate();
    }
    for (px, v) in out.radiance.pixels.iter_mut().zip(&indirect_image.pixels) {
        *px += *v;
    }
    out.aovs.push(("indirect".into(), indirect_image));
    out.aovs
        .push(("photons".into(), photon_hits(scene, out, &photons)));
    stage(out, "readback indirect", t);
    progress.update("photon volumes", 1.0);
    Ok(())
}

/// Where the stored photons land, as seen from the camera: per pixel, the number of visible
/// photons of bounce 1 (green) and of later bounces (red).
fn photon_hits(scene: &Scene, out: &RenderOutput, photons: &[Photon]) -> Image {
    let cam = &scene.camera;
    let mut img = Image::new(cam.width, cam.height);
    for p in photons {
        let pos = p.position();
        let Some((x, y, _)) = cam.project(pos) else {
            continue;
        };
        let i = y as usize * cam.width as usize + x as usize;
        // Visible if the surface seen through the pixel is where the photon is.
        let seen = out.position.pixels[i];
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
