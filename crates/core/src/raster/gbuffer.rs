//! The eye G-buffer pass.
//!
//! Targets and why those formats:
//! - `position` `Rgba32Float`: world position (w = coverage). Shadow-map lookups and light
//!   vectors need it to well under a shadow texel; `f16` would quantize 2 m to ~1 mm steps
//!   and bring back shadow acne.
//! - `normals` `Rgba32Float`: octahedral shading normal (xy) and geometric normal (zw).
//!   The geometric normal decides which side of a surface is lit, as in the path tracer.
//! - `diffuse` and `specular` `Rgba16Float`: material colours with roughness / Fresnel flag.
//!   `f16` keeps 11 significant bits (0.05% relative) where 8-bit unorm would be off by 2.6%
//!   on a reflectance of 0.065 (the Cornell red wall's green channel).
//! - `albedo` `Rgba32Float`: the albedo AOV, read back as is.
//! - `emission` `Rgba32Float`: the radiance the surface emits towards the viewer (its
//!   material's `emission`, textured, on a face that emits), which the direct light adds;
//!   emission may exceed `f16`'s range.
//! - depth `Depth32Float`: visibility only; view depth is derived from `position`.

use super::wgsl;
use crate::gpu::pipeline::{bind_group_layout, pipeline_layout, RenderSpec};
use crate::gpu::raw::{InstanceRaw, VertexRaw};
use crate::gpu::shaders;

pub const POSITION: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub const NORMALS: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub const MATERIAL: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub const ALBEDO: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub const EMISSION: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The depth a G-buffer pass starts from (the far plane), which the edge mask writes at the
/// pixels it opens (`edge_mask.wgsl`).
pub const CLEAR_DEPTH: f32 = 1.0;

/// The G-buffer's colour targets in location order, with their labels.
const TARGETS: [(&str, wgpu::TextureFormat); 6] = [
    ("gbuffer position", POSITION),
    ("gbuffer normals", NORMALS),
    ("gbuffer diffuse", MATERIAL),
    ("gbuffer specular", MATERIAL),
    ("gbuffer albedo", ALBEDO),
    ("gbuffer emission", EMISSION),
];

/// Vertex layout of [`VertexRaw`] (buffer slot 0, per vertex), shared with the shadow pass
/// (which reads location 0 only, or 0, 3, 4 with alpha masks).
pub const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 6] = wgpu::vertex_attr_array![
    0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Uint32, 4 => Float32x2, 5 => Float32x4
];

pub fn vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<VertexRaw>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &VERTEX_ATTRIBUTES,
    }
}

/// Instance layout of [`InstanceRaw`] (buffer slot 1, per instance): object -> world columns
/// (6..9), normal-matrix columns (10..12), material (13). The shadow pass reads 6..9 (and 13
/// with alpha masks).
pub const INSTANCE_ATTRIBUTES: [wgpu::VertexAttribute; 8] = wgpu::vertex_attr_array![
    6 => Float32x4, 7 => Float32x4, 8 => Float32x4, 9 => Float32x4,
    10 => Float32x4, 11 => Float32x4, 12 => Float32x4, 13 => Uint32
];

pub fn instance_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<InstanceRaw>() as u64,
        step_mode: wgpu::VertexStepMode::Instance,
        attributes: &INSTANCE_ATTRIBUTES,
    }
}

/// The G-buffer textures for one image size.
pub struct GBuffer {
    pub textures: Vec<wgpu::Texture>,
    pub views: Vec<wgpu::TextureView>,
    pub depth: wgpu::TextureView,
}

impl GBuffer {
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        let size = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        let make = |label: &str, format, usage| {
            crate::gpu::texture_array(device, label, size, format, usage)
        };
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let textures: Vec<_> = TARGETS
            .iter()
            .map(|(label, format)| make(label, *format, usage))
            .collect();
        let views = textures
            .iter()
            .map(|t| t.create_view(&Default::default()))
            .collect();
        let depth = make(
            "gbuffer depth",
            DEPTH,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        )
        .create_view(&Default::default());
        GBuffer {
            textures,
            views,
            depth,
        }
    }

    /// Views of the targets the lighting passes read: position, normals, diffuse, specular.
    pub fn lighting_inputs(&self) -> &[wgpu::TextureView] {
        &self.views[..4]
    }

    /// The view of the emission target (read by the direct light).
    pub fn emission(&self) -> &wgpu::TextureView {
        &self.views[5]
    }
}

/// The pipelines of a pass that rasterizes the scene: one per texture
/// [`Variant`](super::textures::Variant) (its fragment entry point), the scene's vertices
/// in (`vs_main`), `targets` out, with a depth test (`Less`, writing) or, without
/// `depth_test`, every fragment kept.
pub fn scene_pipelines(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    targets: &[Option<wgpu::ColorTargetState>],
    depth_test: bool,
) -> Vec<wgpu::RenderPipeline> {
    let depth = if depth_test {
        (true, wgpu::CompareFunction::Less)
    } else {
        (false, wgpu::CompareFunction::Always)
    };
    let buffers = [Some(vertex_layout()), Some(instance_layout())];
    let pipeline = |entry: &str| {
        RenderSpec {
            buffers: &buffers,
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH,
                depth_write_enabled: Some(depth.0),
                depth_compare: Some(depth.1),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            targets,
            ..RenderSpec::new(label, layout, module, "vs_main", Some(entry))
        }
        .create(device)
    };
    super::textures::Variant::ALL
        .iter()
        .map(|v| pipeline(v.entry_point()))
        .collect()
}

/// Pipeline and bind group layout of the G-buffer pass.
pub struct GBufferPass {
    /// One per [`super::textures::Variant`], in `Variant::ALL` order.
    pub pipelines: Vec<wgpu::RenderPipeline>,
    /// Group 0: the view (uniform, dynamic offset) and the materials (storage).
    pub layout: wgpu::BindGroupLayout,
}

impl GBufferPass {
    pub fn new(device: &wgpu::Device, textures: &wgpu::BindGroupLayout) -> Self {
        let layout = bind_group_layout(
            device,
            "gbuffer bind group layout",
            &[
                super::view_entry(0),
                super::storage_entry(1, wgpu::ShaderStages::FRAGMENT),
            ],
        );
        let pipeline_layout =
            pipeline_layout(device, "gbuffer pipeline layout", &[&layout, textures]);
        let module = shaders::module(
            device,
            "gbuffer shader",
            &[
                shaders::COMMON,
                shaders::BSDF,
                shaders::TEXTURE,
                shaders::SCENE_VERTEX,
                wgsl::GBUFFER,
            ],
        );
        let targets: Vec<_> = TARGETS
            .iter()
            .map(|(_, f)| Some(wgpu::ColorTargetState::from(*f)))
            .collect();
        let pipelines = scene_pipelines(
            device,
            "gbuffer pipeline",
            &pipeline_layout,
            &module,
            &targets,
            true,
        );
        GBufferPass { pipelines, layout }
    }

    /// Records the pass: clears the G-buffer and draws the geometry seen from the view at
    /// `view_offset` in the bind group's view buffer (`draws`, culled to it; all with `None`).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &GBuffer,
        bind_group: &wgpu::BindGroup,
        view_offset: u32,
        draws: (&super::Geometry, Option<&[super::Draw]>),
        textures: (&wgpu::BindGroup, super::textures::Variant),
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let depth = wgpu::LoadOp::Clear(CLEAR_DEPTH);
        let pass = (bind_group, view_offset, depth);
        self.record_over(encoder, target, pass, draws, textures, timestamps);
    }

    /// As [`Self::record`], with the depth buffer's start given: `LoadOp::Load` keeps the
    /// depth a mask pass left (`super::edges::EdgePass::record_mask`: 0 where no fragment
    /// may land, so the fragment stage runs only at the pixels the mask opened).
    pub fn record_over(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &GBuffer,
        (bind_group, view_offset, depth): (&wgpu::BindGroup, u32, wgpu::LoadOp<f32>),
        (geometry, draws): (&super::Geometry, Option<&[super::Draw]>),
        textures: (&wgpu::BindGroup, super::textures::Variant),
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let clear = wgpu::Operations {
            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
            store: wgpu::StoreOp::Store,
        };
        let attachments: Vec<_> = target
            .views
            .iter()
            .map(|view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: clear,
                })
            })
            .collect();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer pass"),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &target.depth,
                depth_ops: Some(wgpu::Operations {
                    load: depth,
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipelines[textures.1 as usize]);
        pass.set_bind_group(0, bind_group, &[view_offset]);
        pass.set_bind_group(1, textures.0, &[]);
        geometry.draw(&mut pass, draws);
    }
}

impl crate::gpu::Pipelines for GBufferPass {
    fn create(ctx: &crate::gpu::GpuContext) -> Self {
        GBufferPass::new(
            &ctx.device,
            &super::textures::TexturesLayout::get(ctx).layout,
        )
    }
}
