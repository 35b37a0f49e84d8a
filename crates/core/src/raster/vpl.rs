//! Virtual point lights for method `bidir`: their GPU record, the cube shadow-map views of a
//! VPL (six faces, rendered by the ordinary [`super::shadow::ShadowPass`]) and the full-screen
//! pass that adds the indirect light of VPLs and ray bundles to every G-buffer pixel
//! (`bidir.wgsl`).

use super::wgsl;
use crate::gpu::layout::{comparison_sampler_entry, depth_array_entry, texture_entry};
use crate::gpu::pipeline::draw_fullscreen;
use crate::gpu::{self, shaders};
use crate::scene::light_views::{corners, look_to, square_perspective, CUBE_FACES};
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

/// `Vpl` of `bidir.wgsl`: 112 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct VplRaw {
    pub position: [f32; 3],
    pub first_layer: u32,
    pub flux: [f32; 3],
    pub texel_scale: f32,
    pub to_light: [f32; 3],
    /// The material word: bit 0 the uber parameters' Fresnel flag, bits 1… the exact
    /// model's record index + 1 (`raster::exact_models::material_word`; 0: the uber
    /// parameters are shaded). Read as a float: exact below 2^24.
    pub fresnel: u32,
    pub diffuse: [f32; 3],
    pub roughness: f32,
    pub specular: [f32; 3],
    /// Area density of the VPL's point per draw: I(ω)·|ng·ω1,0| / (d²·W).
    pub pdf: f32,
    pub ns: [f32; 3],
    /// Covered flux W of the VPL's light (sum of channels).
    pub light_flux: f32,
    pub ng: [f32; 3],
    /// Squared distance from the VPL to its light.
    pub light_dist2: f32,
}

impl VplRaw {
    /// Texels per VPL in the VPL texture.
    pub const TEXELS: u32 = 7;

    /// The record as seven RGBA float texels (`vpl_at` of `bidir.wgsl`), the integer fields
    /// as float values (their bit patterns would be denormals, which a GPU may flush).
    pub fn texels(&self) -> [[f32; 4]; 7] {
        let v = |a: [f32; 3], w: f32| [a[0], a[1], a[2], w];
        [
            v(self.position, self.first_layer as f32),
            v(self.flux, self.texel_scale),
            v(self.to_light, self.fresnel as f32),
            v(self.diffuse, self.roughness),
            v(self.specular, self.pdf),
            v(self.ns, self.light_flux),
            v(self.ng, self.light_dist2),
        ]
    }
}

/// `Params` of `bidir.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct BidirParamsRaw {
    pub eye: [f32; 3],
    pub vpl_count: u32,
    pub vpls_per_light: u32,
    pub bundles: u32,
    /// 0: MIS, 1: VPLs only, 2: bundles only (one-bounce light; the two strategies of the
    /// longer paths combined by MIS in mode 0, the bundles' connections clamped alone
    /// otherwise).
    pub mode: u32,
    /// Indirect bounces to render (`max_depth` − 1): 0 none (direct light only), 1 the
    /// one-bounce light (VPLs and bundles' hits lit by the lights), 2 also the two-bounce
    /// light (bundles' hits lit by the RSM's VPLs), j > 2 also the traced subpaths'
    /// vertices up to order j − 1.
    pub bounces: u32,
    /// Lower bound of ‖x2 − y‖² of the bundles' connections in modes 1 and 2.
    pub min_dist2: f32,
    pub max_walk: u32,
    /// Random offset in [0, 1) of the two-bounce term's bundle-to-VPL pairing (a pixel adds
    /// its entry of `bidir.wgsl`'s 4×4 Bayer matrix over 16, mod 1).
    pub pair_offset: f32,
    /// Roughness clamping (§5): 1 on, 0 off.
    pub clamp_roughness: u32,
    /// Camera clip -> world.
    pub inv_view_proj: [[f32; 4]; 4],
    /// 1 when the scene has an environment light; (cos, sin) of its rotation.
    pub has_env: u32,
    pub env_cos: f32,
    pub env_sin: f32,
    /// Bundles drawn from the environment and uniformly (their densities' weights).
    pub bundles_env: f32,
    pub bundles_uniform: f32,
    /// 1 / ∫ lum(L_env) dω when bundles are drawn from the environment.
    pub env_pdf_scale: f32,
    /// Lower bound of ‖x3 − y1‖² for the one-bounce light of VPLs without a bundle
    /// strategy (negative `pdf`: the VPLs of area lights, the sun and the sky).
    pub alone_min_dist2: f32,
    /// Records of the light subpaths' vertices (after the `vpl_count` first VPLs): the VPLs
    /// of strategy B of the three-and-more-bounce light, MIS-weighted against the bundles'
    /// connections (`frame::bidir::subpaths`).
    pub sub_count: u32,
    /// β of the sky's control variate (`frame::bidir::sky_share`): 1 in the open, the share
    /// of the sky the visible surfaces see otherwise.
    pub sky_cv: f32,
    pub _pad: [u32; 3],
}

/// Extra field of view of a VPL's cube faces, in shadow texels on each side (as the lights').
const MARGIN_TEXELS: f32 = 8.0;

/// World -> clip of the six cube faces of a source at `p` (depth range: the scene bounds
/// `lo`..`hi`), and the world size of one texel at unit distance.
pub fn cube_views(p: Vec3, lo: Vec3, hi: Vec3, size: u32) -> ([Mat4; 6], f32) {
    let far = corners(lo, hi)
        .map(|c| (c - p).length())
        .into_iter()
        .fold(0.0f32, f32::max)
        * 1.01
        + 1e-3;
    let near = (far * 1e-3).max(1e-5);
    let t = 1.0 + 2.0 * MARGIN_TEXELS / size as f32;
    let m =
        CUBE_FACES.map(|(forward, up)| square_perspective(t, near, far) * look_to(p, forward, up));
    (m, 2.0 * t / size as f32)
}

/// VPL cube faces a shadow-map layer holds (an atlas of 2×2 faces, each `size`² in a
/// `2·size`² layer): a GPU's array-layer limit (2048 on lavapipe) then holds four times the
/// VPLs (1365 instead of 341), and a layer's four faces are drawn in one pass (issue 48).
/// `VPL_FACES_A_LAYER` of `bidir.wgsl` (a unit test checks that the two agree).
pub const FACES_A_LAYER: u32 = 4;

/// Faces a side of a layer's atlas.
pub const TILES_A_SIDE: u32 = 2;

/// The rectangle (x, y, width, height in texels) of cube face `face` (counted over all
/// VPLs) in its layer of `size`² faces.
pub fn tile_rect(face: u32, size: u32) -> [f32; 4] {
    let t = face % FACES_A_LAYER;
    let (tx, ty) = (t % TILES_A_SIDE, t / TILES_A_SIDE);
    let s = size as f32;
    [tx as f32 * s, ty as f32 * s, s, s]
}

/// World -> clip of face `face` for the lookup in its layer: the face's own matrix `m`
/// (which renders it, through the viewport of [`tile_rect`]) followed by the map of its
/// NDC square onto the face's quarter of the layer's (depth unchanged), so that the
/// lighting pass's ordinary shadow lookup reads the atlas.
pub fn tile_matrix(face: u32, m: Mat4) -> Mat4 {
    let t = face % FACES_A_LAYER;
    let (tx, ty) = ((t % TILES_A_SIDE) as f32, (t / TILES_A_SIDE) as f32);
    let k = 1.0 / TILES_A_SIDE as f32;
    // uv = ndc·(½, −½) + ½ over the layer; the face's uv square starts at (tx, ty)·k.
    let ox = (2.0 * tx + 1.0) * k - 1.0;
    let oy = 1.0 - (2.0 * ty + 1.0) * k;
    let atlas = Mat4::from_cols(
        glam::Vec4::new(k, 0.0, 0.0, 0.0),
        glam::Vec4::new(0.0, k, 0.0, 0.0),
        glam::Vec4::new(0.0, 0.0, 1.0, 0.0),
        glam::Vec4::new(ox, oy, 0.0, 1.0),
    );
    atlas * m
}

/// The VPL lighting pipeline and its layouts.
pub struct VplPass {
    /// The pass without the exact models' code (`MODELS` off: no scene material is one),
    /// and with it, made at the first frame that needs it (its code made the pass 70%
    /// slower on lavapipe, and its first compile minutes long: `cornell` never pays either).
    plain: wgpu::RenderPipeline,
    models: std::sync::OnceLock<wgpu::RenderPipeline>,
    module: wgpu::ShaderModule,
    pipeline_layout: wgpu::PipelineLayout,
    /// Group 0: params (uniform), VPLs (texture), their shadow matrices and maps, comparison sampler,
    /// lights, their shadow matrices and maps, bundle views, heads, nodes, the environment's
    /// radiance table, its irradiance table, the models' clamp-energy tables.
    pub layout: wgpu::BindGroupLayout,
    /// The exact models' clamp-energy tables ([`super::model_energy::MODEL_ENERGY`]).
    pub model_energy: wgpu::Buffer,
}

/// The target of the VPL pass.
pub const TARGET: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

impl VplPass {
    /// `gbuffer_layout`: the direct pass's group 1 (the G-buffer's lighting inputs).
    pub fn new(device: &wgpu::Device, gbuffer_layout: &wgpu::BindGroupLayout) -> Self {
        let frag = wgpu::ShaderStages::FRAGMENT;
        let depth_array = |binding| depth_array_entry(binding, frag);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("bidir bind group layout"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: frag,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                texture_entry(1, frag),
                super::storage_entry(2, frag),
                depth_array(3),
                comparison_sampler_entry(4, frag),
                super::storage_entry(5, frag),
                super::storage_entry(6, frag),
                depth_array(7),
                super::storage_entry(8, frag),
                super::storage_entry(9, frag),
                super::storage_entry(10, frag),
                texture_entry(11, frag),
                texture_entry(12, frag),
                super::storage_entry(13, frag),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("bidir pipeline layout"),
            bind_group_layouts: &[Some(&layout), Some(gbuffer_layout)],
            immediate_size: 0,
        });
        let module = shaders::module(
            device,
            "bidir shader",
            &[
                shaders::COMMON,
                shaders::BSDF,
                wgsl::SHADOW_LOOKUP,
                wgsl::BUNDLE_TYPES,
                shaders::FULLSCREEN,
                wgsl::BIDIR,
                wgsl::ROUGHNESS_CLAMP,
                wgsl::ENV_GLOSSY,
                // The exact models at the pixels (env_glossy.wgsl's taps through
                // exact_glossy_tap with the pixel's record).
                shaders::MODELS,
                wgsl::EXACT_MODELS,
                wgsl::EXACT_MODELS_DIRECT,
                wgsl::BIDIR_MODELS,
            ],
        );
        let plain = lighting_pipeline(device, &pipeline_layout, &module, false);
        let model_energy = gpu::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("bidir model energy"),
                contents: bytemuck::cast_slice(&super::model_energy::MODEL_ENERGY),
                usage: wgpu::BufferUsages::STORAGE,
            },
        );
        VplPass {
            plain,
            models: std::sync::OnceLock::new(),
            module,
            pipeline_layout,
            layout,
            model_energy,
        }
    }

    /// Records the pass into `target` (cleared); `models`: some material of the scene is
    /// shaded by its exact model (`raster::exact_models`).
    pub fn record(
        &self,
        device: &wgpu::Device,
        models: bool,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        [group, gbuffer_group]: [&wgpu::BindGroup; 2],
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let pipeline = if models {
            self.models.get_or_init(|| {
                lighting_pipeline(device, &self.pipeline_layout, &self.module, true)
            })
        } else {
            &self.plain
        };
        draw_fullscreen(
            encoder,
            "bidir lighting pass",
            target,
            pipeline,
            &[group, gbuffer_group],
            timestamps,
        );
    }
}

/// The lighting pipeline with the exact models' code (`MODELS` of bidir_models.wgsl) or not.
fn lighting_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    models: bool,
) -> wgpu::RenderPipeline {
    let constants = [("MODELS", if models { 1.0 } else { 0.0 })];
    let options = wgpu::PipelineCompilationOptions {
        constants: &constants,
        ..Default::default()
    };
    gpu::create_fullscreen_pipeline_with(
        device,
        "bidir pipeline",
        layout,
        module,
        ("fs_main", options),
        TARGET.into(),
    )
}

impl crate::gpu::Pipelines for VplPass {
    fn create(ctx: &crate::gpu::GpuContext) -> Self {
        VplPass::new(
            &ctx.device,
            &super::direct::DirectPass::get(ctx).gbuffer_layout,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point seen by a cube face lands, through the face's atlas matrix, on the layer's
    /// texel where the face's own matrix and its viewport rectangle draw it (the render and
    /// the lookup agree), with the same depth; every face's rectangle lies in the layer and
    /// the faces of a layer do not overlap.
    #[test]
    fn atlas_lookup_matches_the_tile_viewport() {
        let size = 64;
        let (m, _) = cube_views(Vec3::new(0.2, 0.3, 0.1), Vec3::splat(-1.0), Vec3::ONE, size);
        let side = (size * TILES_A_SIDE) as f32;
        let points = [Vec3::new(0.9, 0.5, 0.2), Vec3::new(-0.7, 0.1, 0.6)];
        let mut seen = 0;
        for face in 0..12u32 {
            let [x, y, w, h] = tile_rect(face, size);
            assert!(x + w <= side && y + h <= side);
            let others = (0..FACES_A_LAYER).filter(|&g| g != face % FACES_A_LAYER);
            for g in others {
                assert_ne!(tile_rect(g, size)[..2], [x, y]);
            }
            let fm = m[face as usize % 6];
            for p in points {
                let c = fm * p.extend(1.0);
                let ndc = c.truncate() / c.w;
                if c.w <= 0.0 || ndc.x.abs() > 1.0 || ndc.y.abs() > 1.0 {
                    continue;
                }
                // The viewport transform: NDC y = +1 at the rectangle's top.
                let drawn =
                    glam::Vec2::new(x + (ndc.x + 1.0) * 0.5 * w, y + (1.0 - ndc.y) * 0.5 * h);
                let a = tile_matrix(face, fm) * p.extend(1.0);
                let andc = a.truncate() / a.w;
                let uv = glam::Vec2::new(andc.x * 0.5 + 0.5, -andc.y * 0.5 + 0.5) * side;
                assert!((uv - drawn).length() < 1e-3, "face {face}: {uv} vs {drawn}");
                assert!((andc.z - ndc.z).abs() < 1e-6);
                seen += 1;
            }
        }
        assert!(seen >= 4, "{seen} point-face pairs checked");
    }

    #[test]
    fn faces_a_layer_match_the_lighting_pass() {
        let wgsl = include_str!("shaders/bidir.wgsl");
        let line = format!("const VPL_FACES_A_LAYER: u32 = {FACES_A_LAYER}u;");
        assert!(wgsl.contains(&line), "bidir.wgsl lacks `{line}`");
        assert_eq!(TILES_A_SIDE * TILES_A_SIDE, FACES_A_LAYER);
    }
}
