//! Deferred direct lighting: a full-screen pass over the G-buffer that evaluates the uber
//! BSDF for every light with PCF shadow-map visibility, either adding one weighted sub-pixel
//! sample into an `Rgba32Float` accumulation target (additive blending; needs
//! `FLOAT32_BLENDABLE`) or writing the pixel-centre sample (edge-adaptive supersampling,
//! [`super::edges`]). The layouts are visible to compute too: the edge passes share them.
//!
//! Besides the scene's lights (point, spot, directional with an orthographic shadow map), it
//! shades the sampled lights of [`SampledLightRaw`] (points drawn on the emitters, directions
//! drawn from the sky, each with its shadow layers in a second, smaller array of maps), the
//! emission the G-buffer saw and the environment behind uncovered samples; the formulas and
//! their bias are in `shaders/common/direct_shade.wgsl`.

use super::direct_variant::{DirectVariant, VariantCache};
use super::wgsl;
use crate::gpu::layout::{
    comparison_sampler_entry, depth_array_entry, texture_entry, uniform_entry_sized,
};
use crate::gpu::shaders;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Texels per sampled light in the records texture (`SAMPLE_TEXELS` in WGSL).
pub const SAMPLE_TEXELS: u32 = 4;

/// A sampled light of the direct pass, four `Rgba32Float` texels a row of the records
/// texture: a point on the emitters (an oriented point light with a cosine lobe and a cube
/// of six shadow layers) or a direction of the sky (a distant light with one orthographic
/// layer). Layers index the sampled lights' own array of maps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SampledLightRaw {
    Point {
        position: Vec3,
        first_layer: u32,
        normal: Vec3,
        /// World size of a shadow texel at unit distance.
        texel_scale: f32,
        /// Intensity along the normal (W/sr).
        intensity: Vec3,
        /// Radius² of the disc of the area the point stands for (the near-field bound).
        disc_r2: f32,
        two_sided: bool,
    },
    Sky {
        /// Unit direction towards the sky.
        towards: Vec3,
        layer: u32,
        /// L(ω)/(n·p(ω)) (W/m²).
        irradiance: Vec3,
        /// World size of a shadow texel.
        texel: f32,
        /// World depth of the view (depth 0 → 1) and tan α of the cone of directions the
        /// record stands for (sky_cone.wgsl).
        depth: f32,
        tan_cone: f32,
    },
}

impl SampledLightRaw {
    /// The record's texels (integers as float values).
    pub fn texels(&self) -> [[f32; 4]; SAMPLE_TEXELS as usize] {
        let v = |a: Vec3, w: f32| [a.x, a.y, a.z, w];
        match *self {
            SampledLightRaw::Point {
                position,
                first_layer,
                normal,
                texel_scale,
                intensity,
                disc_r2,
                two_sided,
            } => [
                v(position, first_layer as f32),
                v(normal, texel_scale),
                v(intensity, disc_r2),
                [two_sided as u32 as f32, 0.0, 0.0, 0.0],
            ],
            SampledLightRaw::Sky {
                towards,
                layer,
                irradiance,
                texel,
                depth,
                tan_cone,
            } => [
                v(towards, layer as f32),
                v(irradiance, texel),
                [depth, tan_cone, texel, 0.0],
                [0.0; 4],
            ],
        }
    }
}

/// `DirectParams` of `direct_shade.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct DirectParamsRaw {
    /// Points drawn on the emitters (the first records).
    pub area_count: u32,
    /// Directions drawn from the sky (the records after them).
    pub sky_count: u32,
    /// 1: uncovered samples see the environment.
    pub background: u32,
    /// 1: the diffuse light of the sky and of the emitter polygons by the ratio estimator
    /// (0: the plain sums over the samples, unbiased: progressive passes).
    pub ratio: u32,
    /// (cos, sin) of the environment's rotation about +y.
    pub env_cos: f32,
    pub env_sin: f32,
    /// Emitting polygons in the polygons texture (0: the emitters' light is sampled only).
    pub polygons: u32,
    /// The groups (emitting objects) the polygons form, at most [`MAX_GROUPS`].
    pub groups: u32,
    /// Nodes of the per-pixel emitter tree (`scene::emitters::PixelTree`; its triangles
    /// follow them).
    pub tree_nodes: u32,
    /// Its triangles (0: no tree; the emitters of no group are the frame's points alone).
    pub tree_triangles: u32,
    /// Light samples per shading point drawn from the tree (with `ratio` only).
    pub pixel_samples: u32,
    /// Seed of the per-pixel samples (the frame's draw).
    pub seed: u32,
    /// Per group its points [x, y) (the first records, group by group) and its polygons
    /// [z, w).
    pub group_ranges: [[u32; 4]; MAX_GROUPS],
}

/// Texels per emitting polygon (a triangle or a convex quad, `scene::EmitterPolygon`) in
/// the polygons texture: three corners (w of the first: 1 when two-sided; of the second: 1
/// for a quad; of the third: `EmitterPolygon::in_plane_bound`), the radiance, and a quad's
/// fourth corner.
pub const POLYGON_TEXELS: u32 = 5;

/// A round emitter's row of the polygons texture (`round_lights.wgsl`): its centre (w: 1
/// when two-sided), a flat disc's normal (zero for a sphere) with the flag 2 in w,
/// (radius, corners of the polygon that stands for its disc, that polygon's radius over
/// the disc's), the radiance, and the cosine and sine of the angle between the polygon's
/// corners.
pub fn round_texels(
    r: crate::scene::emitters::round::Round,
    two_sided: f32,
    radiance: Vec3,
) -> [[f32; 4]; POLYGON_TEXELS as usize] {
    use crate::scene::emitters::round::{polygon_scale, EDGES};
    let step = std::f32::consts::TAU / EDGES as f32;
    [
        r.centre.extend(two_sided).to_array(),
        r.normal.unwrap_or(Vec3::ZERO).extend(2.0).to_array(),
        [r.radius, EDGES as f32, polygon_scale(), 0.0],
        radiance.extend(0.0).to_array(),
        [step.cos(), step.sin(), 0.0, 0.0],
    ]
}

/// Most emitting triangles whose unshadowed diffuse light the direct pass sums in closed
/// form per pixel (beyond, their light is sampled only).
pub const MAX_POLYGONS: usize = 64;

/// Entries (nodes or triangles) per row of the emitter tree's texture (`TREE_ROW` of
/// `emitter_tree.wgsl`).
pub const TREE_ROW: u32 = 256;

/// Most polygon groups (emitting objects), each with its own visibility ratio (`MAX_GROUPS`
/// of `direct_shade.wgsl`).
pub const MAX_GROUPS: usize = 8;

/// The accumulation target: radiance·weight in rgb, the sum of weights in alpha.
pub const ACCUM: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// A variant's pipelines: (adds one weighted sub-pixel sample, writes the pixel-centre
/// sample with weight 1).
type Pipelines = (wgpu::RenderPipeline, wgpu::RenderPipeline);

pub struct DirectPass {
    device: wgpu::Device,
    module: wgpu::ShaderModule,
    pipeline_layout: wgpu::PipelineLayout,
    /// Per [`DirectVariant`], compiled on first use.
    variants: VariantCache<Pipelines>,
    /// Group 0: view, lights, shadow matrices, shadow maps, comparison sampler, the
    /// penumbra taps per axis of the pixel-centre pass ([`penumbra_taps`]), the sampled
    /// lights' records, shadow matrices (a texture) and maps, the environment's radiance and
    /// irradiance tables, the [`DirectParamsRaw`], the emitting polygons, the emitter tree
    /// and the LTC table.
    pub scene_layout: wgpu::BindGroupLayout,
    /// Group 1: the G-buffer's position, normals, diffuse, specular and emission textures,
    /// and the materials' exact models (`exact_models`).
    pub gbuffer_layout: wgpu::BindGroupLayout,
    pub shadow_sampler: wgpu::Sampler,
    /// The LTC table (group 0, binding 14; `raster::ltc`), uploaded once per device and
    /// read only by the pipelines of variants with `ltc`.
    pub ltc_table: wgpu::TextureView,
}

/// Visibility taps per axis of the pixel-centre pass in shadow penumbrae: the grid of `spp`
/// sub-pixel samples (its side rounded), 1 for a single sample.
pub fn penumbra_taps(spp: u32) -> u32 {
    ((spp as f64).sqrt().round() as u32).max(1)
}

impl DirectPass {
    pub fn new(ctx: &crate::gpu::GpuContext) -> Self {
        let device = &ctx.device;
        let frag = wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let mut view = super::view_entry(0);
        view.visibility |= wgpu::ShaderStages::COMPUTE;
        let scene_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("direct scene bind group layout"),
            entries: &[
                view,
                super::storage_entry(1, frag),
                super::storage_entry(2, frag),
                depth_array_entry(3, frag),
                comparison_sampler_entry(4, frag),
                uniform_entry_sized(5, frag, false, 16),
                texture_entry(6, frag),
                texture_entry(7, frag),
                depth_array_entry(8, frag),
                texture_entry(9, frag),
                texture_entry(10, frag),
                texture_entry(12, frag),
                texture_entry(13, frag),
                texture_entry(14, frag),
                wgpu::BindGroupLayoutEntry {
                    binding: 11,
                    visibility: frag,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(
                            std::mem::size_of::<DirectParamsRaw>() as u64,
                        ),
                    },
                    count: None,
                },
            ],
        });
        let texture = |binding| texture_entry(binding, frag);
        let gbuffer_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("direct gbuffer bind group layout"),
            entries: &[
                texture(0),
                texture(1),
                texture(2),
                texture(3),
                texture(4),
                super::storage_entry(5, frag),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("direct pipeline layout"),
            bind_group_layouts: &[Some(&scene_layout), Some(&gbuffer_layout)],
            immediate_size: 0,
        });
        let module = shaders::module(
            device,
            "direct shader",
            &[
                &[shaders::COMMON, shaders::BSDF][..],
                &wgsl::DIRECT_SHADING,
                &[shaders::FULLSCREEN, wgsl::DIRECT],
            ]
            .concat(),
        );
        let shadow_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow comparison sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        DirectPass {
            device: device.clone(),
            module,
            pipeline_layout,
            variants: VariantCache::default(),
            scene_layout,
            gbuffer_layout,
            shadow_sampler,
            ltc_table: super::ltc::texture(ctx).create_view(&Default::default()),
        }
    }

    /// The pipelines of `variant`, compiled the first time.
    fn pipelines(&self, variant: DirectVariant) -> Pipelines {
        self.variants.get(variant, |v| {
            let add = wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            };
            let blend = wgpu::BlendState {
                color: add,
                alpha: add,
            };
            let constants = v.constants();
            let pipeline = |entry: &str, blend: Option<wgpu::BlendState>| {
                let target = wgpu::ColorTargetState {
                    format: ACCUM,
                    blend,
                    write_mask: wgpu::ColorWrites::ALL,
                };
                let compilation_options = wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    ..Default::default()
                };
                crate::gpu::create_fullscreen_pipeline_with(
                    &self.device,
                    entry,
                    &self.pipeline_layout,
                    &self.module,
                    (entry, compilation_options),
                    target,
                )
            };
            (
                pipeline("fs_main", Some(blend)),
                pipeline("fs_centre", None),
            )
        })
    }

    /// Records the pass, adding into `accum` (cleared first when `clear`), or writing the
    /// pixel-centre sample when `centre`, by the pipelines of `variant` (which must cover
    /// the scene's lights). The bind groups are those of `scene_layout` and
    /// `gbuffer_layout`.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        accum: &wgpu::TextureView,
        clear: bool,
        centre: bool,
        [scene_group, gbuffer_group]: [&wgpu::BindGroup; 2],
        (view_offset, variant): (u32, DirectVariant),
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let load = if clear {
            wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
        } else {
            wgpu::LoadOp::Load
        };
        let (add, write) = self.pipelines(variant);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("direct light pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: accum,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(if centre { &write } else { &add });
        pass.set_bind_group(0, scene_group, &[view_offset]);
        pass.set_bind_group(1, gbuffer_group, &[]);
        pass.draw(0..3, 0..1);
    }
}

impl crate::gpu::Pipelines for DirectPass {
    fn create(ctx: &crate::gpu::GpuContext) -> Self {
        DirectPass::new(ctx)
    }
}
