//! Reflective shadow maps (Dachsbacher & Stamminger 2005) for method `bidir`: per light the
//! views of the ISPM bounce map ([`crate::scene::light_views::light_views`]: one perspective view per spot
//! light, six cube faces per point light, resolutions split by power), each covered texel
//! holding the surface point the light's flux through it reaches (position, normals,
//! material, flux). The targets are copied into mappable buffers in the same submission and
//! read back as [`RsmTexel`]s, from which the frame draws its VPLs.

use super::layers::{LayerTargets, TARGET};
use super::wgsl;
use super::{buffer_init, gbuffer, Geometry};
use crate::error::{Error, Result};
use crate::gpu::layout::{buffer, dynamic_buffer, uniform_entry_sized};
use crate::gpu::pipeline::{bind_group_layout, pipeline_layout};
use crate::gpu::raw::BounceViewRaw;
use crate::gpu::timer::Timer;
use crate::gpu::{self, shaders, GpuContext};
use crate::scene::light_views::LayerKind;
use crate::scene::light_views::LightView;
use crate::scene::Scene;
use glam::{Vec2, Vec3};

const VIEW_SIZE: u64 = std::mem::size_of::<BounceViewRaw>() as u64;
/// position, normals, diffuse, specular, flux.
const TARGETS: usize = 5;

/// One covered RSM texel.
#[derive(Clone, Copy, Debug)]
pub struct RsmTexel {
    /// Index into `Scene::lights`.
    pub light: usize,
    pub position: Vec3,
    /// Shading and geometric normals, facing the light.
    pub ns: Vec3,
    pub ng: Vec3,
    pub diffuse: Vec3,
    pub roughness: f32,
    pub specular: Vec3,
    pub fresnel: bool,
    /// Flux through the texel (W).
    pub flux: Vec3,
}

/// The RSM pipelines (one per [`super::textures::Variant`]) and their group-0 layout.
pub struct RsmPass {
    pub pipelines: Vec<wgpu::RenderPipeline>,
    /// Group 0: the layer's view (uniform, dynamic offset) and the materials (storage).
    pub layout: wgpu::BindGroupLayout,
}

impl RsmPass {
    pub fn new(device: &wgpu::Device, textures: &wgpu::BindGroupLayout) -> Self {
        let layout = bind_group_layout(
            device,
            "rsm bind group layout",
            &[
                uniform_entry_sized(0, wgpu::ShaderStages::VERTEX_FRAGMENT, true, VIEW_SIZE),
                super::storage_entry(1, wgpu::ShaderStages::FRAGMENT),
            ],
        );
        let module = shaders::module(
            device,
            "rsm shader",
            &[
                shaders::COMMON,
                shaders::BSDF,
                shaders::TEXTURE,
                shaders::SCENE_VERTEX,
                wgsl::LIGHT_VIEW,
                wgsl::RSM,
            ],
        );
        let pipeline_layout = pipeline_layout(device, "rsm pipeline layout", &[&layout, textures]);
        let targets: [_; TARGETS] =
            std::array::from_fn(|_| Some(wgpu::ColorTargetState::from(TARGET)));
        let pipelines = gbuffer::scene_pipelines(
            device,
            "rsm pipeline",
            &pipeline_layout,
            &module,
            &targets,
            true,
        );
        RsmPass { pipelines, layout }
    }
}

/// The RSM targets of a set of layers, their views and mappable copies.
pub struct RsmTargets {
    layers: LayerTargets,
    views: wgpu::Buffer,
    group: wgpu::BindGroup,
}

/// The reflective shadow maps' five targets.
const RSMS: LayerKind = LayerKind {
    name: "reflective shadow map",
    setting: "rsm_size",
    targets: &[
        "rsm position",
        "rsm normals",
        "rsm diffuse",
        "rsm specular",
        "rsm flux",
    ],
};

impl RsmTargets {
    /// Resources for `layers` (`None` when no light emits).
    pub fn new(
        ctx: &GpuContext,
        pass: &RsmPass,
        layers: &[LightView],
        materials: &wgpu::Buffer,
    ) -> Result<Option<Self>> {
        if layers.is_empty() {
            return Ok(None);
        }
        let targets = LayerTargets::new(ctx, layers, &RSMS)?;
        let views = buffer_init(
            ctx,
            "rsm views",
            &vec![0u8; layers.len() * VIEW_SIZE as usize],
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let group = gpu::create_bind_group(
            &ctx.device,
            &wgpu::BindGroupDescriptor {
                label: Some("rsm bind group"),
                layout: &pass.layout,
                entries: &[dynamic_buffer(0, &views, VIEW_SIZE), buffer(1, materials)],
            },
        );
        Ok(Some(RsmTargets {
            layers: targets,
            views,
            group,
        }))
    }

    /// Whether these resources serve `layers`.
    pub fn fits(&self, layers: &[LightView]) -> bool {
        self.layers.fits(layers)
    }

    /// Uploads the layers' views (after lights or geometry moved).
    pub fn write_views(&self, ctx: &GpuContext, scene: &Scene, layers: &[LightView]) {
        let views: Vec<BounceViewRaw> = layers
            .iter()
            .enumerate()
            .map(|(i, l)| BounceViewRaw::new(i as u32, l, &scene.lights[l.light], 0))
            .collect();
        gpu::write_buffer(
            &ctx.queue,
            "rsm views",
            &self.views,
            0,
            bytemuck::cast_slice(&views),
        );
    }

    /// Records the RSM passes of all layers and the copies of their targets.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        pass: &RsmPass,
        encoder: &mut wgpu::CommandEncoder,
        layers: &[LightView],
        geometry: &Geometry,
        cull: &super::shadow::CullUnits,
        textures: (&wgpu::BindGroup, super::textures::Variant),
        timer: &mut Timer,
    ) {
        self.layers.record(
            encoder,
            "rsm",
            &pass.pipelines[textures.1 as usize],
            (&self.group, VIEW_SIZE),
            textures.0,
            geometry,
            layers,
            cull,
            timer,
        );
    }

    /// Maps the copies once submission `after` is done: the covered texels with flux.
    pub fn read(
        &self,
        ctx: &GpuContext,
        layers: &[LightView],
        after: Option<wgpu::SubmissionIndex>,
    ) -> Result<Vec<RsmTexel>> {
        let max_res = self.layers.max_res as usize;
        let read = self.layers.read(ctx, after)?;
        let [position, normals, diffuse, specular, flux] = &read[..] else {
            return Err(Error::Gpu("reflective shadow map readback".into()));
        };
        let mut out = Vec::new();
        for (li, layer) in layers.iter().enumerate() {
            for y in 0..layer.res as usize {
                for x in 0..layer.res as usize {
                    let i = li * max_res * max_res + y * max_res + x;
                    let phi = flux[i].truncate();
                    if position[i].w <= 0.0 || phi.max_element() <= 0.0 {
                        continue;
                    }
                    let n = normals[i];
                    out.push(RsmTexel {
                        light: layer.light,
                        position: position[i].truncate(),
                        ns: super::oct_decode(Vec2::new(n.x, n.y)),
                        ng: super::oct_decode(Vec2::new(n.z, n.w)),
                        diffuse: diffuse[i].truncate(),
                        roughness: diffuse[i].w,
                        specular: specular[i].truncate(),
                        fresnel: specular[i].w > 0.5,
                        flux: phi,
                    });
                }
            }
        }
        Ok(out)
    }
}

impl crate::gpu::Pipelines for RsmPass {
    fn create(ctx: &crate::gpu::GpuContext) -> Self {
        RsmPass::new(
            &ctx.device,
            &super::textures::TexturesLayout::get(ctx).layout,
        )
    }
}
