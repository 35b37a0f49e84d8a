//! Method `bidir` (Tokuyoshi & Ogaki 2012, "Real-time bidirectional path tracing via
//! rasterization") as a frame of the engine:
//!
//! 1. Shadow maps and reflective shadow maps of the lights (the RSM with the copies of its
//!    targets), one submission; the RSM is read back.
//! 2. VPLs (§4.1): per light `vpls_per_light` texels drawn with probability ∝ flux
//!    (stratified), each VPL carrying its light's covered flux / N; a cube shadow map each.
//! 3. Global ray bundles (§3.2): `bundles` directions, each uniform over the sphere and
//!    together stratified ([`bundle_directions`]), the scene rasterized along each into
//!    per-pixel fragment lists.
//! 4. Direct light (the frame of method `direct`), then at the pixel-centre G-buffer the
//!    one-bounce light of the VPLs and of the bundles combined by MIS (§4.2) and the
//!    two-bounce light (§4.3, when `max_depth` ≥ 3) in one pass (`bidir.wgsl`), the
//!    composite and the readback of what was asked for.

use super::direct::{assemble, normalized, readback_names};
use super::gpu::rgb_image;
use super::options::BidirOptions;
use super::options::BidirStrategy;
use super::{FrameParams, RenderOutput, RenderStats};
use super::{GpuState, Images};
use crate::cancel::Progress;
use crate::error::{Error, Result};
use crate::gpu::Pipelines;
use crate::gpu::{self, raw::ViewRaw, GpuContext};
use crate::photon::specular::specular_paths_direct;
use crate::raster::bundles::BundlePass;
use crate::raster::bundles::{bundle_view, BundleBuffers, BundleViewRaw};
use crate::raster::direct::DirectPass;
use crate::raster::rsm::RsmPass;
use crate::raster::rsm::{RsmTargets, RsmTexel};
use crate::raster::shadow::ShadowPass;
use crate::raster::vpl::{cube_views, BidirParamsRaw, VplPass, VplRaw};
use crate::raster::{buffer_init, shadow, VIEW_SIZE};
use crate::sampling::Rng;
use crate::scene::light_views::{self, light_views, LightView};
use crate::scene::{Environment, Scene};
use crate::trace::SceneBvh;
use bytemuck::Zeroable;
use glam::{Mat4, Vec3};
use std::time::Instant;

/// What `bidir` keeps between frames: the RSM targets, the VPL buffers and their shadow maps,
/// the indirect target. Rebuilt when the image size, the light views or the VPL count change.
pub(super) struct BidirState {
    layers: Vec<LightView>,
    rsm: Option<RsmTargets>,
    /// VPL slots (all lights together).
    capacity: u32,
    vpl_size: u32,
    /// The VPL records as texels ([`VplRaw::texels`]): 7 per VPL in a row, a row per VPL.
    vpls: wgpu::Texture,
    params: wgpu::Buffer,
    matrices: wgpu::Buffer,
    views: wgpu::Buffer,
    view_group: wgpu::BindGroup,
    layer_views: Vec<wgpu::TextureView>,
    group: wgpu::BindGroup,
    indirect: wgpu::Texture,
    bundles: BundleBuffers,
    /// 1 / ∫ lum(L_env) dω of an image environment drawn by importance (§3.3); 0 otherwise.
    env_pdf_scale: f32,
    /// (bundles, resolution, memory MiB) the bundle buffers were made for.
    bundle_key: (u32, u32, u32),
    /// Whether the specular target holds an image of mirrors and glass (to be cleared when
    /// the materials no longer have delta lobes).
    specular_written: bool,
}

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

impl BidirState {
    fn new(
        ctx: &GpuContext,
        g: &GpuState,
        layers: Vec<LightView>,
        capacity: u32,
        vpl_size: u32,
        bundle_key: (u32, u32, u32),
        env: Option<&Environment>,
    ) -> Result<Self> {
        let direct_pass = DirectPass::get(ctx);
        let device = &ctx.device;
        let n_layers = capacity.max(1) * 6;
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
        if vpl_size > max_dim {
            return Err(Error::setting(
                "vpl_shadow_map_size",
                format!("the GPU allows at most {max_dim}"),
            ));
        }
        let bytes = n_layers as u64 * vpl_size as u64 * vpl_size as u64 * 4;
        crate::memory::check(|| "the VPL shadow maps".to_string(), bytes)?;
        let rsm = RsmTargets::new(ctx, &RsmPass::get(ctx), &layers, &g.scene.materials)?;
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        // A texture, not a storage buffer: the lighting pass loops over the VPLs, and
        // lavapipe reads textures in loops many times faster.
        let vpls = gpu::create_texture(
            device,
            &wgpu::TextureDescriptor {
                label: Some("vpls"),
                size: wgpu::Extent3d {
                    width: VplRaw::TEXELS,
                    height: capacity.max(1),
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            },
        );
        let vpls_view = vpls.create_view(&Default::default());
        let params = buffer_init(
            ctx,
            "bidir params",
            bytemuck::bytes_of(&BidirParamsRaw::zeroed()),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let (n_bundles, res, mb) = bundle_key;
        let bundles = BundleBuffers::new(
            ctx,
            &BundlePass::get(ctx),
            &g.scene.materials,
            n_bundles,
            res,
            mb as u64 * (1 << 20),
        )?;
        let (light_views, light_maps) = g.scene.shadow_lookup();
        let (env_table, env_pdf_scale) = env_table(ctx, env);
        let matrices = buffer_init(
            ctx,
            "vpl shadow matrices",
            &vec![0u8; n_layers as usize * 64],
            storage,
        );
        let views = buffer_init(
            ctx,
            "vpl shadow views",
            &vec![0u8; n_layers as usize * VIEW_SIZE as usize],
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let view_group = gpu::create_bind_group(
            device,
            &wgpu::BindGroupDescriptor {
                label: Some("vpl shadow bind group"),
                layout: &ShadowPass::get(ctx).layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: crate::raster::view_binding(&views),
                }],
            },
        );
        let (layer_views, array) =
            shadow::layered_maps(device, "vpl shadow maps", vpl_size, n_layers);
        let group = gpu::create_bind_group(
            device,
            &wgpu::BindGroupDescriptor {
                label: Some("vpl bind group"),
                layout: &VplPass::get(ctx).layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: params.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&vpls_view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: matrices.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::TextureView(&array),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: wgpu::BindingResource::Sampler(&direct_pass.shadow_sampler),
                    },
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: g.scene.lights.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 6,
                        resource: light_views.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 7,
                        resource: wgpu::BindingResource::TextureView(light_maps),
                    },
                    wgpu::BindGroupEntry {
                        binding: 8,
                        resource: bundles.views.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 9,
                        resource: bundles.heads.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 10,
                        resource: bundles.nodes.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 11,
                        resource: wgpu::BindingResource::TextureView(
                            &env_table.create_view(&Default::default()),
                        ),
                    },
                ],
            },
        );
        let (w, h) = (g.targets.width, g.targets.height);
        let indirect = gpu::create_texture(
            device,
            &wgpu::TextureDescriptor {
                label: Some("bidir indirect"),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: crate::raster::vpl::TARGET,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            },
        );
        Ok(BidirState {
            layers,
            rsm,
            capacity,
            vpl_size,
            vpls,
            params,
            matrices,
            views,
            view_group,
            layer_views,
            group,
            indirect,
            bundles,
            env_pdf_scale,
            bundle_key,
            specular_written: false,
        })
    }

    fn fits(
        &self,
        layers: &[LightView],
        capacity: u32,
        vpl_size: u32,
        bundle_key: (u32, u32, u32),
    ) -> bool {
        self.capacity == capacity
            && self.vpl_size == vpl_size
            && self.bundle_key == bundle_key
            && self.layers.len() == layers.len()
            && self.rsm.as_ref().is_none_or(|r| r.fits(layers))
    }
}

/// The environment's radiance table as an `Rgba32Float` texture (1×1 black without one),
/// and for an image drawn by importance (§3.3) 1 / ∫ lum(L) dω (0 otherwise).
fn env_table(ctx: &GpuContext, env: Option<&Environment>) -> (wgpu::Texture, f32) {
    let (w, h, texels) = match env {
        Some(e) => {
            let (w, h, t, _) = e.gpu_table();
            (w, h, t)
        }
        None => (1, 1, vec![Vec3::ZERO]),
    };
    let luminance = |c: Vec3| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    let integral: f64 = texels
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let theta = std::f64::consts::PI * ((i as u32 / w) as f64 + 0.5) / h as f64;
            let d_omega = 2.0 * std::f64::consts::PI * std::f64::consts::PI * theta.sin()
                / (w as f64 * h as f64);
            luminance(*t).max(0.0) as f64 * d_omega
        })
        .sum();
    let importance = env.is_some_and(|e| e.importance) && w * h > 1 && integral > 0.0;
    let pdf_scale = if importance {
        (1.0 / integral) as f32
    } else {
        0.0
    };
    let data: Vec<[f32; 4]> = texels.iter().map(|t| t.extend(1.0).to_array()).collect();
    let texture = gpu::create_texture(
        &ctx.device,
        &wgpu::TextureDescriptor {
            label: Some("environment table"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        },
    );
    crate::gpu::alloc::note_upload("environment table", data.len() as u64 * 16);
    ctx.queue.write_texture(
        texture.as_image_copy(),
        bytemuck::cast_slice(&data),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(w * 16),
            rows_per_image: Some(h),
        },
        texture.size(),
    );
    (texture, pdf_scale)
}

/// The RSM layers: the bounce-map views with `rsm_size`² texels per view for a light of
/// average power.
fn rsm_layers(scene: &Scene, rsm_size: u32) -> Vec<LightView> {
    let views: u64 = scene
        .lights
        .iter()
        .map(|l| match l {
            crate::scene::Light::Point { .. } => 6,
            crate::scene::Light::Spot { .. } => 1,
        })
        .sum();
    let texels = (rsm_size as u64).pow(2) * views.max(1);
    light_views(scene, texels)
}

/// VPL records and their cube-face matrices for the GPU: `per_light` slots per light, light
/// by light (the lighting pass finds a light's VPLs and covered flux by slot); a light
/// without covered texels keeps zero-flux slots.
fn vpl_records(scene: &Scene, vpls: &[Vpl], per_light: u32, size: u32) -> (Vec<VplRaw>, Vec<Mat4>) {
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
    (raws, matrices)
}

/// The frame's `n` bundle directions: a spherical Fibonacci set under a uniformly random
/// rotation. Each direction alone is uniform over the sphere (p_r = 1/4π, 1/2π over a
/// hemisphere with ±ω), as §3.3's; together they are stratified, which matters because
/// every pixel shares them: with independent directions the image mean of 16 bundles
/// wanders by ±7% in the furnace (all pixels err alike).
pub fn bundle_directions(n: u32, seed: u64) -> Vec<Vec3> {
    let mut rng = Rng::new(seed, 0xb0d1e, 0);
    // Uniform random rotation (Shoemake 1992).
    let (u1, u2, u3) = (rng.next_f32(), rng.next_f32(), rng.next_f32());
    let tau = std::f32::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let rot = glam::Quat::from_xyzw(
        a * (tau * u2).sin(),
        a * (tau * u2).cos(),
        b * (tau * u3).sin(),
        b * (tau * u3).cos(),
    )
    .normalize();
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f32 / n as f32;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden * i as f32;
            rot * Vec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// Share of the bundles drawn from an image environment's luminance (§3.3; the paper's
/// offset L_o for indirect light is this mixture's uniform part).
const ENV_BUNDLE_SHARE: f32 = 0.75;

/// How many of `n` bundles are drawn from the environment (the rest uniform).
fn env_bundles(n: u32, env_pdf_scale: f32) -> u32 {
    if env_pdf_scale > 0.0 && n >= 4 {
        (n as f32 * ENV_BUNDLE_SHARE).round() as u32
    } else {
        0
    }
}

/// The views of the frame's bundles: `n_env` directions drawn from the environment (a
/// stratified 2D lattice through `Environment::sample`, each axis flipped with probability
/// ½) and the rest uniform ([`bundle_directions`]); each with 1 / D, D = n_uniform/2π +
/// n_env·(p_env(ω) + p_env(−ω)) the multi-sample density of the frame's directions over a
/// hemisphere.
fn bundle_views(
    scene: &Scene,
    bundles: u32,
    seed: u64,
    b: &BundleBuffers,
    n_env: u32,
) -> Vec<BundleViewRaw> {
    let (lo, hi) = light_views::bounds(scene);
    let centre = (lo + hi) * 0.5;
    let radius = (hi - lo).length() * 0.5;
    let n_uni = bundles - n_env;
    let mut dirs = bundle_directions(n_uni, seed);
    let env = scene.environment.as_deref().filter(|_| n_env > 0);
    if let Some(env) = env {
        let mut rng = Rng::new(seed, 0xe17, 0);
        let (j1, j2) = (rng.next_f32(), rng.next_f32());
        let golden = 0.618_034f32;
        for i in 0..n_env {
            let u = glam::Vec2::new(
                ((i as f32 + j1) / n_env as f32).min(0.999_999),
                (i as f32 * golden + j2).fract(),
            );
            let d = env
                .sample(u)
                .map_or_else(|| crate::sampling::uniform_sphere(rng.next_2d()), |s| s.wi);
            dirs.push(if rng.next_f32() < 0.5 { d } else { -d });
        }
    }
    let density = |d: Vec3| {
        let uniform = n_uni as f32 / std::f32::consts::TAU;
        uniform + env.map_or(0.0, |e| n_env as f32 * (e.pdf(d) + e.pdf(-d)))
    };
    dirs.into_iter()
        .enumerate()
        .map(|(i, dir)| BundleViewRaw {
            inv_density: 1.0 / density(dir).max(1e-12),
            ..bundle_view(dir, centre, radius, i as u32, b.res, b.capacity)
        })
        .collect()
}

/// Longest fragment list the lighting pass walks (a guard against runaway loops).
const MAX_WALK: u32 = 4096;

/// The two-bounce term's lower bound on ‖x1 − x2‖, as a fraction of the scene's bounding
/// diagonal (§4.3 clamps it; the paper gives no value). Measured on `cornell` at 80×60,
/// depth 3, 64 VPLs / 16 bundles, two seeds: RMSE against `path` 0.154/0.061 at 2%,
/// 0.060/0.061 at 5%, 0.046/0.053 at 10%, 0.038/0.046 at 20%; image mean −1…+2% at 10%,
/// −3% at 20%.
const TWO_BOUNCE_MIN_DIST: f32 = 0.1;

pub(super) fn frame(
    g: &mut GpuState,
    scene: &Scene,
    bvh: &SceneBvh,
    options: &BidirOptions,
    frame: &FrameParams,
    images: Images,
    progress: &dyn Progress,
) -> Result<RenderOutput> {
    if scene.environment.is_some() && options.bundles == 0 {
        return Err(Error::setting(
            "bundles",
            "the environment light reaches `bidir` through its ray bundles: use bundles > 0",
        ));
    }
    let ctx = g.ctx.clone();
    g.timer.reset();
    let layers = rsm_layers(scene, options.rsm_size);
    let per_light = options.vpls_per_light;
    let capacity = per_light * scene.lights.len() as u32;
    let size = options.vpl_shadow_map_size;
    let bundle_key = (
        options.bundles.max(1),
        options.bundle_resolution,
        options.bundle_memory_mb,
    );
    if !g
        .bidir
        .as_ref()
        .is_some_and(|b| b.fits(&layers, capacity, size, bundle_key))
    {
        g.bidir = None;
        let env = scene.environment.as_deref();
        let state = BidirState::new(&ctx, g, layers.clone(), capacity, size, bundle_key, env)?;
        let view = state.indirect.create_view(&Default::default());
        g.targets.bind_composite(&ctx, Some(&view));
        g.bidir = Some(state);
    }
    let Some(state) = g.bidir.as_mut() else {
        return Err(Error::Cancelled);
    };
    state.layers = layers;
    let t = Instant::now();
    if let Some(rsm) = &state.rsm {
        rsm.write_views(&ctx, scene, &state.layers);
    }
    g.targets.write_eye(&ctx, scene);
    let n_env = env_bundles(options.bundles, state.env_pdf_scale);
    let views = bundle_views(scene, options.bundles, frame.seed, &state.bundles, n_env);
    if !views.is_empty() {
        state.bundles.write_views(&ctx, &views);
    }
    let mut upload = t.elapsed().as_secs_f64();

    // 1. Shadow maps and reflective shadow maps.
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("bidir lights"),
        });
    g.scene
        .record_shadows(&ctx, &mut encoder, &mut g.timer, scene);
    let textures = (&g.scene.textures.group, g.scene.variant);
    if let Some(rsm) = &state.rsm {
        rsm.record(
            &RsmPass::get(&ctx),
            &mut encoder,
            &state.layers,
            &g.scene.geometry,
            &g.scene.cull,
            textures,
            &mut g.timer,
        );
    }
    let index = ctx.queue.submit([encoder.finish()]);
    let t = Instant::now();
    let texels = match &state.rsm {
        Some(rsm) => rsm.read(&ctx, &state.layers, Some(index))?,
        None => Vec::new(),
    };
    let rsm_readback = t.elapsed().as_secs_f64();
    crate::cancel::check(progress)?;

    // 2. VPLs and their shadow maps.
    let t = Instant::now();
    let vpls = sample_vpls(&texels, scene.lights.len(), per_light, frame.seed);
    let (raws, matrices) = vpl_records(scene, &vpls, per_light, size);
    let vpl_seconds = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let q = &ctx.queue;
    if !raws.is_empty() {
        let texels: Vec<[f32; 4]> = raws.iter().flat_map(VplRaw::texels).collect();
        crate::gpu::alloc::note_upload("vpls", texels.len() as u64 * 16);
        q.write_texture(
            state.vpls.as_image_copy(),
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
        let m: Vec<[f32; 16]> = matrices.iter().map(|m| m.to_cols_array()).collect();
        gpu::write_buffer(
            q,
            "vpl shadow matrices",
            &state.matrices,
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
            &state.views,
            0,
            bytemuck::cast_slice(&views),
        );
    }
    let (lo, hi) = light_views::bounds(scene);
    let min_dist = TWO_BOUNCE_MIN_DIST * (hi - lo).length();
    let env_rot = scene
        .environment
        .as_ref()
        .map_or((1.0, 0.0), |e| e.rotation());
    let params = BidirParamsRaw {
        eye: scene.camera.position.into(),
        vpl_count: raws.len() as u32,
        vpls_per_light: per_light,
        bundles: options.bundles,
        mode: match options.strategy {
            BidirStrategy::Mis => 0,
            BidirStrategy::Vpl => 1,
            BidirStrategy::Bundle => 2,
        },
        two_bounce: (options.max_depth >= 3) as u32,
        min_dist2: min_dist * min_dist,
        max_walk: MAX_WALK,
        pair_offset: Rng::new(frame.seed, 0xfa17, 0).next_f32(),
        clamp_roughness: options.roughness_clamping as u32,
        inv_view_proj: glam::Mat4::from_cols_array_2d(
            &crate::raster::camera_view(scene, glam::Vec2::splat(0.5), 0.0).view_proj,
        )
        .inverse()
        .to_cols_array_2d(),
        has_env: scene.environment.is_some() as u32,
        env_cos: env_rot.0,
        env_sin: env_rot.1,
        bundles_env: n_env as f32,
        bundles_uniform: (options.bundles - n_env) as f32,
        env_pdf_scale: state.env_pdf_scale,
        _pad1: [0.0; 2],
    };
    gpu::write_buffer(
        q,
        "bidir params",
        &state.params,
        0,
        bytemuck::bytes_of(&params),
    );
    upload += t.elapsed().as_secs_f64();
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("bidir frame"),
        });
    let lit = vpls.len();
    // Each VPL cube face draws only the triangle runs that reach into its view.
    let draws = g.scene.cull.draws(&matrices);
    for (slot, chunk) in state.layer_views.chunks(6).take(raws.len()).enumerate() {
        if raws[slot].flux == [0.0; 3] && lit < raws.len() {
            continue;
        }
        for (face, view) in chunk.iter().enumerate() {
            let offset = ((slot * 6 + face) as u64 * VIEW_SIZE) as u32;
            let ts = g.timer.pass("vpl shadow maps");
            ShadowPass::get(&ctx).record(
                &mut encoder,
                view,
                &state.view_group,
                offset,
                &g.scene.geometry,
                draws.get(slot * 6 + face).map(|d| d.as_slice()),
                g.scene.shadow_masks(),
                ts,
            );
        }
    }

    // 3. Ray bundles.
    state.bundles.record(
        &BundlePass::get(&ctx),
        &mut encoder,
        options.bundles,
        &g.scene.geometry,
        textures,
        &mut g.timer,
    );

    // 4. Direct light, the indirect light, composite.
    let mut encoder = g
        .targets
        .record_direct(&ctx, &g.scene, encoder, &mut g.timer, progress)?;
    let indirect_view = state.indirect.create_view(&Default::default());
    let ts = g.timer.pass("bidir lighting");
    VplPass::get(&ctx).record(
        &mut encoder,
        &indirect_view,
        [&state.group, g.targets.lighting_group()],
        ts,
    );
    g.targets.record_composite(&ctx, &mut encoder, &mut g.timer);
    // 5. Mirrors and glass seen by the camera, traced on the CPU while the GPU works on the
    // lights (uploaded before the composite runs: queue writes precede the submission).
    let t = Instant::now();
    let specular = if scene.has_delta_materials() {
        let samples = super::photon::camera_samples(options.direct.spp, options.max_depth, frame);
        let img = specular_paths_direct(scene, bvh, &samples, options.specular_sampling, progress)?;
        g.targets.write_specular(&ctx, &img);
        state.specular_written = true;
        Some(img)
    } else {
        if state.specular_written {
            let (w, h) = (g.targets.width, g.targets.height);
            g.targets
                .write_specular(&ctx, &crate::image::Image::new(w, h));
            state.specular_written = false;
        }
        None
    };
    let specular_seconds = t.elapsed().as_secs_f64();
    let names = readback_names(images, true);
    g.targets
        .record_readback(&ctx, &mut encoder, &names, Some(&state.indirect));
    g.timer.resolve(&mut encoder);
    let index = ctx.queue.submit([encoder.finish()]);
    let t = Instant::now();
    let data = g.targets.read(&ctx, &names)?;
    let (fragments, overflow) = if options.bundles > 0 {
        state.bundles.fragments(&ctx, Some(index))?
    } else {
        (0, 0)
    };
    let readback = t.elapsed().as_secs_f64();
    g.timer.collect(&ctx)?;

    let mut stats = RenderStats {
        triangles: scene.triangles.len() as u64,
        samples_per_pixel: g.targets.spp(),
        vpls: vpls.len() as u64,
        bundles: options.bundles as u64,
        bundle_fragments: fragments,
        bundle_overflow: overflow,
        ..Default::default()
    };
    stats.stages.push(("upload".into(), upload));
    stats.stages.push(("rsm readback".into(), rsm_readback));
    stats.stages.push(("vpl sampling".into(), vpl_seconds));
    if specular.is_some() {
        stats
            .stages
            .push(("specular paths".into(), specular_seconds));
    }
    stats.stages.append(&mut g.timer.totals);
    stats.stages.push(("readback".into(), readback));
    let mut out = assemble(scene, &g.targets, &data, stats);
    if images.extras {
        if let Some(a) = data.get("accum") {
            out.aovs.push(("direct".into(), normalized(&g.targets, a)));
        }
        let (w, h) = (g.targets.width, g.targets.height);
        out.aovs.push((
            "specular".into(),
            specular.unwrap_or_else(|| crate::image::Image::new(w, h)),
        ));
        if let Some(i) = data.get("indirect") {
            out.aovs.push((
                "indirect".into(),
                rgb_image(g.targets.width, g.targets.height, i),
            ));
        }
    }
    Ok(out)
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
