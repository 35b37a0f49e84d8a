//! Virtual point lights (Tokuyoshi & Ogaki 2012 §4.1): drawn from the reflective shadow
//! maps by flux, uploaded as texels, each with a cube shadow map.

use super::super::gpu::GpuScene;
use super::subpaths::Head;
use crate::error::{Error, Result};
use crate::gpu::layout::{buffer_init, VIEW_SIZE};
use crate::gpu::raw::ViewRaw;
use crate::gpu::timer::Timer;
use crate::gpu::{self, GpuContext, Pipelines};
use crate::raster::exact_models::material_word;
use crate::raster::rsm::RsmTexel;
use crate::raster::shadow::{self, ShadowPass, Tile};
use crate::raster::vpl::{cube_views, tile_matrix, tile_rect, VplRaw, FACES_A_LAYER, TILES_A_SIDE};
use crate::sampling::Rng;
use crate::scene::light_views;
use crate::scene::Scene;
use bytemuck::Zeroable;
use glam::{Mat4, Vec3};

/// A VPL drawn from the RSM, before upload.
#[derive(Clone, Copy, Debug)]
pub struct Vpl {
    pub light: usize,
    pub texel: RsmTexel,
    /// Flux it carries (W): the light's covered flux / N, in the texel's colour.
    pub flux: Vec3,
    /// The light's covered flux W (sum of channels).
    pub light_flux: f32,
}

/// Draws `per_light` VPLs from each light's covered RSM texels with probability ∝ flux
/// (summed over channels), stratified over the texels' cumulative flux. The VPLs of a light
/// carry its covered flux in total: Φ_v = Φ_texel · W / (N · w_texel).
pub fn sample_vpls(texels: &[RsmTexel], lights: usize, per_light: u32, seed: u64) -> Vec<Vpl> {
    let mut out = Vec::new();
    for light in 0..lights {
        let ts: Vec<&RsmTexel> = texels.iter().filter(|t| t.light == light).collect();
        let mut cdf = Vec::with_capacity(ts.len());
        let mut total = 0.0f64;
        for t in &ts {
            total += t.flux.element_sum() as f64;
            cdf.push(total);
        }
        if total <= 0.0 || total.is_nan() {
            continue;
        }
        let mut rng = Rng::new(seed, 0xb1d1, light as u64);
        let n = per_light as f64;
        for k in 0..per_light {
            let u = (k as f64 + rng.next_f32() as f64) / n * total;
            let i = cdf.partition_point(|&c| c <= u).min(ts.len() - 1);
            let t = *ts[i];
            let w = t.flux.element_sum() as f64;
            let flux = t.flux * (total / (n * w)) as f32;
            out.push(Vpl {
                light,
                texel: t,
                flux,
                light_flux: total as f32,
            });
        }
    }
    out
}

/// VPL records for the GPU and their cube faces' matrices (six a record), slot by slot.
#[derive(Default)]
pub(super) struct Records {
    pub raws: Vec<VplRaw>,
    pub matrices: Vec<Mat4>,
}

/// VPL records and their cube-face matrices for the GPU: `per_light` slots per light, light
/// by light (the lighting pass finds a light's VPLs and covered flux by slot); a light
/// without covered texels keeps zero-flux slots.
pub(super) fn vpl_records(scene: &Scene, vpls: &[Vpl], per_light: u32, size: u32) -> Records {
    let (lo, hi) = light_views::bounds(scene);
    let diag = (hi - lo).length().max(1e-6);
    let slots = per_light as usize * scene.lights.len();
    let mut raws = vec![VplRaw::zeroed(); slots];
    let mut matrices = vec![Mat4::IDENTITY; slots * 6];
    let mut next = vec![0usize; scene.lights.len()];
    for v in vpls {
        let slot = v.light * per_light as usize + next[v.light];
        next[v.light] += 1;
        let t = &v.texel;
        let light = &scene.lights[v.light];
        let to = t.position - light.position();
        let d2 = to.length_squared().max(1e-12);
        let to_light = -to.normalize_or_zero();
        // Off its own surface, so that the VPL's cube map does not see it edge-on.
        let p = t.position + t.ng * (1e-4 * diag);
        let (m, texel_scale) = cube_views(p, lo, hi, size);
        matrices[slot * 6..slot * 6 + 6].copy_from_slice(&m);
        // The path tracer's cosine at x1 is the shading one (f·|ns·ω1,0|); the RSM flux
        // carries the geometric one (the texel's projected area).
        let cos_g = t.ng.dot(to_light).abs().max(1e-6);
        let ratio = (t.ns.dot(to_light).abs() / cos_g).min(10.0);
        let intensity = light.intensity_towards(-to_light).element_sum();
        raws[slot] = VplRaw {
            position: p.into(),
            first_layer: slot as u32 * 6,
            flux: (v.flux * ratio).into(),
            texel_scale,
            to_light: to_light.into(),
            fresnel: t.fresnel as u32,
            diffuse: t.diffuse.into(),
            roughness: t.roughness,
            specular: t.specular.into(),
            pdf: intensity * cos_g / (d2 * v.light_flux.max(1e-30)),
            ns: t.ns.into(),
            light_flux: v.light_flux,
            ng: t.ng.into(),
            light_dist2: d2,
        };
    }
    for (slot, r) in raws.iter_mut().enumerate() {
        r.first_layer = slot as u32 * 6;
    }
    Records { raws, matrices }
}

/// Marks the RSM VPLs' records (`per_light` slots a light, [`vpl_records`]) with the exact
/// model their heads found (`heads[l][k]`: light l's k-th VPL, as `vpl_records` placed it):
/// the RSM holds only the uber stand-in's parameters.
pub(super) fn mark_models(records: &mut Records, heads: &[Vec<Option<Head>>], per_light: u32) {
    for (l, group) in heads.iter().enumerate() {
        for (k, h) in group.iter().enumerate() {
            if let (Some(h), Some(r)) = (h, records.raws.get_mut(l * per_light as usize + k)) {
                r.fresnel = material_word(r.fresnel & 1 != 0, h.model);
            }
        }
    }
}

/// The VPLs' GPU resources for `capacity` VPLs with `size`² cube faces: the records as a
/// texture (7 texels per VPL in a row, a row per VPL; a texture, not a storage buffer: the
/// lighting pass loops over the VPLs, and lavapipe reads textures in loops many times
/// faster), the cube faces' matrices (for the lookup, into the atlas) and views (for
/// drawing), and the shadow maps: [`FACES_A_LAYER`] faces a layer, face f of the VPLs in
/// layer f / [`FACES_A_LAYER`] (`raster::vpl::tile_rect`).
pub(super) struct VplMaps {
    pub capacity: u32,
    pub size: u32,
    pub records: wgpu::Texture,
    pub matrices: wgpu::Buffer,
    views: wgpu::Buffer,
    view_group: wgpu::BindGroup,
    layer_views: Vec<wgpu::TextureView>,
    /// The shadow maps as one array (for the lighting pass).
    pub array: wgpu::TextureView,
}

impl VplMaps {
    /// Resources for `capacity` VPLs, or a setting error when the GPU cannot hold their
    /// shadow maps.
    pub fn new(ctx: &GpuContext, capacity: u32, size: u32) -> Result<Self> {
        let device = &ctx.device;
        let n_faces = capacity.max(1) * 6;
        let n_layers = n_faces.div_ceil(FACES_A_LAYER);
        let max_layers = device.limits().max_texture_array_layers;
        if n_layers > max_layers {
            return Err(Error::setting(
                "vpls_per_light",
                format!(
                    "{capacity} VPLs need {n_layers} shadow-map layers; the GPU allows {max_layers}"
                ),
            ));
        }
        let max_dim = device.limits().max_texture_dimension_2d;
        let side = size * TILES_A_SIDE;
        if side > max_dim {
            return Err(Error::setting(
                "vpl_shadow_map_size",
                format!("the GPU allows at most {}", max_dim / TILES_A_SIDE),
            ));
        }
        let bytes = n_layers as u64 * side as u64 * side as u64 * 4;
        crate::memory::check(|| "the VPL shadow maps".to_string(), bytes)?;
        let records = gpu::texture_2d(
            device,
            "vpls",
            VplRaw::TEXELS,
            capacity.max(1),
            wgpu::TextureFormat::Rgba32Float,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        );
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let matrices = buffer_init(
            ctx,
            "vpl shadow matrices",
            &vec![0u8; n_faces as usize * 64],
            storage,
        );
        let views = buffer_init(
            ctx,
            "vpl shadow views",
            &vec![0u8; n_faces as usize * VIEW_SIZE as usize],
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let view_group = ShadowPass::get(ctx).view_group(device, "vpl shadow bind group", &views);
        let (layer_views, array, _) =
            shadow::layered_maps(device, "vpl shadow maps", side, n_layers);
        Ok(VplMaps {
            capacity,
            size,
            records,
            matrices,
            views,
            view_group,
            layer_views,
            array,
        })
    }

    /// Uploads the VPL records and their cube faces' matrices and views.
    pub fn upload(&self, ctx: &GpuContext, raws: &[VplRaw], matrices: &[Mat4]) {
        if raws.is_empty() {
            return;
        }
        let q = &ctx.queue;
        let texels: Vec<[f32; 4]> = raws.iter().flat_map(VplRaw::texels).collect();
        crate::gpu::alloc::note_upload("vpls", texels.len() as u64 * 16);
        q.write_texture(
            self.records.as_image_copy(),
            bytemuck::cast_slice(&texels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(VplRaw::TEXELS * 16),
                rows_per_image: Some(raws.len() as u32),
            },
            wgpu::Extent3d {
                width: VplRaw::TEXELS,
                height: raws.len() as u32,
                depth_or_array_layers: 1,
            },
        );
        let m: Vec<[f32; 16]> = (0u32..)
            .zip(matrices)
            .map(|(face, m)| tile_matrix(face, *m).to_cols_array())
            .collect();
        gpu::write_buffer(
            q,
            "vpl shadow matrices",
            &self.matrices,
            0,
            bytemuck::cast_slice(&m),
        );
        let views: Vec<ViewRaw> = matrices
            .iter()
            .map(|m| ViewRaw::new(*m, Vec3::ZERO, 1.0))
            .collect();
        gpu::write_buffer(
            q,
            "vpl shadow views",
            &self.views,
            0,
            bytemuck::cast_slice(&views),
        );
    }

    /// Records the cube shadow maps of the VPLs `records` (`lit` of them drawn from texels;
    /// zero-flux slots are skipped when some are lit), each face drawing only the triangle
    /// runs that reach into its view, the [`FACES_A_LAYER`] faces of a layer in one pass.
    pub fn record_shadows(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        gs: &GpuScene,
        records: &Records,
        lit: usize,
        timer: &mut Timer,
    ) {
        let (raws, matrices) = (&records.raws, &records.matrices);
        let pass = ShadowPass::get(ctx);
        let draws = gs.cull.draws(matrices);
        let faces = raws.len() * 6;
        let per_layer = FACES_A_LAYER as usize;
        for (layer, view) in self.layer_views.iter().enumerate() {
            let tiles: Vec<Tile> = (layer * per_layer..((layer + 1) * per_layer).min(faces))
                .filter(|&f| raws[f / 6].flux != [0.0; 3] || lit >= raws.len())
                .map(|f| Tile {
                    viewport: Some(tile_rect(f as u32, self.size)),
                    view_offset: (f as u64 * VIEW_SIZE) as u32,
                    draws: draws.get(f).map(|d| d.as_slice()),
                })
                .collect();
            if tiles.is_empty() {
                continue;
            }
            let ts = timer.pass("vpl shadow maps");
            let target = (view, &self.view_group, &gs.geometry, gs.shadow_masks());
            pass.record_tiles(encoder, target, &tiles, ts);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texel(light: usize, flux: Vec3) -> RsmTexel {
        RsmTexel {
            light,
            position: Vec3::ZERO,
            ns: Vec3::Y,
            ng: Vec3::Y,
            diffuse: Vec3::splat(0.5),
            roughness: 1.0,
            specular: Vec3::ZERO,
            fresnel: false,
            flux,
        }
    }

    /// The VPLs of a light carry its covered flux in total (per channel, exactly for a
    /// light of one colour), each light gets `per_light`, and bright texels are drawn more.
    #[test]
    fn vpls_carry_each_lights_flux() {
        let mut texels = Vec::new();
        for i in 0..100 {
            texels.push(texel(0, Vec3::splat(if i < 50 { 0.01 } else { 0.03 })));
            texels.push(texel(1, Vec3::new(2.0, 1.0, 0.5) * 0.1));
        }
        let vpls = sample_vpls(&texels, 3, 16, 9);
        assert_eq!(vpls.len(), 32, "light 2 has no texels: no VPLs");
        for light in 0..2 {
            let total: Vec3 = texels
                .iter()
                .filter(|t| t.light == light)
                .map(|t| t.flux)
                .sum();
            let got: Vec3 = vpls
                .iter()
                .filter(|v| v.light == light)
                .map(|v| v.flux)
                .sum();
            assert!(
                ((got - total).abs() / total).max_element() < 1e-4,
                "{got} vs {total}"
            );
        }
        // Stratified by cumulative flux: the texels of flux 0.03 (half of light 0's texels,
        // 3/4 of its flux) get exactly 12 of its 16 VPLs.
        let bright = vpls
            .iter()
            .filter(|v| v.light == 0 && v.texel.flux.x > 0.025)
            .count();
        assert_eq!(bright, 12);
    }
}
