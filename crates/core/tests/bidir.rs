//! Method `bidir` (Tokuyoshi & Ogaki 2012) on lavapipe: reflective shadow maps, VPLs with
//! cube shadow maps, one-bounce VPL lighting of the G-buffer.
//!
//! - furnace: the one-bounce light (bidir − direct) against the analytic value;
//! - Cornell box against the path tracer limited to the same depth (direct + one bounce);
//! - every built-in scene at `max_depth` 7 against the path tracer (issue 29), those with
//!   mirrors and glass included;
//! - settings are validated.

mod common;

use common::{block_means, load, mean, run};
use gi_core::frame::options::BidirStrategy;
use gi_core::Silent;
use gi_core::{render, Method, RenderOutput, Scene};
use glam::DVec3;
use std::f64::consts::PI;

fn bidir_settings(size: u32) -> gi_core::RenderOptions {
    gi_core::options!(Bidir, spp: 1, width: size, height: size, seed: 3)
}

/// Relative error of each channel of `got` against `expected`.
fn rel_err(got: DVec3, expected: DVec3) -> DVec3 {
    (got / expected - DVec3::ONE).abs()
}

/// Furnace (closed sphere R = 1, ρ = 0.5, point light I = 1 at the centre): direct radiance
/// L0 = ρI/(πR²); each bounce off the uniformly lit enclosure multiplies by ρ, so the
/// indirect light (bidir − direct) is ρ·L0 = 0.25/π with one bounce (`max_depth` 2) and
/// (ρ + ρ²)·L0 = 0.375/π with two (`max_depth` 3).
/// - VPLs: between two points of a sphere cos θ1 = cos θ3 = d/2R, so the VPL term is the
///   constant 1/(4R²) (no spikes) and 64 VPLs are exact up to the RSM's covered flux;
/// - bundles: every point sees the uniform sphere, so 16 bundles vary only by the cosine
///   of their directions (about 7% per pixel, far less over the image mean);
/// - MIS of both; two bounces add the clamped (§4.3) VPL-to-bundle-hit term, whose clamp
///   (‖x1 − x2‖ ≥ 5% of the diagonal) removes about 0.3% of ρ²·L0 here.
///
/// Tolerance 3% on the image mean, the issue's.
#[test]
fn furnace_matches_analytic() {
    let scene = load("furnace");
    let base = bidir_settings(32).with("max_depth", 2);
    let direct = mean(&run(&scene, &base.clone().with_method(gi_core::Method::Direct)).radiance);
    let mut failures = Vec::new();
    for (strategy, depth, expected) in [
        (BidirStrategy::Mis, 2, 0.25 / PI),
        (BidirStrategy::Vpl, 2, 0.25 / PI),
        (BidirStrategy::Bundle, 2, 0.25 / PI),
        (BidirStrategy::Mis, 3, 0.375 / PI),
    ] {
        let out = run(
            &scene,
            &base
                .clone()
                .with("bidir_strategy", strategy)
                .with("max_depth", depth),
        );
        let indirect = mean(&out.radiance) - direct;
        let err = rel_err(indirect, DVec3::splat(expected));
        eprintln!(
            "furnace {strategy:?} depth {depth}: indirect {:.5} expected {expected:.5} (err {:.4}); \
             {} fragments",
            indirect.x,
            err.max_element(),
            out.stats.bundle_fragments
        );
        assert_eq!(out.stats.vpls, 64);
        assert_eq!(out.stats.bundles, 16);
        assert_eq!(out.stats.bundle_overflow, 0);
        failures.extend(
            (err.max_element() >= 0.03).then(|| format!("{strategy:?} {depth}: {indirect:?}")),
        );
        let aov = out
            .aovs
            .iter()
            .find(|(n, _)| n == "indirect")
            .expect("indirect AOV");
        assert!((mean(&aov.1) - indirect).abs().max_element() < 1e-4);
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// Mean relative error per channel over the 8×8-pixel blocks.
fn block_error(a: &gi_core::image::Image, b: &gi_core::image::Image) -> DVec3 {
    let (ba, bb) = (block_means(a, 8), block_means(b, 8));
    ba.iter()
        .zip(&bb)
        .map(|(x, y)| (*x - *y).abs() / y.max(DVec3::splat(1e-3)))
        .sum::<DVec3>()
        / ba.len() as f64
}

/// Cornell box, 48×48, against the path tracer limited to the same depth (1024 spp):
/// `max_depth` 2 (direct + one bounce) and 3 (+ the two-bounce term), MIS of 64 VPLs and 32
/// bundles. Criteria: the mean image of 4 frames (seeds 1–4) per channel within 3%
/// (measured 0.2–0.7% at depth 2, 0.3–0.5% at depth 3; a single frame's mean varies by
/// 1.5–1.9% at depth 3 over seeds 1–8, before and after issue 29's MIS of the two-bounce
/// light, so one frame was a coin toss against 3%: seed 3 gave −2.0% red after it, 0.5%
/// before); mean relative 8×8-block error of the seed-3 frame ≤ 6% (measured 2.3–2.7% at
/// depth 2, 3.6–4.6% at depth 3, where the two-bounce light of 32 bundle–subpath pairs is
/// the noisiest part; the reference's own block noise is ~1% at 1024 spp).
#[test]
fn cornell_matches_path_tracer() {
    let scene = load("cornell");
    let size = 48;
    for depth in [2, 3] {
        let settings = bidir_settings(size)
            .with("spp", 4)
            .with("bundles", 32)
            .with("max_depth", depth);
        let bidir = run(&scene, &settings);
        let path = run(
            &scene,
            &bidir_settings(size)
                .with_method(gi_core::Method::Path)
                .with("spp", 1024)
                .with("max_depth", depth),
        );
        let (a, b) = (bidir_mean(&scene, &settings, 4).0, mean(&path.radiance));
        let rel = rel_err(a, b);
        let block_err = block_error(&bidir.radiance, &path.radiance);
        eprintln!(
            "cornell depth {depth}: bidir {a:?} path {b:?} rel {rel:?}; 8x8-block error \
             {block_err:?}; {:?}",
            bidir.stats
        );
        if rel.max_element() >= 0.03 || block_err.max_element() >= 0.06 {
            let dir = common::output_dir();
            for (name, img) in [
                (format!("bidir-cornell-{depth}.pfm"), &bidir.radiance),
                (format!("bidir-cornell-{depth}-path.pfm"), &path.radiance),
            ] {
                let _ = common::write_pfm(&dir.join(name), img);
            }
        }
        assert!(
            rel.max_element() < 0.03,
            "depth {depth}: mean {a:?} vs {b:?}"
        );
        assert!(
            block_err.max_element() < 0.06,
            "depth {depth}: block error {block_err:?}"
        );
    }
}

/// A glossy Cornell box (every material: specular 0.3, GGX roughness 0.5, diffuse × 0.6),
/// 48×48, one bounce, against the path tracer at depth 2 (1024 spp), MIS of 64 VPLs and 32
/// bundles with the roughness clamping of §5. Criteria: image mean per channel within 3%
/// (measured −0.5…−0.8%: clamping widens lobes and GGX loses a little albedo as α grows,
/// the paper's "loss of illumination"); 8×8-block error ≤ 5% (measured 3.2–3.4%; glossy
/// reflections of the bright ceiling are the noisiest part for 32 shared bundle
/// directions). Without clamping the same frame is 2.3–2.9% too bright, the VPL and bundle
/// spikes that §5 suppresses.
#[test]
fn glossy_cornell_matches_path_tracer() {
    let mut scene = load("cornell");
    for m in scene.materials.iter_mut() {
        m.specular = glam::Vec3::splat(0.3);
        m.roughness = 0.5;
        m.diffuse *= 0.6;
    }
    let base = bidir_settings(48)
        .with("spp", 4)
        .with("bundles", 32)
        .with("max_depth", 2);
    let bidir = run(&scene, &base);
    let path = run(
        &scene,
        &base
            .clone()
            .with_method(gi_core::Method::Path)
            .with("spp", 1024),
    );
    let (a, b) = (mean(&bidir.radiance), mean(&path.radiance));
    let rel = rel_err(a, b);
    let block_err = block_error(&bidir.radiance, &path.radiance);
    eprintln!("glossy cornell: bidir {a:?} path {b:?} rel {rel:?}; 8x8-block error {block_err:?}");
    assert!(rel.max_element() < 0.03, "mean {a:?} vs {b:?}");
    assert!(block_err.max_element() < 0.05, "block error {block_err:?}");
}

/// Figure 4 of the paper on the Cornell box (one bounce, 48×48, 16 VPLs and 16 bundles,
/// about the paper's 21 + 21): the indirect light of each strategy against the path
/// tracer's (depth 2 − depth 1, 1024 spp each), in 4×4-pixel blocks, relative to the
/// reference block.
/// - VPLs alone spike where a VPL lies close to a receiver (the ceiling corner above the
///   back wall): their largest block excess is above 2 (measured 4.2);
/// - bundles alone are blotchy (all pixels share 16 directions): mean |error| 0.36;
/// - MIS removes both: its largest excess is below 1.2 (measured 0.71, the reference's own
///   4×4-block noise included), and its mean |error| is under 0.6× either strategy's
///   (measured 0.15 vs 0.31 and 0.36).
#[test]
fn mis_removes_the_corner_spike() {
    let scene = load("cornell");
    let size = 48;
    let base = bidir_settings(size)
        .with("spp", 4)
        .with("max_depth", 2)
        .with("vpls_per_light", 16)
        .with("bundles", 16);
    let path = |depth| {
        run(
            &scene,
            &base
                .clone()
                .with_method(gi_core::Method::Path)
                .with("spp", 1024)
                .with("max_depth", depth),
        )
        .radiance
    };
    let (p2, p1) = (path(2), path(1));
    let reference: Vec<f64> = p2
        .pixels
        .iter()
        .zip(&p1.pixels)
        .map(|(a, b)| (*a - *b).element_sum() as f64)
        .collect();
    let blocks = |v: &[f64]| -> Vec<f64> {
        let n = (size / 4) as usize;
        let mut out = vec![0.0; n * n];
        for (i, x) in v.iter().enumerate() {
            let (px, py) = (i % size as usize, i / size as usize);
            out[(py / 4) * n + px / 4] += x / 16.0;
        }
        out
    };
    let rb = blocks(&reference);
    let mut errors = Vec::new();
    for strategy in [
        BidirStrategy::Vpl,
        BidirStrategy::Bundle,
        BidirStrategy::Mis,
    ] {
        let out = run(&scene, &base.clone().with("bidir_strategy", strategy));
        let (_, indirect) = out
            .aovs
            .iter()
            .find(|(n, _)| n == "indirect")
            .expect("indirect AOV");
        let ib: Vec<f64> = indirect
            .pixels
            .iter()
            .map(|p| p.element_sum() as f64)
            .collect();
        let e: Vec<f64> = blocks(&ib)
            .iter()
            .zip(&rb)
            .map(|(a, r)| (a - r) / r.max(1e-3))
            .collect();
        let max = e.iter().copied().fold(f64::MIN, f64::max);
        let mean_abs = e.iter().map(|x| x.abs()).sum::<f64>() / e.len() as f64;
        eprintln!("{strategy:?}: largest 4x4-block excess {max:.3}, mean |error| {mean_abs:.3}");
        errors.push((max, mean_abs));
    }
    let [(vpl_max, vpl_mean), (_, bundle_mean), (mis_max, mis_mean)] = errors[..] else {
        unreachable!()
    };
    assert!(vpl_max > 2.0, "no VPL spike to remove: {vpl_max}");
    assert!(mis_max < 1.2, "MIS keeps a spike: {mis_max}");
    assert!(
        mis_mean < 0.6 * vpl_mean.min(bundle_mean),
        "{mis_mean} vs {vpl_mean}, {bundle_mean}"
    );
}

/// A sphere (ρ = 0.6, 0.4, 0.2, geodesic, 5 subdivisions) under a constant environment
/// L = (1, 2, 3) and no other light: convex, so it sees only the sky and its radiance is
/// ρ·L everywhere (§6, Figure 6: the bundles' misses are the environment). The mean over
/// the sphere's pixels (from the position AOV) within 2%, the issue's tolerance, for
/// `bidir` (32 bundles) and `path` (64 spp); measured 0.3% and 0.1%. The background shows
/// L in both.
#[test]
fn convex_object_under_constant_environment() {
    let json = r#"{
        "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40,
                   "width": 32, "height": 32},
        "lights": [],
        "environment": {"radiance": [1, 2, 3]},
        "materials": {"m": {"diffuse": [0.6, 0.4, 0.2]}},
        "objects": [{"shape": {"type": "sphere", "radius": 0.8, "subdivisions": 5},
                     "material": "m"}]
    }"#;
    let scene = Scene::from_json(json, "env-sphere", &Default::default()).expect("scene");
    let expected = DVec3::new(0.6, 0.8, 0.6);
    for (method, spp) in [(Method::Bidir, 4), (Method::Path, 64)] {
        let out = run(
            &scene,
            &bidir_settings(32)
                .with("bundles", 32)
                .with_method(method)
                .with("spp", spp),
        );
        // Pixels whose 3×3 neighbourhood is all sphere (all sky for the background): the
        // path tracer's pixels are box-filtered, so edge pixels mix the two.
        let w = 32i32;
        let hit =
            |x: i32, y: i32| out.depth[(y.clamp(0, w - 1) * w + x.clamp(0, w - 1)) as usize] > 0.0;
        let all = |x: i32, y: i32, v: bool| {
            (-1..=1).all(|dy| (-1..=1).all(|dx| hit(x + dx, y + dy) == v))
        };
        let (mut sum, mut n, mut bg, mut nb) = (DVec3::ZERO, 0, DVec3::ZERO, 0);
        for (i, p) in out.radiance.pixels.iter().enumerate() {
            let (x, y) = (i as i32 % w, i as i32 / w);
            if all(x, y, true) {
                sum += p.as_dvec3();
                n += 1;
            } else if all(x, y, false) {
                bg += p.as_dvec3();
                nb += 1;
            }
        }
        let m = sum / n as f64;
        let bg = bg / nb as f64;
        eprintln!(
            "{method:?}: sphere {m:?} (expected {expected:?}, err {:?}) over {n} px; \
             background {bg:?}",
            rel_err(m, expected)
        );
        assert!(n > 200, "{n}");
        assert!(
            rel_err(m, expected).max_element() < 0.02,
            "{method:?}: {m:?}"
        );
        assert!(rel_err(bg, DVec3::new(1.0, 2.0, 3.0)).max_element() < 1e-3);
    }
    let e = render(&scene, &bidir_settings(16).with("bundles", 0), &Silent).err();
    assert!(matches!(e, Some(gi_core::Error::Setting { .. })), "{e:?}");
}

/// §3.3: bundles drawn from an image environment's luminance. A ground and a box under a
/// dim sky with a small bright sun (8×4 texels of 64×32, about 0.04 sr, 45° up), 32×32,
/// direct sky light only (`path` at `max_depth` 1, 256 spp; no point lights). With uniform
/// bundles the image mean is a lottery on how many of 64 directions see the sun (measured
/// 0.67–1.41 of `path` over seeds with 64–256 bundles); with 48 of the 64 drawn from the
/// sky it stays within 5% of `path` for each of four seeds (measured 0.967–0.989).
#[test]
fn importance_sampled_bundles_find_a_small_sun() {
    let (w, h) = (64u32, 32u32);
    let mut texels = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        let v = (y as f32 + 0.5) / h as f32;
        for x in 0..w {
            let sun = (h / 4 - 2..h / 4 + 2).contains(&y) && (w / 4 - 4..w / 4 + 4).contains(&x);
            texels.push(if sun {
                glam::Vec3::new(60.0, 55.0, 45.0)
            } else {
                glam::Vec3::new(0.05, 0.08, 0.15) * (1.0 - 0.5 * v)
            });
        }
    }
    let images = std::collections::HashMap::from([(
        "sky.exr".to_string(),
        gi_core::scene::EnvImage {
            width: w,
            height: h,
            texels,
        },
    )]);
    let json = r#"{
        "camera": {"position": [0, 7, 3], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 45,
                   "width": 32, "height": 32},
        "lights": [],
        "environment": {"file": "sky.exr", "rotation": 30},
        "materials": {"ground": {"diffuse": [0.8, 0.8, 0.8]}, "box": {"diffuse": [0.6, 0.6, 0.6]}},
        "objects": [
            {"shape": {"type": "quad", "size": [8, 8]}, "material": "ground"},
            {"shape": {"type": "box", "size": [1, 1, 1]}, "transform": {"translate": [0, 0.5, 0]},
             "material": "box"}
        ]
    }"#;
    let scene =
        Scene::from_json_with_images(json, "sun", &Default::default(), &images).expect("scene");
    let path = mean(
        &run(
            &scene,
            &bidir_settings(32)
                .with_method(gi_core::Method::Path)
                .with("spp", 256)
                .with("max_depth", 1),
        )
        .radiance,
    );
    let mut ratios = Vec::new();
    for seed in 0..4 {
        let out = run(
            &scene,
            &bidir_settings(32)
                .with("spp", 4)
                .with("bundles", 64)
                .with("bundle_resolution", 64)
                .with("seed", seed),
        );
        assert_eq!(out.stats.bundle_overflow, 0);
        ratios.push(mean(&out.radiance) / path);
    }
    eprintln!("small sun: bidir / path per seed {ratios:?}");
    for r in &ratios {
        assert!((*r - DVec3::ONE).abs().max_element() < 0.05, "{ratios:?}");
    }
}

#[test]
fn bad_settings_are_setting_errors() {
    let scene = load("cornell");
    let bad = |change: fn(&mut gi_core::frame::options::BidirOptions)| {
        let mut s = bidir_settings(16);
        if let gi_core::MethodOptions::Bidir(o) = &mut s.method {
            change(o);
        }
        s
    };
    for s in [
        bad(|o| o.vpls_per_light = 0),
        bad(|o| o.vpl_shadow_map_size = 8),
        bad(|o| o.rsm_size = 0),
        // 4 GiB of fragment lists: more than any GPU binds (lavapipe: 128 MiB).
        bad(|o| o.bundle_memory_mb = 4096),
    ] {
        let e = render(&scene, &s, &Silent).err();
        assert!(matches!(e, Some(gi_core::Error::Setting { .. })), "{e:?}");
    }
    assert_eq!("bidir".parse::<Method>().ok(), Some(Method::Bidir));
}

/// Mirrors and glass seen by the camera are traced on the CPU (next-event estimation where
/// the paths land) and composited: on `cornell-glass` the glass and mirror spheres are not
/// black, and the radiance is the sum of the direct, indirect and specular images.
/// Tolerance 1e-3 of the brightest pixel: the composite adds f32 images on the GPU, the
/// direct image is read back from its f32 accumulation (one division per pixel).
#[test]
fn mirrors_and_glass_seen_by_the_camera_are_traced() {
    let scene = load("cornell-glass");
    let out = run(&scene, &bidir_settings(32));
    let aov = |name: &str| {
        out.aovs
            .iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("no {name} image"))
            .1
            .clone()
    };
    let (direct, indirect, specular) = (aov("direct"), aov("indirect"), aov("specular"));
    let lit = specular
        .pixels
        .iter()
        .filter(|p| p.max_element() > 0.0)
        .count();
    // The two spheres cover a sizeable part of the 32×32 view.
    assert!(lit > 40, "{lit} specular pixels");
    let peak = out
        .radiance
        .pixels
        .iter()
        .map(|p| p.max_element())
        .fold(0.0, f32::max);
    for i in 0..out.radiance.pixels.len() {
        let sum = direct.pixels[i] + indirect.pixels[i] + specular.pixels[i];
        let d = (out.radiance.pixels[i] - sum).abs().max_element();
        assert!(
            d <= 1e-3 * peak,
            "pixel {i}: {} vs {sum}",
            out.radiance.pixels[i]
        );
    }
}

/// Mean image of `frames` independent `bidir` frames (seeds 1, 2, …).
fn bidir_mean(scene: &Scene, s: &gi_core::RenderOptions, frames: u64) -> (DVec3, RenderOutput) {
    let (m, _, out) = bidir_mean_se(scene, s, frames);
    (m, out)
}

/// Mean image of `frames` independent `bidir` frames (seeds 1, 2, …), and the standard
/// error of that mean per channel (from the frames' spread).
fn bidir_mean_se(
    scene: &Scene,
    s: &gi_core::RenderOptions,
    frames: u64,
) -> (DVec3, DVec3, RenderOutput) {
    let mut means = Vec::new();
    let mut last = None;
    for seed in 1..=frames {
        let out = run(scene, &s.clone().with("seed", seed));
        means.push(mean(&out.radiance));
        last = Some(out);
    }
    let n = frames as f64;
    let m = means.iter().sum::<DVec3>() / n;
    let var = means.iter().map(|x| (*x - m) * (*x - m)).sum::<DVec3>() / (n - 1.0).max(1.0);
    (m, (var / n).powf(0.5), last.expect("one frame"))
}

/// Issue 29: `bidir` at `max_depth` 7 (direct light, one bounce, and two to six bounces
/// through the light subpaths of `subpaths.rs`, its two strategies combined by MIS) against
/// ground truth: the furnace's analytic value (1 + ρ + … + ρ⁶)·L0 (32 bundles, 8 frames) and
/// the path tracer at depth 7 (1024 spp) on the built-in scenes without mirrors or glass
/// (those with: `mirror_and_glass_scenes_match_path_tracer`), 32×32, 64 bundles, the mean
/// of 32 frames (seeds 1–32).
///
/// Tolerance 2%, the issue's, on each channel. Measured (max channel): furnace −0.4%;
/// cornell +0.5% (standard error 0.32%), cornell-anim −1.1% red (0.40%; −0.7…−0.8% green
/// and blue), whose rest is the direct light (−0.4% of the image: the shared GPU direct
/// pass, −5% in the corners whatever its shadow maps' size) and the one-bounce light
/// (−0.4%, both strategies alone low too), `docs/bench/bidir-breakdown.md`. The noise is
/// checked too (standard error of the 32-frame mean under 0.6% of the reference on every
/// channel), so that 2% stays a test of the bias: single frames vary by 2–3% (the shared
/// bundle directions, 64 subpaths a light), and 32 of them leave cornell-anim's red 2.2
/// standard errors inside the bound. Before the MIS of the three-and-more-bounce light
/// (when ‖x2 − y‖ was clamped at 10% of the diagonal) the
/// Cornell boxes were 1.6–3.7% low; without the light subpaths 11–12% low.
#[test]
fn any_depth_matches_path_tracer() {
    let mut failures = Vec::new();
    let furnace = load("furnace");
    let s = bidir_settings(32).with("max_depth", 7).with("bundles", 32);
    let (got, out) = bidir_mean(&furnace, &s, 8);
    let rho: f64 = 0.5;
    let expected = (0..7).map(|k| rho.powi(k)).sum::<f64>() * rho / PI;
    let err = rel_err(got, DVec3::splat(expected));
    eprintln!(
        "furnace depth 7: {got:?} expected {expected:.5} (err {err:?}); {:?}",
        out.stats
    );
    assert!(out.stats.light_paths > 0, "no light subpaths traced");
    failures.extend((err.max_element() >= 0.02).then(|| format!("furnace: {got:?}")));
    for name in ["cornell", "cornell-anim"] {
        let s = bidir_settings(32).with("max_depth", 7).with("bundles", 64);
        failures.extend(depth_7_failures(name, &s, 32, 0.006));
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// `bidir` with settings `s` (32×32, `max_depth` 7), averaged over `frames` frames, against
/// `path` at 1024 spp on built-in scene `name`: a failure when a channel of the mean is 2% or
/// more off, or when the standard error of the mean reaches `max_noise` (so that 2% tests
/// the bias, not the noise).
fn depth_7_failures(
    name: &str,
    s: &gi_core::RenderOptions,
    frames: u64,
    max_noise: f64,
) -> Vec<String> {
    let scene = load(name);
    let (got, se, out) = bidir_mean_se(&scene, s, frames);
    let path = run(
        &scene,
        &bidir_settings(32)
            .with_method(gi_core::Method::Path)
            .with("spp", 1024)
            .with("max_depth", 7),
    );
    let reference = mean(&path.radiance);
    let err = rel_err(got, reference);
    let noise = se / reference;
    eprintln!(
        "{name} depth 7: bidir {got:?} path {reference:?} (err {err:?}, standard error \
         {noise:?}); {:?}",
        out.stats
    );
    let mut failures = Vec::new();
    failures
        .extend((err.max_element() >= 0.02).then(|| format!("{name}: {got:?} vs {reference:?}")));
    failures.extend(
        (noise.max_element() >= max_noise).then(|| format!("{name}: too noisy, {noise:?}")),
    );
    failures
}

/// A closed white room (2 m, the walls' colours as the Cornell box's) lit only by an
/// emitting square under its ceiling, facing down.
const AREA_ROOM: &str = r#"{
    "camera": {"position": [0, 0.9, 3.2], "look_at": [0, 0.7, 0], "up": [0, 1, 0], "fov": 40,
               "width": 32, "height": 32},
    "lights": [],
    "materials": {
        "white": {"diffuse": [0.73, 0.73, 0.73]},
        "red": {"diffuse": [0.63, 0.065, 0.05]},
        "green": {"diffuse": [0.14, 0.45, 0.09]},
        "lamp": {"diffuse": [0.78, 0.78, 0.78], "emission": [17, 12, 4]}
    },
    "objects": [
        {"shape": {"type": "quad", "size": [2, 2]}, "material": "white"},
        {"shape": {"type": "quad", "size": [2, 2]}, "material": "white",
         "transform": {"translate": [0, 2, 0], "rotate": [180, 0, 0]}},
        {"shape": {"type": "quad", "size": [2, 2]}, "material": "white",
         "transform": {"translate": [0, 1, -1], "rotate": [90, 0, 0]}},
        {"shape": {"type": "quad", "size": [2, 2]}, "material": "red",
         "transform": {"translate": [-1, 1, 0], "rotate": [0, 0, -90]}},
        {"shape": {"type": "quad", "size": [2, 2]}, "material": "green",
         "transform": {"translate": [1, 1, 0], "rotate": [0, 0, 90]}},
        {"shape": {"type": "box", "size": [0.6, 1.2, 0.6]}, "material": "white",
         "transform": {"translate": [-0.35, 0.6, -0.3], "rotate": [0, 20, 0]}},
        {"shape": {"type": "quad", "size": [0.5, 0.5]}, "material": "lamp",
         "transform": {"translate": [0, 1.98, 0], "rotate": [180, 0, 0]}}
    ]
}"#;

/// A ground plate with a box and a wall under a sun (directional light) and, optionally, a
/// constant sky.
fn sun_scene(sky: bool) -> Scene {
    let env = if sky {
        r#""environment": {"radiance": [0.3, 0.4, 0.6]},"#
    } else {
        ""
    };
    let json = format!(
        r#"{{
        "camera": {{"position": [0, 2.2, 4], "look_at": [0, 0.4, 0], "up": [0, 1, 0],
                   "fov": 40, "width": 32, "height": 32}},
        "lights": [{{"type": "directional", "direction": [-0.5, -1, -0.3],
                     "irradiance": [3, 2.8, 2.5]}}],
        {env}
        "materials": {{
            "ground": {{"diffuse": [0.6, 0.55, 0.5]}},
            "red": {{"diffuse": [0.7, 0.2, 0.15]}},
            "wall": {{"diffuse": [0.8, 0.8, 0.8]}}
        }},
        "objects": [
            {{"shape": {{"type": "quad", "size": [4, 4]}}, "material": "ground"}},
            {{"shape": {{"type": "box", "size": [0.8, 0.8, 0.8]}}, "material": "red",
             "transform": {{"translate": [0.3, 0.4, 0], "rotate": [0, 30, 0]}}}},
            {{"shape": {{"type": "quad", "size": [3, 1.5]}}, "material": "wall",
             "transform": {{"translate": [0, 0.75, -1.2], "rotate": [90, 0, 0]}}}}
        ]
    }}"#
    );
    Scene::from_json(&json, "sun", &Default::default()).expect("scene")
}

fn sky_only() -> Scene {
    let mut s = sun_scene(true);
    s.lights.clear();
    s
}

/// Issue 28: `bidir`'s VPLs come from every source (`frame/bidir/emitted.rs`: photons of
/// the emitters, the sun and the sky, each one's first hit a VPL, continued into light
/// subpaths as the RSM's VPLs are), against `path` (512 spp) at the same depth: an area
/// light in a closed room (not seen by the camera: the G-buffer's pixel-centre view of it
/// and the path tracer's box filter would differ at its edges), a sun over a box and a wall,
/// and the same under a constant sky alone. 32×32, 64 bundles, the mean of 8 frames (16
/// under the sky, whose direct light through the bundles' misses is the noisiest term).
///
/// Measured (max channel error): depth 2 (direct + one bounce, the new VPLs' own term)
/// +0.6% (area), −0.5% (sun), −1.4% red (sky, whose direct light through the bundles' misses
/// is the noisiest term: −2.8% over 8 frames); depth 7 −1.4% green (area), −1.2% (sun),
/// −2.0% red (sky) since the light past one bounce is two strategies combined by MIS
/// (issue 29; −2.9%, −1.5%, −2.3% when the bundles' connections were clamped at 10% of the
/// diagonal). Without these VPLs the images are the direct light, 24%
/// (area) and 12% (sun) below `path` at depth 2. Tolerances: 3% at both depths (2% for the
/// point-lit Cornell boxes in `any_depth_matches_path_tracer`; the sky's frames, 64 photons
/// each, vary more).
#[test]
fn area_lights_sun_and_sky_match_path_tracer() {
    let area = Scene::from_json(AREA_ROOM, "area-room", &Default::default()).expect("scene");
    let mut failures = Vec::new();
    for (name, scene, frames) in [
        ("area room", area, 8),
        ("sun", sun_scene(false), 8),
        ("sky", sky_only(), 16),
    ] {
        let size = 32;
        for (depth, tolerance) in [(2u32, 0.03), (7, 0.03)] {
            let s = bidir_settings(size)
                .with("max_depth", depth)
                .with("bundles", 64);
            let (got, out) = bidir_mean(&scene, &s, frames);
            let path = run(
                &scene,
                &bidir_settings(size)
                    .with_method(gi_core::Method::Path)
                    .with("spp", 512)
                    .with("max_depth", depth),
            );
            let reference = mean(&path.radiance);
            let err = rel_err(got, reference);
            eprintln!(
                "{name} depth {depth}: bidir {got:?} path {reference:?} (err {err:?}); \
                 vpls {} subpaths {}",
                out.stats.vpls, out.stats.light_paths
            );
            assert!(out.stats.vpls > 0, "{name}: no VPLs");
            failures.extend(
                (err.max_element() >= tolerance)
                    .then(|| format!("{name} depth {depth}: {got:?} vs {reference:?}")),
            );
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// An emitting furnace: a closed cube (2 m) whose six walls emit L = 1 inwards (one-sided,
/// so that every photon stays inside) and reflect with albedo ρ = 0.5, no other light:
/// every point sees radiance L·(1 + ρ + … + ρ^d) at `max_depth` d, as in a sphere (uniform
/// emission and albedo in any closed enclosure), and every VPL lies on an emitter (where
/// adding the emitted radiance at a VPL would count direct light twice). The light past
/// the direct light (the `indirect` AOV: the VPLs of the emitters' photons and their
/// subpaths) must be L·(ρ² + … + ρ^d): within 5% at depth 2 (measured −2.6%; the same with
/// no clamp of ‖x3 − y1‖), within 4% at depth 7 (measured −1.7% with the light past one
/// bounce by two strategies under MIS, issue 29; it was −5.2% when the bundles' connections
/// x2 ↔ y_j were clamped at 10% of the diagonal, dropping the light of the close pairs, many
/// in a 2 m cube; without the light subpaths it would be −28%). 32×32, 32 bundles, the mean of 8 frames. The direct light is the GPU's
/// sampled emitter points (the `direct` frame, with its own stated near-field bias),
/// emission seen by the camera the G-buffer's.
#[test]
fn emitting_furnace_matches_analytic() {
    let wall = |t: &str| {
        format!(
            r#"{{"shape": {{"type": "quad", "size": [2, 2]}}, "material": "wall", "transform": {t}}}"#
        )
    };
    let walls = [
        r#"{"translate": [0, -1, 0]}"#,
        r#"{"translate": [0, 1, 0], "rotate": [180, 0, 0]}"#,
        r#"{"translate": [0, 0, -1], "rotate": [90, 0, 0]}"#,
        r#"{"translate": [0, 0, 1], "rotate": [-90, 0, 0]}"#,
        r#"{"translate": [-1, 0, 0], "rotate": [0, 0, -90]}"#,
        r#"{"translate": [1, 0, 0], "rotate": [0, 0, 90]}"#,
    ]
    .map(wall)
    .join(",");
    let json = format!(
        r#"{{"camera": {{"position": [0, 0, 0.5], "look_at": [0, -0.2, -1], "up": [0, 1, 0],
                        "fov": 70, "width": 32, "height": 32}},
            "lights": [],
            "materials": {{"wall": {{"diffuse": [0.5, 0.5, 0.5], "emission": [1, 1, 1]}}}},
            "objects": [{walls}]}}"#
    );
    let scene = Scene::from_json(&json, "emitting-cube", &Default::default()).unwrap();
    let mut failures = Vec::new();
    for depth in [2u32, 7] {
        let mut sum = DVec3::ZERO;
        let mut vpls = 0;
        for seed in 1..=8u64 {
            let s = bidir_settings(32)
                .with("max_depth", depth)
                .with("bundles", 32)
                .with("seed", seed);
            let out = run(&scene, &s);
            let aov = out.aovs.iter().find(|(n, _)| n == "indirect");
            sum += mean(&aov.expect("indirect AOV").1);
            vpls += out.stats.vpls;
        }
        let got = sum / 8.0;
        let expected: f64 = (2..=depth).map(|k| 0.5f64.powi(k as i32)).sum();
        let err = rel_err(got, DVec3::splat(expected));
        eprintln!(
            "emitting cube depth {depth}: indirect {got:?} expected {expected:.4} (err {err:?}); \
             {vpls} VPLs"
        );
        // Every photon stays inside: every one is a VPL.
        assert_eq!(vpls, 8 * 64);
        let tolerance = if depth == 2 { 0.05 } else { 0.04 };
        failures
            .extend((err.max_element() >= tolerance).then(|| format!("depth {depth}: {got:?}")));
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// `max_depth` 1 asks for direct light alone: `bidir` then adds no indirect light (it used
/// to add the one-bounce light whatever the depth). On `cornell` (a point light, no sky:
/// the direct light is the GPU direct pass that `direct` runs too) its image equals
/// `direct`'s with the same options to float rounding (1e-5 of the mean), while at depth 2
/// the one-bounce light adds at least 10% (the box's colour bleeding; measured 41%).
#[test]
fn max_depth_one_is_direct_light_only() {
    let scene = load("cornell");
    let depth = |d: i64| bidir_settings(32).with("max_depth", d);
    let one = mean(&run(&scene, &depth(1)).radiance);
    let two = mean(&run(&scene, &depth(2)).radiance);
    let direct = mean(
        &run(
            &scene,
            &gi_core::options!(Direct, spp: 1, width: 32, height: 32, seed: 3),
        )
        .radiance,
    );
    eprintln!("bidir depth 1 {one:.5}, depth 2 {two:.5}, direct {direct:.5}");
    let d = (one - direct).abs().max_element() / direct.element_sum();
    assert!(d < 1e-5, "depth 1 differs from direct by {d}");
    assert!(
        two.element_sum() > 1.1 * one.element_sum(),
        "{two} vs {one}"
    );
}

/// Issue 29: `bidir` at `max_depth` 7 on the built-in scenes with mirrors and glass against
/// the path tracer at depth 7 (1024 spp), 32×32, 64 bundles, 4 direct samples a pixel (at
/// 1 the pixel-centre direct light of `mirror-shadow`'s small bright patches is +3.8% over
/// the pixel-area mean at depth 1, a sampling matter of the 32×32 image, not of the light
/// transport: −1.3% at 16 samples), the mean of `frames` frames. The paths through mirrors
/// and glass are traced on the CPU (`frame/bidir/specular_paths.rs`: the light tracer's
/// caustics, the camera paths through a delta lobe); before them these scenes were 3–27%
/// low (caustic-ring 0.810, cornell-glass 0.876, mirror-shadow 0.971, ring-room 0.727 of
/// `path`, 8 frames at 32 bundles).
///
/// Tolerance 2%, the issue's, on each channel, and the standard error of the frames' mean
/// under 0.7% of the reference (so that 2% tests the bias). Measured here (max channel,
/// standard error): caustic-ring +0.00% (0.20%), cornell-glass +0.79% blue (0.46%),
/// mirror-shadow −0.41% (0.38%), ring-room +0.17% (0.54%); with the `bidir_scenes` example
/// (16 frames, mean of RGB, `spp` camera samples then): caustic-ring +0.05 ± 0.15%,
/// cornell-glass +0.21 ± 0.24%, mirror-shadow −0.23 ± 0.64%, ring-room +0.46 ± 0.50%. The
/// frame counts below keep the standard error near 0.5% (cornell-glass, 2.5–4.5 s a frame on
/// lavapipe, 8 frames); about 75 s in all on 2 shared cores.
#[test]
fn mirror_and_glass_scenes_match_path_tracer() {
    let mut failures = Vec::new();
    for (name, frames) in [
        ("caustic-ring", 8),
        ("cornell-glass", 8),
        ("mirror-shadow", 24),
        ("ring-room", 16),
    ] {
        let s = bidir_settings(32)
            .with("max_depth", 7)
            .with("bundles", 64)
            .with("spp", 4);
        failures.extend(depth_7_failures(name, &s, frames, 0.007));
    }
    assert!(failures.is_empty(), "{failures:?}");
}
