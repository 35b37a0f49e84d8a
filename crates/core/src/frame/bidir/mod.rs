//! Method `bidir` (Tokuyoshi & Ogaki 2012, "Real-time bidirectional path tracing via
//! rasterization") as a frame of the engine:
//!
//! 1. Shadow maps and reflective shadow maps of the lights (the RSM with the copies of its
//!    targets), one submission; the RSM is read back.
//! 2. [`vpls`] (§4.1): per light `vpls_per_light` texels drawn with probability ∝ flux
//!    (stratified), each VPL carrying its light's covered flux / N; a cube shadow map each.
//! 3. [`bundles`] (§3.2): `bundles` global ray bundles, directions each uniform over the
//!    sphere and together stratified, the scene rasterized along each into per-pixel
//!    fragment lists.
//! 4. Direct light (the frame of method `direct`), then at the pixel-centre G-buffer the
//!    one-bounce light of the VPLs and of the bundles combined by MIS (§4.2, when `max_depth`
//!    ≥ 2: at 1 the frame is the direct light alone) and the
//!    light of two and more bounces (§4.3, when `max_depth` ≥ 3) in one pass
//!    (`bidir.wgsl`), the composite and the readback of what was asked for. [`subpaths`]
//!    continues each bundle's paired VPL into a light subpath traced on the CPU, every
//!    vertex a VPL; a path of two and more bounces is drawn both by the bundle's hit
//!    connecting to a subpath vertex and by a subpath vertex lighting the pixel, the two
//!    combined by MIS.
//! 5. [`specular_paths`]: the paths through mirrors and glass, on the CPU (a light tracer
//!    and camera paths through delta lobes), added to the specular target.
//! 6. [`interleave`]: the lighting pass's image read back, the deep subpath vertices it
//!    interleaved over pixel blocks filtered (mean-preserving); [`spikes`]: its isolated
//!    spikes spread over their neighbourhood (mean-preserving hot-spot control), the
//!    radiance corrected.

mod bundles;
mod emitted;
mod glass_aim;
mod interleave;
mod sky_share;
mod specular_paths;
mod spikes;
mod subpaths;
mod vpls;

use super::context::FrameCtx;
use super::gpu::{normalized, readback_names, rgb_image};
use super::gpu::{GpuFrame, GpuScene, LightDraw, Readback};
use super::options::{BidirOptions, BidirStrategy};
use super::{FrameParams, GpuState, Images, RenderOutput};
use crate::error::{Error, Result};
use crate::gpu::layout::{buffer_init, texture};
use crate::gpu::{self, GpuContext, Pipelines};
use crate::image::Image;
use crate::photon::specular::specular_paths_direct;
use crate::raster::bundles::{BundleBuffers, BundlePass};
use crate::raster::direct::DirectPass;
use crate::raster::rsm::{RsmPass, RsmTargets};
use crate::raster::vpl::{BidirParamsRaw, VplPass, TARGET};
use crate::sampling::Rng;
use crate::scene::light_views::{self, light_views, LightView};
use crate::scene::Scene;
use crate::trace::SceneBvh;
use bytemuck::Zeroable;
use vpls::{sample_vpls, vpl_records, Records, VplMaps};

/// What `bidir` keeps between frames: the RSM targets, the VPLs and their shadow maps, the
/// ray bundles, the lighting pass's inputs and its target. Rebuilt when the image size,
/// the light views, the VPL count or the bundles change.
pub(super) struct BidirState {
    layers: Vec<LightView>,
    rsm: Option<RsmTargets>,
    vpls: VplMaps,
    bundles: BundleBuffers,
    /// What the VPL maps and the bundle buffers were made for.
    sizes: Sizes,
    /// 1 / ∫ lum(L_env) dω of an image environment drawn by importance (§3.3); 0 otherwise.
    env_pdf_scale: f32,
    /// The lighting pass's parameters and bind group, and its target.
    params: wgpu::Buffer,
    group: wgpu::BindGroup,
    indirect: wgpu::Texture,
    /// Whether the specular target holds an image of mirrors and glass (to be cleared when
    /// the materials no longer have delta lobes).
    specular_written: bool,
    /// β of the sky's control variate, kept while the view, the geometry and the
    /// materials stay ([`BidirState::view_changed`]).
    sky_share: sky_share::SkyShare,
}

/// The RSM layers: the light views with `rsm_size`² texels per view for a light of average
/// power.
fn rsm_layers(scene: &Scene, rsm_size: u32) -> Vec<LightView> {
    let views = light_views::view_count(scene) as u64;
    let texels = (rsm_size as u64).pow(2) * views.max(1);
    light_views(scene, texels)
}

/// What a [`BidirState`] is made for: kept while the options and the scene's lights ask
/// for the same.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Sizes {
    /// VPL slots (the first VPLs' and the subpath vertices').
    capacity: u32,
    /// Side of a VPL's cube shadow-map face.
    vpl_size: u32,
    /// Ray bundles (at least 1), their resolution and their fragment memory in MiB.
    bundles: u32,
    bundle_resolution: u32,
    bundle_memory_mb: u32,
}

impl BidirState {
    fn new(
        ctx: &GpuContext,
        g: &GpuState,
        layers: Vec<LightView>,
        sizes: Sizes,
        scene: &Scene,
    ) -> Result<Self> {
        let vpls = VplMaps::new(ctx, sizes.capacity, sizes.vpl_size)?;
        let rsm = RsmTargets::new(ctx, &RsmPass::get(ctx), &layers, &g.scene.materials)?;
        let params = buffer_init(
            ctx,
            "bidir params",
            bytemuck::bytes_of(&BidirParamsRaw::zeroed()),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let bundles = BundleBuffers::new(
            ctx,
            &BundlePass::get(ctx),
            &g.scene.materials,
            sizes.bundles,
            sizes.bundle_resolution,
            sizes.bundle_memory_mb as u64 * (1 << 20),
        )?;
        let env = bundles::env_tables(ctx, scene.environment.as_deref());
        let env_pdf_scale = env.pdf_scale;
        let group = lighting_group(ctx, &g.scene, &vpls, &bundles, &params, &env);
        let (w, h) = (g.targets.width, g.targets.height);
        Ok(BidirState {
            layers,
            rsm,
            vpls,
            bundles,
            sizes,
            env_pdf_scale,
            params,
            group,
            indirect: indirect_target(ctx, w, h),
            specular_written: false,
            sky_share: Default::default(),
        })
    }

    /// The camera, the geometry or the materials changed since the last frame (the
    /// environment and the image size make a new state).
    pub(super) fn view_changed(&mut self) {
        self.sky_share.invalidate();
    }

    /// Uploads the RSM views and the frame's bundle views; returns how many bundles are
    /// drawn from the environment.
    fn write_views(&self, ctx: &GpuContext, scene: &Scene, bundles: u32, seed: u64) -> u32 {
        if let Some(rsm) = &self.rsm {
            rsm.write_views(ctx, scene, &self.layers);
        }
        let n_env = bundles::env_bundles(bundles, self.env_pdf_scale);
        let views = bundles::bundle_views(scene, bundles, seed, &self.bundles, n_env);
        if !views.is_empty() {
            self.bundles.write_views(ctx, &views);
        }
        n_env
    }

    fn fits(&self, layers: &[LightView], sizes: Sizes) -> bool {
        self.sizes == sizes
            && self.layers.len() == layers.len()
            && self.rsm.as_ref().is_none_or(|r| r.fits(layers))
    }
}

/// The lighting pass's bind group: its parameters, the VPLs and their shadow maps, the
/// lights and theirs, the ray bundles and the environment's tables.
fn lighting_group(
    ctx: &GpuContext,
    gs: &GpuScene,
    vpls: &VplMaps,
    bundles: &BundleBuffers,
    params: &wgpu::Buffer,
    env: &bundles::EnvTables,
) -> wgpu::BindGroup {
    let (light_views, light_maps) = gs.shadow_lookup();
    let sampler = &DirectPass::get(ctx).shadow_sampler;
    let pass = VplPass::get(ctx);
    let records = vpls.records.create_view(&Default::default());
    let irradiance = env.irradiance.create_view(&Default::default());
    let env = env.radiance.create_view(&Default::default());
    fn buffer(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
        wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        }
    }
    gpu::create_bind_group(
        &ctx.device,
        &wgpu::BindGroupDescriptor {
            label: Some("vpl bind group"),
            layout: &pass.layout,
            entries: &[
                buffer(0, params),
                texture(1, &records),
                buffer(2, &vpls.matrices),
                texture(3, &vpls.array),
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::Sampler(sampler),
                },
                buffer(5, &gs.lights),
                buffer(6, light_views),
                texture(7, light_maps),
                buffer(8, &bundles.views),
                buffer(9, &bundles.heads),
                buffer(10, &bundles.nodes),
                texture(11, &env),
                texture(12, &irradiance),
                buffer(13, &pass.model_energy),
            ],
        },
    )
}

/// The lighting pass's `width × height` target.
fn indirect_target(ctx: &GpuContext, width: u32, height: u32) -> wgpu::Texture {
    gpu::texture_2d(
        &ctx.device,
        "bidir indirect",
        width,
        height,
        TARGET,
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
    )
}

/// Longest fragment list the lighting pass walks (a guard against runaway loops).
const MAX_WALK: u32 = 4096;

/// The two-bounce term's lower bound on ‖x1 − x2‖, as a fraction of the scene's bounding
/// diagonal (§4.3 clamps it; the paper gives no value). Measured on `cornell` at 80×60,
/// depth 3, 64 VPLs / 16 bundles, two seeds: RMSE against `path` 0.154/0.061 at 2%,
/// 0.060/0.061 at 5%, 0.046/0.053 at 10%, 0.038/0.046 at 20%; image mean −1…+2% at 10%,
/// −3% at 20%. Only the single-strategy modes (`bidir_strategy` vpl or bundle) clamp: with
/// MIS (the default) strategy B of `subpaths` takes over where the pair is close.
const TWO_BOUNCE_MIN_DIST: f32 = 0.1;

/// The frame's random offset of the bundle-to-VPL pairing (the lighting pass's and the
/// light subpaths').
fn pair_offset(frame: &FrameParams) -> f32 {
    Rng::new(frame.seed, 0xfa17, 0).next_f32()
}

/// The lighting pass's parameters for the frame's records (`v.count` first VPLs, then
/// `v.used` subpath vertices) and `n_env` environment bundles.
fn lighting_params(
    scene: &Scene,
    options: &BidirOptions,
    frame: &FrameParams,
    v: &FrameVpls,
    n_env: u32,
    env_pdf_scale: f32,
    sky_cv: f32,
) -> BidirParamsRaw {
    let (vpl_count, sub_count) = (v.count, v.used);
    let (lo, hi) = light_views::bounds(scene);
    let min_dist = TWO_BOUNCE_MIN_DIST * (hi - lo).length();
    let env_rot = scene
        .environment
        .as_ref()
        .map_or((1.0, 0.0), |e| e.rotation());
    BidirParamsRaw {
        eye: scene.camera.position.into(),
        vpl_count,
        vpls_per_light: options.vpls_per_light,
        bundles: options.bundles,
        mode: match options.strategy {
            BidirStrategy::Mis => 0,
            BidirStrategy::Vpl => 1,
            BidirStrategy::Bundle => 2,
        },
        bounces: options.max_depth.saturating_sub(1),
        min_dist2: min_dist * min_dist,
        max_walk: MAX_WALK,
        pair_offset: pair_offset(frame),
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
        env_pdf_scale,
        alone_min_dist2: (emitted::ALONE_MIN_DIST * (hi - lo).length()).powi(2),
        sub_count,
        sky_cv,
        _pad: [0; 3],
    }
}

/// Groups of `vpls_per_light` VPL slots: one per light, and one more for the sources the
/// RSM does not see ([`emitted`]) when the scene has any.
fn vpl_groups(scene: &Scene) -> u32 {
    let others = scene.lights.iter().any(|l| !l.is_local())
        || scene.environment.is_some()
        || scene.materials.iter().any(|m| m.emits());
    scene.lights.len() as u32 + others as u32
}

/// A frame's VPL records (the first VPLs', then the light subpaths' vertices) and their
/// cube faces.
struct FrameVpls {
    records: Records,
    /// The first VPLs' records (`vpl_groups` × `vpls_per_light`), and those that carry light.
    count: u32,
    lit: usize,
    /// Light subpaths with a vertex.
    placed: usize,
    /// Records of subpath vertices after the first VPLs' (the slots up to the last used).
    used: u32,
}

/// The frame's VPLs: the first ones drawn (stage "vpl sampling"), then the light subpaths
/// traced from them (stage "light subpaths").
fn frame_vpls(
    fc: &mut FrameCtx,
    options: &BidirOptions,
    texels: &[crate::raster::rsm::RsmTexel],
    maps: &VplMaps,
) -> Result<FrameVpls> {
    let (scene, bvh, frame) = (fc.scene, fc.bvh()?, fc.params);
    let (mut records, groups, lit, count) = fc.timed("vpl sampling", |_| {
        let (records, groups) = first_vpls(scene, bvh, options, frame.seed, texels, maps);
        let lit = records.raws.iter().filter(|r| r.flux != [0.0; 3]).count();
        let count = records.raws.len() as u32;
        (records, groups, lit, count)
    });
    let (placed, used) = fc.timed("light subpaths", |_| {
        subpaths::append(scene, bvh, &groups, options, frame, maps, &mut records)
    });
    Ok(FrameVpls {
        records,
        count,
        lit,
        placed,
        used: used as u32,
    })
}

/// The frame's first VPLs y1 and their records, group by group (`vpl_groups`): drawn from
/// the RSM `texels` for each light, then from the photons of the other sources.
fn first_vpls(
    scene: &Scene,
    bvh: &SceneBvh,
    options: &BidirOptions,
    seed: u64,
    texels: &[crate::raster::rsm::RsmTexel],
    maps: &VplMaps,
) -> (Records, Vec<Vec<Option<subpaths::Head>>>) {
    let per_light = options.vpls_per_light;
    let vpls = sample_vpls(texels, scene.lights.len(), per_light, seed);
    let mut records = vpl_records(scene, &vpls, per_light, maps.size);
    let mut groups: Vec<Vec<Option<subpaths::Head>>> = (0..scene.lights.len())
        .map(|l| {
            vpls.iter()
                .filter(|v| v.light == l)
                .map(|v| Some(subpaths::Head::of_rsm(scene, bvh, v)))
                .collect()
        })
        .collect();
    vpls::mark_models(&mut records, &groups, per_light);
    if vpl_groups(scene) > scene.lights.len() as u32 {
        let heads = match emitted::sources(scene) {
            Some(sources) => emitted::heads(scene, bvh, &sources, per_light, seed),
            None => vec![None; per_light as usize],
        };
        emitted::append_records(scene, &heads, maps, &mut records);
        groups.push(heads);
    }
    (records, groups)
}

/// The frame's state: kept when it fits the options and the scene's lights, else made anew
/// (and the composite pointed at its target).
fn state<'a>(
    g: &'a mut GpuState,
    scene: &Scene,
    options: &BidirOptions,
) -> Result<&'a mut BidirState> {
    if scene.environment.is_some() && options.bundles == 0 {
        return Err(Error::setting(
            "bundles",
            "the environment light reaches `bidir` through its ray bundles: use bundles > 0",
        ));
    }
    let ctx = g.ctx.clone();
    let layers = rsm_layers(scene, options.rsm_size);
    let lights = vpl_groups(scene);
    let first = options.vpls_per_light * lights;
    // Six cube faces a VPL, `FACES_A_LAYER` a shadow-map layer.
    let faces = ctx.device.limits().max_texture_array_layers * crate::raster::vpl::FACES_A_LAYER;
    let max_slots = faces / 6;
    let (n1, bundles) = (options.vpls_per_light, options.bundles);
    let capacity =
        first + subpaths::slots(lights, n1, bundles, options.max_depth, first, max_slots);
    let sizes = Sizes {
        capacity,
        vpl_size: options.vpl_shadow_map_size,
        bundles: options.bundles.max(1),
        bundle_resolution: options.bundle_resolution,
        bundle_memory_mb: options.bundle_memory_mb,
    };
    if !g.bidir.as_ref().is_some_and(|b| b.fits(&layers, sizes)) {
        g.bidir = None;
        let state = BidirState::new(&ctx, g, layers.clone(), sizes, scene)?;
        let view = state.indirect.create_view(&Default::default());
        g.targets.bind_composite(&ctx, Some(&view));
        g.bidir = Some(state);
    }
    let state = g.bidir.as_mut().ok_or_else(no_state)?;
    state.layers = layers;
    Ok(state)
}

pub(super) fn frame(
    g: &mut GpuState,
    mut fc: FrameCtx,
    options: &BidirOptions,
    draw: LightDraw,
    images: Images,
) -> Result<RenderOutput> {
    let (scene, params) = (fc.scene, fc.params);
    state(g, scene, options)?;
    let GpuState {
        ctx,
        scene: gs,
        targets,
        timer,
        bidir,
        ..
    } = g;
    let state = bidir.as_mut().ok_or_else(no_state)?;
    let mut gpu = GpuFrame::begin(ctx, gs, targets, timer, &mut fc);
    let ctx = gpu.ctx.clone();
    let n_env = fc.timed("upload", |_| {
        state.write_views(&ctx, scene, options.bundles, params.seed)
    });

    // 1. Shadow maps and reflective shadow maps, read back.
    let mut encoder = gpu.encoder("bidir lights");
    gpu.record_shadows(&mut encoder, &fc, draw);
    let textures = (&gpu.scene.textures.group, gpu.scene.variant);
    if let Some(rsm) = &state.rsm {
        let pass = RsmPass::get(&ctx);
        rsm.record(
            &pass,
            &mut encoder,
            &state.layers,
            &gpu.scene.geometry,
            &gpu.scene.cull,
            textures,
            gpu.timer,
        );
    }
    let index = ctx.queue.submit([encoder.finish()]);
    let texels = fc.timed("rsm readback", |_| match &state.rsm {
        Some(rsm) => rsm.read(&ctx, &state.layers, Some(index)),
        None => Ok(Vec::new()),
    })?;
    crate::cancel::check(fc.progress)?;

    // 2. VPLs and their shadow maps.
    let v = frame_vpls(&mut fc, options, &texels, &state.vpls)?;
    let bvh = fc.bvh()?;
    let sky_cv = state.sky_share.get(&mut fc, bvh);
    fc.timed("upload", |_| {
        let (raws, matrices) = (&v.records.raws, &v.records.matrices);
        state.vpls.upload(&ctx, raws, matrices);
        let p = lighting_params(
            scene,
            options,
            params,
            &v,
            n_env,
            state.env_pdf_scale,
            sky_cv,
        );
        gpu::write_buffer(
            &ctx.queue,
            "bidir params",
            &state.params,
            0,
            bytemuck::bytes_of(&p),
        );
    });
    let mut encoder = gpu.encoder("bidir frame");
    state
        .vpls
        .record_shadows(&ctx, &mut encoder, gpu.scene, &v.records, v.lit, gpu.timer);

    // 3. Ray bundles.
    let bundle_pass = BundlePass::get(&ctx);
    let textures = (&gpu.scene.textures.group, gpu.scene.variant);
    state.bundles.record(
        &bundle_pass,
        &mut encoder,
        options.bundles,
        &gpu.scene.geometry,
        textures,
        gpu.timer,
    );

    // 4. Direct light, the indirect light, composite.
    let mut encoder = gpu.record_direct(encoder, &fc)?;
    let indirect_view = state.indirect.create_view(&Default::default());
    let ts = gpu.timer.pass("bidir lighting");
    let groups = [&state.group, gpu.targets.lighting_group()];
    let models = scene.materials.iter().enumerate().any(|(i, m)| {
        let maps = scene.material_maps.get(i).cloned().unwrap_or_default();
        crate::raster::exact_models::shades_exactly(m, &maps)
    });
    VplPass::get(&ctx).record(
        &ctx.device,
        models,
        &mut encoder,
        &indirect_view,
        groups,
        ts,
    );
    // 5. The paths through mirrors and glass (`specular_paths`), traced on the CPU while the
    // GPU works on the lights (uploaded before the composite runs: queue writes precede the
    // submission).
    let specular = specular(&gpu, state, &mut fc, options)?;
    let names = spikes::with_indirect(readback_names(images, true));
    let data = gpu.finish(encoder, &names, Some(&state.indirect), &mut fc)?;
    let (fragments, overflow) = fc.timed("readback", |_| match options.bundles {
        0 => Ok((0, 0)),
        _ => state.bundles.fragments(&ctx, None),
    })?;

    fc.stats.vpls = v.lit as u64;
    fc.stats.light_paths = v.placed as u64;
    fc.stats.bundles = options.bundles as u64;
    fc.stats.bundle_fragments = fragments;
    fc.stats.bundle_overflow = overflow;
    // The pass interleaves the subpath vertices past the first `v.count` (`interleave`).
    let deep = v.used > v.count;
    Ok(output(&gpu, &data, specular, images, deep, fc))
}

/// The frame's images from the read-back textures, with `bidir`'s own (`direct`,
/// `specular`, `indirect`) when asked for; `deep`: the lighting pass interleaved deep
/// subpath vertices (to be filtered).
fn output(
    gpu: &GpuFrame,
    data: &Readback,
    specular: Option<Image>,
    images: Images,
    deep: bool,
    fc: FrameCtx,
) -> RenderOutput {
    let mut out = gpu.output(data, fc);
    let targets = &*gpu.targets;
    let (w, h) = (targets.width, targets.height);
    // The lighting pass's image with its spikes spread (`spikes`), the difference added
    // to the radiance.
    let indirect = data.get("indirect").map(|i| {
        let mut img = rgb_image(w, h, i);
        let covered: Vec<bool> = i.iter().map(|p| p.w > 0.5).collect();
        let original = img.pixels.clone();
        // Alpha: 1 + the distance from the eye where the pass saw a surface.
        let depth: Vec<Option<f32>> = i.iter().map(|p| (p.w > 0.5).then(|| p.w - 1.0)).collect();
        if deep {
            interleave::filter(&mut img.pixels, &depth, w as usize, h as usize);
        }
        spikes::spread(&mut img.pixels, &covered, w as usize, h as usize);
        for ((r, new), old) in out
            .radiance
            .pixels
            .iter_mut()
            .zip(&img.pixels)
            .zip(&original)
        {
            *r += *new - *old;
        }
        img
    });
    if images.extras {
        if let Some(a) = data.get("accum") {
            out.aovs.push(("direct".into(), normalized(targets, a)));
        }
        let specular = specular.unwrap_or_else(|| Image::new(w, h));
        out.aovs.push(("specular".into(), specular));
        if let Some(i) = indirect {
            out.aovs.push(("indirect".into(), i));
        }
    }
    out
}

/// Step 5: the light of the paths through mirrors and glass that the GPU passes leave out
/// ([`specular_paths`]: next-event estimation where the camera's paths through them land
/// (stage "specular paths"), the light tracer's caustics ("caustic light paths"), the camera
/// paths through a delta lobe continued by the path tracer ("delta camera paths")) written
/// to the specular target; the target cleared once when the scene no longer has them.
fn specular(
    gpu: &GpuFrame,
    state: &mut BidirState,
    fc: &mut FrameCtx,
    options: &BidirOptions,
) -> Result<Option<Image>> {
    let (scene, frame, progress) = (fc.scene, fc.params, fc.progress);
    let targets = &*gpu.targets;
    if scene.has_delta_materials() {
        let bvh = fc.bvh()?;
        let mut img = fc.timed("specular paths", |_| {
            let samples = super::options::derived::camera_samples(
                options.direct.spp,
                options.max_depth,
                frame,
            );
            let sampling = options.specular_sampling;
            specular_paths_direct(scene, bvh, &samples, sampling, progress)
        })?;
        // One light path a pixel (at least MIN_LIGHT_PATHS), and ⌈spp/4⌉ camera samples a
        // pixel for the delta camera paths (`spp` is the direct light's, taken at
        // silhouettes and edges: 16 by default, as many over the whole image would cost
        // seconds a frame on the CPU at 512²). At 48² the first frame's relMSE against
        // `path` falls from 0.27 to 0.085 on `cornell-glass` and from 0.41 to 0.14 on
        // `ring-room` with 4 samples instead of 1 (`benches/measure/bidir_scenes`).
        let (w, h) = (targets.width as u64, targets.height as u64);
        let paths = (w * h).max(specular_paths::MIN_LIGHT_PATHS);
        let (seed, depth) = (frame.seed, options.max_depth);
        let caustics = fc.timed("caustic light paths", |_| {
            specular_paths::caustics(scene, bvh, paths, seed, depth, progress)
        })?;
        let spp = options.direct.spp.div_ceil(4);
        let through = fc.timed("delta camera paths", |_| {
            specular_paths::delta_camera_paths(scene, bvh, spp, seed, depth, progress)
        })?;
        for ((p, c), t) in img
            .pixels
            .iter_mut()
            .zip(&caustics.pixels)
            .zip(&through.pixels)
        {
            *p += *c + *t;
        }
        targets.write_specular(&gpu.ctx, &img);
        state.specular_written = true;
        return Ok(Some(img));
    }
    if state.specular_written {
        targets.write_specular(&gpu.ctx, &Image::new(targets.width, targets.height));
        state.specular_written = false;
    }
    Ok(None)
}

/// The error of a `bidir` frame that finds no `bidir` state (`state` makes it first).
fn no_state() -> Error {
    Error::internal("a bidir frame found no bidir state (made by `state` first)")
}
