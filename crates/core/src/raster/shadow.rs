//! Shadow maps: one perspective view per spot light, a cube (six 90°+ faces) per point
//! light, all as layers of one `Depth32Float` 2D array. The lighting pass picks the layer and
//! projects with the same matrices, so rendering and lookup agree by construction.
//! Acne is fought twice: slope-scaled depth bias when rendering, and a normal offset of
//! about one texel at lookup (`direct.wgsl`); edges are softened by PCF there.

use crate::gpu::raw::{LightRaw, ViewRaw};
use crate::gpu::shaders;
use crate::scene::{Light, Scene};
use glam::{Mat4, Vec3};

pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Bias in depth units (scaled by the format's resolution) and per unit depth slope.
const DEPTH_BIAS: wgpu::DepthBiasState = wgpu::DepthBiasState {
    constant: 4,
    slope_scale: 2.0,
    clamp: 0.0,
};

/// Extra field of view, in shadow texels on each side, so PCF taps near a view's border
/// stay inside it.
const MARGIN_TEXELS: f32 = 8.0;

/// Cube faces in layer order: forward and up vectors.
pub(crate) const CUBE_FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::Y),
    (Vec3::NEG_X, Vec3::Y),
    (Vec3::Y, Vec3::Z),
    (Vec3::NEG_Y, Vec3::Z),
    (Vec3::Z, Vec3::Y),
    (Vec3::NEG_Z, Vec3::Y),
];

/// The shadow views of a scene's lights and the lights' GPU records pointing at them.
pub struct ShadowViews {
    pub lights: Vec<LightRaw>,
    /// World -> clip per shadow-map layer.
    pub matrices: Vec<Mat4>,
}

impl ShadowViews {
    pub fn new(scene: &Scene, size: u32) -> Self {
        let (lo, hi) = bounds(scene);
        let mut lights = Vec::with_capacity(scene.lights.len());
        let mut matrices = Vec::new();
        for light in &scene.lights {
            let mut raw = light.to_raw();
            let p = light.position();
            // Depth range: everything in the scene's bounding box.
            let far = corners(lo, hi)
                .map(|c| (c - p).length())
                .into_iter()
                .fold(0.0f32, f32::max)
                * 1.01
                + 1e-3;
            let near = (far * 1e-3).max(1e-5);
            let grow = 1.0 + 2.0 * MARGIN_TEXELS / size as f32;
            raw.first_layer = matrices.len() as u32;
            let tan_half = match *light {
                Light::Point { .. } => {
                    let t = grow;
                    for (forward, up) in CUBE_FACES {
                        matrices.push(perspective(t, near, far) * super::look_to(p, forward, up));
                    }
                    t
                }
                Light::Spot {
                    direction,
                    cos_outer,
                    ..
                } => {
                    let t = (cos_outer.acos().tan() * grow).max(1e-3);
                    let up = if direction.y.abs() < 0.99 {
                        Vec3::Y
                    } else {
                        Vec3::X
                    };
                    matrices.push(perspective(t, near, far) * super::look_to(p, direction, up));
                    t
                }
            };
            raw.layers = matrices.len() as u32 - raw.first_layer;
            raw.texel_scale = 2.0 * tan_half / size as f32;
            lights.push(raw);
        }
        ShadowViews { lights, matrices }
    }
}

pub(crate) fn perspective(tan_half: f32, near: f32, far: f32) -> Mat4 {
    super::perspective(2.0 * tan_half.atan(), 1.0, near, far)
}

/// A `layers`-deep array of `size`² shadow maps: the texture's views per layer (render
/// targets) and over the whole array (for lookups).
pub fn layered_maps(
    device: &wgpu::Device,
    label: &str,
    size: u32,
    layers: u32,
) -> (Vec<wgpu::TextureView>, wgpu::TextureView) {
    let maps = crate::gpu::create_texture(
        device,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: size,
                height: size,
                depth_or_array_layers: layers,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
    );
    let layer_views = (0..layers)
        .map(|i| {
            maps.create_view(&wgpu::TextureViewDescriptor {
                label: Some(label),
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: i,
                array_layer_count: Some(1),
                ..Default::default()
            })
        })
        .collect();
    let array = maps.create_view(&wgpu::TextureViewDescriptor {
        label: Some(label),
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    (layer_views, array)
}

/// Axis-aligned bounds of the scene's vertices.
pub fn bounds(scene: &Scene) -> (Vec3, Vec3) {
    scene.positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

pub(crate) fn corners(lo: Vec3, hi: Vec3) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// Pipeline of the shadow pass (depth only).
pub struct ShadowPass {
    pub pipeline: wgpu::RenderPipeline,
    /// For scenes with alpha-masked materials: discards cut-out fragments (group 1: the
    /// textures).
    pub masked: wgpu::RenderPipeline,
    /// Group 0: the layer's view (uniform, dynamic offset).
    pub layout: wgpu::BindGroupLayout,
}

impl ShadowPass {
    pub fn new(device: &wgpu::Device, textures: &wgpu::BindGroupLayout) -> Self {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadow bind group layout"),
            entries: &[super::view_entry(0)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shadow pipeline layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = shaders::module(device, "shadow shader", &[shaders::COMMON, shaders::SHADOW]);
        let masked_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("masked shadow pipeline layout"),
            bind_group_layouts: &[Some(&layout), Some(textures)],
            immediate_size: 0,
        });
        let masked_module = shaders::module(
            device,
            "masked shadow shader",
            &[shaders::COMMON, shaders::TEXTURE, shaders::SHADOW_MASKED],
        );
        let attributes = super::gbuffer::VERTEX_ATTRIBUTES;
        let masked_attributes = [attributes[0], attributes[3], attributes[4]];
        let masked = crate::gpu::create_render_pipeline(
            device,
            &wgpu::RenderPipelineDescriptor {
                label: Some("masked shadow pipeline"),
                layout: Some(&masked_layout),
                vertex: wgpu::VertexState {
                    module: &masked_module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        attributes: &masked_attributes,
                        ..super::gbuffer::vertex_layout()
                    })],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: Default::default(),
                    bias: DEPTH_BIAS,
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &masked_module,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[],
                }),
                multiview_mask: None,
                cache: None,
            },
        );
        let pipeline = crate::gpu::create_render_pipeline(
            device,
            &wgpu::RenderPipelineDescriptor {
                label: Some("shadow pipeline"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        attributes: &super::gbuffer::VERTEX_ATTRIBUTES[..1],
                        ..super::gbuffer::vertex_layout()
                    })],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: Default::default(),
                    bias: DEPTH_BIAS,
                }),
                multisample: Default::default(),
                fragment: None,
                multiview_mask: None,
                cache: None,
            },
        );
        ShadowPass {
            pipeline,
            masked,
            layout,
        }
    }

    /// The views to render, one per layer, for the view uniform buffer.
    pub fn views(views: &ShadowViews) -> Vec<ViewRaw> {
        views
            .matrices
            .iter()
            .map(|m| ViewRaw::new(*m, Vec3::ZERO, 1.0))
            .collect()
    }

    /// Records one layer's pass.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        layer: &wgpu::TextureView,
        bind_group: &wgpu::BindGroup,
        view_offset: u32,
        geometry: &super::Geometry,
        masks: Option<&wgpu::BindGroup>,
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow pass"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: layer,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        match masks {
            Some(textures) => {
                pass.set_pipeline(&self.masked);
                pass.set_bind_group(1, textures, &[]);
            }
            None => pass.set_pipeline(&self.pipeline),
        }
        pass.set_bind_group(0, bind_group, &[view_offset]);
        pass.set_vertex_buffer(0, geometry.vertices.slice(..));
        pass.draw(0..geometry.count, 0..1);
    }
}
