//! The ISPM bounce maps (McGuire & Luebke 2009, section 4.2), rasterized: per light view
//! ([`crate::scene::light_views`]: one perspective view per spot light, six cube faces per
//! point light) a light-space G-buffer whose texels are the photons leaving the light. A
//! texel's power is I(ω)·A·cos³θ with the view's corrected texel area; the hits are direct
//! light and are not stored. Their first scatter (importance sampling of the uber BSDF,
//! Russian roulette, path density) is taken in the same fragment shader (`bounce.wgsl`, a
//! port of `Material::sample`); surviving texels are read back as [`PhotonRay`]s.
//!
//! The bounce maps are submitted before the direct-light frame, with the copies of their
//! targets into mappable buffers in the same submission, and mapped after it
//! ([`BounceTargets::finish`]): the readback does not stall the CPU (section 4.3).

use super::layers::{LayerTargets, TARGET};
use super::textures::{TexturesLayout, Variant};
use super::wgsl;
use super::{buffer_init, gbuffer, Geometry};
use crate::error::{Error, Result};
use crate::gpu::layout::{buffer, dynamic_buffer, storage_entry, uniform_entry_sized};
use crate::gpu::pipeline::bind_group_layout;
use crate::gpu::raw::BounceViewRaw;
use crate::gpu::timer::Timer;
use crate::gpu::{self, shaders, GpuContext, Pipelines};
use crate::photon::bounce::BounceMap;
use crate::photon::PhotonRay;
use crate::scene::light_views::{light_views, LightView, BOUNCE_MAPS};
use crate::scene::Scene;
use std::time::Instant;

const BOUNCE_VIEW_SIZE: u64 = std::mem::size_of::<BounceViewRaw>() as u64;

/// The bounce pass's pipelines (one per [`Variant`], in `Variant::ALL` order) and layout.
pub struct BouncePass {
    pipelines: Vec<wgpu::RenderPipeline>,
    layout: wgpu::BindGroupLayout,
}

impl Pipelines for BouncePass {
    fn create(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let textures = &TexturesLayout::get(ctx).layout;
        let bounce_layout = bind_group_layout(
            device,
            "bounce bind group layout",
            &[
                uniform_entry_sized(
                    0,
                    wgpu::ShaderStages::VERTEX_FRAGMENT,
                    true,
                    BOUNCE_VIEW_SIZE,
                ),
                storage_entry(1, wgpu::ShaderStages::FRAGMENT),
                storage_entry(2, wgpu::ShaderStages::FRAGMENT),
            ],
        );
        let module = shaders::module(
            device,
            "bounce shader",
            &[
                shaders::COMMON,
                shaders::BSDF,
                shaders::MODELS,
                shaders::SAMPLE,
                wgsl::EXACT_MODELS,
                shaders::TEXTURE,
                shaders::SCENE_VERTEX,
                wgsl::LIGHT_VIEW,
                wgsl::BOUNCE,
            ],
        );
        let bounce_pipeline_layout =
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("bounce pipeline layout"),
                bind_group_layouts: &[Some(&bounce_layout), Some(textures)],
                immediate_size: 0,
            });
        let targets: [_; 5] = std::array::from_fn(|_| Some(wgpu::ColorTargetState::from(TARGET)));
        let pipelines = gbuffer::scene_pipelines(
            device,
            "bounce pipeline",
            &bounce_pipeline_layout,
            &module,
            &targets,
            true,
        );

        BouncePass {
            pipelines,
            layout: bounce_layout,
        }
    }
}

/// [`BounceTargets`] on the context of `adapter`, for inspection and tests: the bounce maps
/// of `scene` for `photons` texels rendered and read back once.
pub fn render_bounce_map(
    scene: &Scene,
    adapter: Option<&str>,
    photons: u64,
    seed: u64,
) -> Result<BounceMap> {
    let ctx = gpu::context(adapter)?;
    ctx.scoped("bounce map", || {
        let cull = super::shadow::CullUnits::of(scene);
        let geometry = Geometry::upload(&ctx, scene, &cull);
        let materials: Vec<_> = scene.materials.iter().map(|m| m.to_raw()).collect();
        let materials = buffer_init(
            &ctx,
            "materials",
            bytemuck::cast_slice(&materials),
            wgpu::BufferUsages::STORAGE,
        );
        let layers = light_views(scene, photons);
        let textures =
            super::textures::GpuTextures::new(&ctx, scene, &TexturesLayout::get(&ctx).layout)?;
        let models = buffer_init(
            &ctx,
            "model materials",
            bytemuck::cast_slice(&super::exact_models::records(scene)),
            wgpu::BufferUsages::STORAGE,
        );
        let Some(targets) = BounceTargets::new(&ctx, &layers, (&materials, &models))? else {
            return Ok(BounceMap::default());
        };
        targets.write_views(&ctx, scene, &layers, seed);
        let mut timer = Timer::new(&ctx, layers.len() as u32);
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("bounce maps"),
            });
        targets.record(
            &BouncePass::get(&ctx),
            &mut encoder,
            &layers,
            &geometry,
            &cull,
            (&textures.group, Variant::of(scene)),
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
    /// Resources for `layers` (`None` when there are none: no light emits), reading the
    /// scene's `materials` and their exact `models` (`exact_models::records`).
    pub fn new(
        ctx: &GpuContext,
        layers: &[LightView],
        (materials, models): (&wgpu::Buffer, &wgpu::Buffer),
    ) -> Result<Option<Self>> {
        if layers.is_empty() {
            return Ok(None);
        }
        let passes = BouncePass::get(ctx);
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
                layout: &passes.layout,
                entries: &[
                    dynamic_buffer(0, &views, BOUNCE_VIEW_SIZE),
                    buffer(1, materials),
                    buffer(2, models),
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
        passes: &BouncePass,
        encoder: &mut wgpu::CommandEncoder,
        layers: &[LightView],
        geometry: &Geometry,
        cull: &super::shadow::CullUnits,
        textures: (&wgpu::BindGroup, Variant),
        timer: &mut Timer,
    ) {
        self.layers.record(
            encoder,
            "bounce maps",
            &passes.pipelines[textures.1 as usize],
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
