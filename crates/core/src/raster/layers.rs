//! Light-view render targets shared by the ISPM bounce maps and `bidir`'s reflective shadow
//! maps: per layer (a spot light's view, or one cube face of a point light) a pass that
//! writes several `Rgba32Float` targets of one texture array each, and the copies of all
//! layers into mappable buffers in the same submission, read back after it.

use super::shadow::CullUnits;
use super::{gbuffer, Geometry};
use crate::error::{Error, Result};
use crate::gpu::timer::Timer;
use crate::gpu::{self, GpuContext};
use crate::scene::light_views::{check_layer_memory, LayerKind, LightView};
use glam::{Mat4, Vec4};

/// Format of every layer target.
pub const TARGET: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub struct LayerTargets {
    pub max_res: u32,
    pub n_layers: u32,
    /// Bytes per row of the readback copies.
    row: u32,
    targets: Vec<wgpu::Texture>,
    /// Per layer: the target views and the depth view.
    layer_views: Vec<(Vec<wgpu::TextureView>, wgpu::TextureView)>,
    staging: Vec<wgpu::Buffer>,
}

impl LayerTargets {
    /// Targets for `layers` (not empty), or a typed error when the GPU cannot hold them.
    pub fn new(ctx: &GpuContext, layers: &[LightView], kind: &LayerKind) -> Result<Self> {
        let device = &ctx.device;
        let max_res = layers.iter().map(|l| l.res).max().unwrap_or(1);
        let limits = device.limits();
        let name = kind.name;
        if max_res > limits.max_texture_dimension_2d {
            return Err(Error::setting(
                kind.setting,
                format!(
                    "the {name} needs {max_res} texels a side; the GPU allows {}",
                    limits.max_texture_dimension_2d
                ),
            ));
        }
        let n_layers = layers.len() as u32;
        check_layer_memory(layers, kind)?;
        if n_layers > limits.max_texture_array_layers {
            return Err(Error::Gpu(format!(
                "{n_layers} {name} layers exceed the GPU's {}",
                limits.max_texture_array_layers
            )));
        }
        let size = wgpu::Extent3d {
            width: max_res,
            height: max_res,
            depth_or_array_layers: n_layers,
        };
        let make = |label, format, usage| gpu::texture_array(device, label, size, format, usage);
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let targets: Vec<_> = kind
            .targets
            .iter()
            .map(|label| make(label, TARGET, usage))
            .collect();
        let depth = make(name, gbuffer::DEPTH, wgpu::TextureUsages::RENDER_ATTACHMENT);
        let layer_view = |t: &wgpu::Texture, i: u32| {
            t.create_view(&wgpu::TextureViewDescriptor {
                label: Some(name),
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: i,
                array_layer_count: Some(1),
                ..Default::default()
            })
        };
        let layer_views = (0..n_layers)
            .map(|i| {
                (
                    targets.iter().map(|t| layer_view(t, i)).collect(),
                    layer_view(&depth, i),
                )
            })
            .collect();
        let row = (max_res * 16).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let staging = (0..targets.len())
            .map(|_| {
                gpu::readback_buffer(device, name, row as u64 * max_res as u64 * n_layers as u64)
            })
            .collect();
        Ok(LayerTargets {
            max_res,
            n_layers,
            row,
            targets,
            layer_views,
            staging,
        })
    }

    /// Whether these targets serve `layers`.
    pub fn fits(&self, layers: &[LightView]) -> bool {
        self.n_layers as usize == layers.len()
            && self.max_res == layers.iter().map(|l| l.res).max().unwrap_or(1)
    }

    /// Records one pass of `pipeline` per layer (bind group 0 = `group` at the layer's
    /// `view_size`-byte view, 1 = the textures), timed as `stage`, then the copies of every
    /// target, all layers, into the mappable buffers.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        stage: &'static str,
        pipeline: &wgpu::RenderPipeline,
        (group, view_size): (&wgpu::BindGroup, u64),
        textures: &wgpu::BindGroup,
        geometry: &Geometry,
        layers: &[LightView],
        cull: &CullUnits,
        timer: &mut Timer,
    ) {
        // Each layer draws only the triangles that reach into its view.
        let matrices: Vec<Mat4> = layers.iter().map(|l| l.view_proj).collect();
        let draws = cull.draws(&matrices);
        for (i, layer) in layers.iter().enumerate() {
            let (views, depth_view) = &self.layer_views[i];
            let attachments: Vec<_> = views
                .iter()
                .map(|view| Some(crate::gpu::cleared(view)))
                .collect();
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(stage),
                color_attachments: &attachments,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.pass(stage),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_viewport(0.0, 0.0, layer.res as f32, layer.res as f32, 0.0, 1.0);
            pass.set_scissor_rect(0, 0, layer.res, layer.res);
            pass.set_bind_group(0, group, &[(i as u64 * view_size) as u32]);
            pass.set_bind_group(1, textures, &[]);
            geometry.draw(&mut pass, Some(&draws[i]));
        }
        let size = wgpu::Extent3d {
            width: self.max_res,
            height: self.max_res,
            depth_or_array_layers: self.n_layers,
        };
        for (texture, buffer) in self.targets.iter().zip(&self.staging) {
            encoder.copy_texture_to_buffer(
                texture.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(self.row),
                        rows_per_image: Some(self.max_res),
                    },
                },
                size,
            );
        }
    }

    /// Maps the copies once submission `after` is done: per target, its texels, layer after
    /// layer, `max_res`² each (row padding dropped).
    pub fn read(
        &self,
        ctx: &GpuContext,
        after: Option<wgpu::SubmissionIndex>,
    ) -> Result<Vec<Vec<Vec4>>> {
        let width = self.max_res as usize * 16;
        let buffers: Vec<&wgpu::Buffer> = self.staging.iter().collect();
        // Rows copied out of the mapped buffers directly (one copy, no per-row vectors).
        ctx.read_buffers_with(&buffers, after, |_, bytes| {
            let rows = bytes.chunks_exact(self.row as usize);
            let mut out: Vec<Vec4> = Vec::with_capacity(rows.len() * self.max_res as usize);
            for r in rows {
                out.extend_from_slice(bytemuck::cast_slice::<u8, Vec4>(&r[..width]));
            }
            out
        })
    }
}
