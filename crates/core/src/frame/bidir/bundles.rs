//! Global ray bundles (Tokuyoshi & Ogaki 2012 §3.2–3.3): the frame's directions, uniform
//! and stratified or drawn from an image environment, and the environment's table.

use crate::gpu::{self, GpuContext};
use crate::raster::bundles::{bundle_view, BundleBuffers, BundleViewRaw};
use crate::sampling::Rng;
use crate::scene::light_views;
use crate::scene::{Environment, Scene};
use glam::Vec3;

/// Side of the environment's irradiance table (columns; rows side/2 + 1), as the `direct`
/// frame's.
const IRRADIANCE_SIDE: u32 = 64;

/// The environment's tables for the lighting pass.
pub(super) struct EnvTables {
    /// Radiance (`Rgba32Float`, 1×1 black without an environment).
    pub radiance: wgpu::Texture,
    /// Irradiance E(n) (`Environment::irradiance_table`, rows from pole to pole): the
    /// expectation of the sky's direct-light control variate (`bidir.wgsl`).
    pub irradiance: wgpu::Texture,
    /// For an image drawn by importance (§3.3) 1 / ∫ lum(L) dω (0 otherwise).
    pub pdf_scale: f32,
}

/// The environment's tables ([`EnvTables`]).
pub(super) fn env_tables(ctx: &GpuContext, env: Option<&Environment>) -> EnvTables {
    let (radiance, pdf_scale) = env_table(ctx, env);
    let (iw, ih) = (IRRADIANCE_SIDE, IRRADIANCE_SIDE / 2 + 1);
    let (w, h, texels) = match env {
        Some(e) => (iw, ih, e.irradiance_table(iw, ih)),
        None => (1, 1, vec![Vec3::ZERO]),
    };
    EnvTables {
        radiance,
        irradiance: float_table(ctx, "environment irradiance", w, h, &texels),
        pdf_scale,
    }
}

/// A `w`×`h` `Rgba32Float` texture of `texels`.
fn float_table(ctx: &GpuContext, label: &str, w: u32, h: u32, texels: &[Vec3]) -> wgpu::Texture {
    let data: Vec<[f32; 4]> = texels.iter().map(|t| t.extend(1.0).to_array()).collect();
    gpu::float_texture_of(ctx, label, (w, h), &data)
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
    (
        float_table(ctx, "environment table", w, h, &texels),
        pdf_scale,
    )
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
pub(super) fn env_bundles(n: u32, env_pdf_scale: f32) -> u32 {
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
pub(super) fn bundle_views(
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
