//! The scene's GPU-resident data: meshes and instances, materials, textures, lights and their shadow
//! maps, the sampled lights of the direct pass ([`super::samples`]), uploaded once and then
//! only what changed.

use super::samples::{LightSamples, SampleCounts};
use crate::error::{Error, Result};
use crate::gpu::timer::Timer;
use crate::gpu::Pipelines;
use crate::gpu::{self, GpuContext};
use crate::raster::shadow::ShadowPass;
use crate::raster::textures::TexturesLayout;
use crate::raster::{self, buffer_init, shadow, Geometry, VIEW_SIZE};
use crate::scene::Scene;

/// How a frame draws its light samples: the sampled lights' seed, and for progressive passes
/// the shrinking near-field discs and a new direction within each directional light's disc.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightDraw {
    pub seed: u64,
    /// Scale of the emitter points' near-field disc radii (1; shrinking per progressive pass).
    pub disc_scale: f32,
    /// A progressive pass: directional lights cast hard shadows along a direction drawn
    /// from their disc (seeded by `seed`).
    pub progressive: bool,
}

/// The scene's GPU-resident data.
pub(crate) struct GpuScene {
    pub geometry: Geometry,
    pub materials: wgpu::Buffer,
    /// Mitsuba's exact models of the materials, per material (`raster::exact_models`).
    pub model_materials: wgpu::Buffer,
    /// Textures and material maps (group 1 of the passes that rasterize the scene).
    pub textures: raster::textures::GpuTextures,
    /// Whether any material is alpha-masked (the shadow pass then discards cut-outs).
    masked: bool,
    /// The fragment shaders the scene needs (textures, alpha masks).
    pub variant: raster::textures::Variant,
    pub lights: wgpu::Buffer,
    pub(super) shadow_matrices: wgpu::Buffer,
    shadow_views: wgpu::Buffer,
    shadow_layers: Vec<wgpu::TextureView>,
    pub(super) shadow_array: wgpu::TextureView,
    shadow_group: wgpu::BindGroup,
    /// Shadow-map layers (one per spot light, six per point light).
    pub layers: u32,
    /// The shadow maps must be rendered again (lights or geometry moved).
    pub shadows_stale: bool,
    /// World -> clip per shadow layer (CPU copies, for culling the shadow passes).
    shadow_clip: Vec<glam::Mat4>,
    /// The geometry's culling data for the eye and light-view passes (G-buffer, shadow,
    /// bounce, RSM, VPL maps): the meshes' clusters and the objects' transforms, re-read
    /// when objects move.
    pub cull: shadow::CullUnits,
    /// Points drawn on the emitters and directions drawn from the sky.
    pub samples: LightSamples,
    shadow_map_size: u32,
    /// The progressive pass whose directional-light directions the lights hold (`None`:
    /// their axes).
    lights_jitter: Option<u64>,
    /// Whether any light is directional (the direct pass's variant).
    directional: bool,
    /// What the materials need of the direct shading (the direct pass's variant).
    material_kinds: raster::direct_variant::MaterialKinds,
}

fn storage_init(ctx: &GpuContext, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    buffer_init(ctx, label, bytes, usage)
}

impl GpuScene {
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        shadow_map_size: u32,
        counts: SampleCounts,
    ) -> Result<Self> {
        let textures =
            raster::textures::GpuTextures::new(ctx, scene, &TexturesLayout::get(ctx).layout)?;
        let samples = LightSamples::new(ctx, scene, SampleCounts::of(scene, counts))?;
        let shadows = shadow::ShadowViews::new(scene, shadow_map_size, None);
        let layers = (shadows.matrices.len() as u32).max(1);
        let materials: Vec<_> = scene.materials.iter().map(|m| m.to_raw()).collect();
        let records = raster::exact_models::records(scene);
        let matrices: Vec<[f32; 16]> = shadows.matrices.iter().map(|m| m.to_cols_array()).collect();
        let shadow_views = buffer_init(
            ctx,
            "shadow views",
            bytemuck::cast_slice(&shadow::ShadowPass::views(&shadows)),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let (shadow_layers, shadow_array, _) =
            shadow::layered_maps(&ctx.device, "shadow maps", shadow_map_size, layers);
        let shadow_group =
            ShadowPass::get(ctx).view_group(&ctx.device, "shadow bind group", &shadow_views);
        let cull = shadow::CullUnits::of(scene);
        Ok(GpuScene {
            geometry: Geometry::upload(ctx, scene, &cull),
            materials: storage_init(ctx, "materials", bytemuck::cast_slice(&materials)),
            model_materials: storage_init(ctx, "model materials", bytemuck::cast_slice(&records)),
            textures,
            masked: scene.has_alpha_masks(),
            variant: raster::textures::Variant::of(scene),
            lights: storage_init(ctx, "lights", bytemuck::cast_slice(&shadows.lights)),
            shadow_matrices: storage_init(ctx, "shadow matrices", bytemuck::cast_slice(&matrices)),
            shadow_views,
            shadow_layers,
            shadow_array,
            shadow_group,
            layers,
            shadows_stale: true,
            shadow_clip: shadows.matrices,
            cull,
            samples,
            shadow_map_size,
            lights_jitter: None,
            directional: raster::direct_variant::any_directional(&shadows.lights),
            material_kinds: raster::direct_variant::MaterialKinds::of(&materials, &records),
        })
    }

    /// Whether the scene's lights still fit these shadow maps (same number of layers) and
    /// its emitters and sky the sampled lights drawn for `counts`.
    pub fn fits(&self, scene: &Scene, counts: SampleCounts) -> bool {
        let needed: u32 = scene
            .lights
            .iter()
            .map(crate::scene::light_views::shadow_layers_of)
            .sum();
        needed.max(1) == self.layers && SampleCounts::of(scene, counts) == self.samples.counts
    }

    /// Rewrites object `o`'s instance record (it moved; its mesh stays).
    pub fn write_instance(&self, ctx: &GpuContext, scene: &Scene, o: usize) {
        self.geometry.write_instance(ctx, scene, o);
    }

    pub fn write_materials(&mut self, ctx: &GpuContext, scene: &Scene) {
        let materials: Vec<_> = scene.materials.iter().map(|m| m.to_raw()).collect();
        gpu::write_buffer(
            &ctx.queue,
            "materials",
            &self.materials,
            0,
            bytemuck::cast_slice(&materials),
        );
        let records = raster::exact_models::records(scene);
        gpu::write_buffer(
            &ctx.queue,
            "model materials",
            &self.model_materials,
            0,
            bytemuck::cast_slice(&records),
        );
        self.material_kinds = raster::direct_variant::MaterialKinds::of(&materials, &records);
        self.textures.write_maps(ctx, scene);
        let masked = scene.has_alpha_masks();
        if masked || self.masked {
            // Cut-outs appeared, changed or went: the shadow maps change with them.
            self.shadows_stale = true;
        }
        // Emission may have changed (and the sampled lights' shadows with the cut-outs).
        self.samples.invalidate(true);
        self.masked = masked;
        self.variant = raster::textures::Variant::of(scene);
    }

    /// Uploads the lights and their shadow views (they depend on the scene's bounds too);
    /// with `jitter`, a progressive pass's directions of the directional lights.
    pub fn write_lights(&mut self, ctx: &GpuContext, scene: &Scene, jitter: Option<u64>) {
        let shadows = shadow::ShadowViews::new(scene, self.shadow_map_size, jitter);
        self.lights_jitter = jitter;
        self.directional = raster::direct_variant::any_directional(&shadows.lights);
        let matrices: Vec<[f32; 16]> = shadows.matrices.iter().map(|m| m.to_cols_array()).collect();
        let q = &ctx.queue;
        gpu::write_buffer(
            q,
            "lights",
            &self.lights,
            0,
            bytemuck::cast_slice(&shadows.lights),
        );
        gpu::write_buffer(
            q,
            "shadow matrices",
            &self.shadow_matrices,
            0,
            bytemuck::cast_slice(&matrices),
        );
        gpu::write_buffer(
            q,
            "shadow views",
            &self.shadow_views,
            0,
            bytemuck::cast_slice(&shadow::ShadowPass::views(&shadows)),
        );
        self.shadow_clip = shadows.matrices;
        self.shadows_stale = true;
    }

    /// The direct-light shaders for the kinds of light the scene has.
    pub fn direct_variant(&self) -> raster::direct_variant::DirectVariant {
        let c = &self.samples.counts;
        raster::direct_variant::DirectVariant {
            sampled: c.area > 0 || c.sky > 0,
            directional: self.directional,
            background: c.background,
            emission: self.material_kinds.emission,
            glossy: self.material_kinds.glossy,
            ltc: self.material_kinds.glossy && self.samples.has_polygon_groups(),
            round: self.samples.has_round_groups(),
        }
    }

    /// The lights' shadow matrices and maps (for lookups outside the direct pass).
    pub fn shadow_lookup(&self) -> (&wgpu::Buffer, &wgpu::TextureView) {
        (&self.shadow_matrices, &self.shadow_array)
    }

    /// The texture group for shadow passes of scenes with alpha masks (they discard
    /// cut-outs), `None` otherwise.
    pub fn shadow_masks(&self) -> Option<&wgpu::BindGroup> {
        self.masked.then_some(&self.textures.group)
    }

    /// The geometry moved: the objects' transforms for culling, and the sampled lights'
    /// shadows with them.
    pub fn geometry_moved(&mut self, scene: &Scene) {
        self.cull.moved(scene);
        self.samples.invalidate(true);
    }

    /// Renders the shadow maps if lights or geometry moved since they were last rendered,
    /// and draws the sampled lights of `draw` (with their shadow maps) unless drawn already.
    /// True when the direct light changed with them.
    pub fn record_shadows(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut Timer,
        scene: &Scene,
        draw: LightDraw,
    ) -> bool {
        // Progressive passes: a new direction within each directional light's disc.
        let soft_sun = scene.lights.iter().any(|l| {
            matches!(l, crate::scene::Light::Directional { cos_half_angle, .. } if *cos_half_angle < 1.0)
        });
        let jitter = (draw.progressive && soft_sun).then_some(draw.seed);
        if jitter != self.lights_jitter {
            self.write_lights(ctx, scene, jitter);
        }
        let mut changed = self.shadows_stale && !scene.lights.is_empty();
        let (seed, disc_scale, ratio) = (draw.seed, draw.disc_scale, !draw.progressive);
        changed |= self.samples.prepare(ctx, scene, seed, disc_scale, ratio);
        let masks = self.masked.then_some(&self.textures.group);
        let (geometry, cull) = (&self.geometry, &self.cull);
        self.samples
            .record_shadows(ctx, encoder, timer, geometry, cull, masks);
        if !self.shadows_stale || scene.lights.is_empty() {
            return changed;
        }
        // Each layer draws only the triangle runs that reach into its view.
        let draws = self.cull.draws(&self.shadow_clip);
        for (layer, view) in self.shadow_layers.iter().enumerate() {
            let offset = (layer as u64 * VIEW_SIZE) as u32;
            let ts = timer.pass("shadow maps");
            ShadowPass::get(ctx).record(
                encoder,
                view,
                &self.shadow_group,
                offset,
                &self.geometry,
                draws.get(layer).map(|d| d.as_slice()),
                self.masked.then_some(&self.textures.group),
                ts,
            );
        }
        self.shadows_stale = false;
        changed
    }
}

/// Fails with a setting or GPU error when the image, the shadow maps or their layers exceed
/// the adapter's limits.
pub(crate) fn check_limits(
    ctx: &GpuContext,
    scene: &Scene,
    shadow_map_size: u32,
    layers: u32,
) -> Result<()> {
    let l = ctx.device.limits();
    let max = l.max_texture_dimension_2d;
    if scene.camera.width > max || scene.camera.height > max {
        return Err(Error::setting(
            "width",
            format!("the GPU allows images up to {max} pixels a side"),
        ));
    }
    if shadow_map_size > max {
        return Err(Error::setting(
            "shadow_map_size",
            format!("the GPU allows at most {max}"),
        ));
    }
    if layers > l.max_texture_array_layers {
        return Err(Error::Gpu(format!(
            "{layers} shadow-map layers exceed the GPU's {}",
            l.max_texture_array_layers
        )));
    }
    Ok(())
}

#[cfg(test)]
#[path = "scene_tests.rs"]
mod tests;
