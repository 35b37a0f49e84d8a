//! The emitter splat pass: adds the light of emitters smaller than a pixel
//! (`raster::subpixel`) into the direct light's accumulation, depth-tested against the
//! centre G-buffer (`emitter_splat.wgsl`). Recorded only for a view that has such emitters.

use super::direct::{DirectPass, ACCUM};
use super::subpixel::Splat;
use super::wgsl;
use crate::gpu::layout::{buffer, buffer_init};
use crate::gpu::pipeline::{additive_target, bind_group_layout, pipeline_layout, RenderSpec};
use crate::gpu::{self, shaders, GpuContext, Pipelines};
use crate::scene::Scene;

/// `SplatParams` of `emitter_splat.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ParamsRaw {
    eye: [f32; 4],
    size: [f32; 2],
    _pad: [f32; 2],
}

/// The pass's pipeline and its group 0 layout (the parameters); group 1 is the direct
/// pass's G-buffer group.
pub struct SplatPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

/// One view's splats: their vertex buffer and the parameters' group.
pub struct Splats {
    vertices: wgpu::Buffer,
    count: u32,
    group: wgpu::BindGroup,
}

impl SplatPass {
    fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = bind_group_layout(
            device,
            "emitter splat bind group layout",
            &[crate::gpu::layout::uniform_entry(0)],
        );
        let direct = DirectPass::get(ctx);
        let pipeline_layout = pipeline_layout(
            device,
            "emitter splat pipeline layout",
            &[&layout, &direct.gbuffer_layout],
        );
        let module = shaders::module(device, "emitter splat shader", &[wgsl::EMITTER_SPLAT]);
        let pipeline = RenderSpec {
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<Splat>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4],
            })],
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::PointList,
                ..Default::default()
            },
            targets: &[Some(additive_target(ACCUM))],
            ..RenderSpec::new(
                "emitter splat",
                &pipeline_layout,
                &module,
                "splat_vs",
                Some("splat_fs"),
            )
        }
        .create(device);
        SplatPass { pipeline, layout }
    }

    /// The splats of `scene`'s small emitters seen from its camera; `None` where it has
    /// none (no pass is recorded).
    pub fn splats(&self, ctx: &GpuContext, scene: &Scene, list: &[Splat]) -> Option<Splats> {
        if list.is_empty() {
            return None;
        }
        let cam = &scene.camera;
        let params = ParamsRaw {
            eye: cam.position.extend(0.0).into(),
            size: [cam.width as f32, cam.height as f32],
            _pad: [0.0; 2],
        };
        let uniform = buffer_init(
            ctx,
            "emitter splat params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM,
        );
        let vertices = buffer_init(
            ctx,
            "emitter splats",
            bytemuck::cast_slice(list),
            wgpu::BufferUsages::VERTEX,
        );
        let group = gpu::create_bind_group(
            &ctx.device,
            &wgpu::BindGroupDescriptor {
                label: Some("emitter splat bind group"),
                layout: &self.layout,
                entries: &[buffer(0, &uniform)],
            },
        );
        Some(Splats {
            vertices,
            count: list.len() as u32,
            group,
        })
    }

    /// Adds `splats` into `accum` (after the direct light is complete there), depth-tested
    /// against the centre G-buffer of `gbuffer_group` (the direct pass's group 1).
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        accum: &wgpu::TextureView,
        splats: &Splats,
        gbuffer_group: &wgpu::BindGroup,
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("emitter splat pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: accum,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &splats.group, &[]);
        pass.set_bind_group(1, gbuffer_group, &[]);
        pass.set_vertex_buffer(0, splats.vertices.slice(..));
        pass.draw(0..splats.count, 0..1);
    }
}

impl Pipelines for SplatPass {
    fn create(ctx: &GpuContext) -> Self {
        SplatPass::new(ctx)
    }
}
