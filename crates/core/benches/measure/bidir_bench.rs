//! Method `bidir` (Tokuyoshi & Ogaki 2012): frame time by stage (the paper's Table 1) and an
//! equal-error comparison against `ispm` and `path` on `cornell`. Markdown to stdout:
//!
//! `cargo run -p gi-core --profile test --example bidir_bench >> docs/bench/bidir.md`
//!
//! Options: `--table-only`, `--equal-error-only`, `--frames N` (timed frames per size, 3).
//!
//! 1. Stages: a `Renderer` per size (640×480, 1280×720) with the defaults of `bidir`
//!    (64 VPLs, 16 bundles of 128², 16 direct-light samples per pixel); one warm-up frame,
//!    then the mean of `--frames` frames with fresh seeds. GPU stages are timestamp-query
//!    times, the rest wall clock.
//! 2. Equal error at 160×120, all methods limited to two indirect bounces (`max_depth` 3,
//!    what `bidir` computes): the converged image is `path` at 2048 spp; `bidir` at three
//!    VPL/bundle budgets and `ispm` at its defaults, each frame timed on a warm renderer;
//!    then `path` at 1, 2, 4, … spp until its RMSE is at most theirs, the time interpolated
//!    log-linearly between the last two counts.

use gi_core::frame::options::BidirStrategy;
use gi_core::scene::builtin;
use gi_core::{render, Silent};
use gi_core::{FrameDesc, Image, Images, Method, Renderer, Scene, SceneUpdate};
use std::collections::BTreeMap;
use std::time::Instant;

fn rmse(a: &Image, b: &Image) -> f64 {
    let n = a.pixels.len() as f64 * 3.0;
    (a.pixels
        .iter()
        .zip(&b.pixels)
        .map(|(x, y)| (*x - *y).as_dvec3().length_squared())
        .sum::<f64>()
        / n)
        .sqrt()
}

/// One warm frame of `settings`: (seconds, radiance, stats stages).
fn warm_frame(
    scene: &Scene,
    s: &gi_core::RenderOptions,
    seed: u64,
) -> (f64, Image, Vec<(String, f64)>) {
    let mut r = Renderer::new(scene, s).expect("renderer");
    r.render(&FrameDesc::default(), &Silent).expect("warm-up");
    let t = Instant::now();
    let out = r
        .render(
            &FrameDesc {
                seed: Some(seed),
                images: Images::default(),
                serial: false,
                readout: Default::default(),
            },
            &Silent,
        )
        .expect("frame");
    (t.elapsed().as_secs_f64(), out.radiance, out.stats.stages)
}

fn equal_error(curve: &[(u32, f64, f64)], e: f64) -> Option<(f64, f64)> {
    let i = curve.iter().position(|c| c.2 <= e)?;
    let (spp, t, e1) = curve[i];
    match i.checked_sub(1).map(|j| curve[j]) {
        Some((p_spp, p_t, p_e)) if p_e > e1 => {
            let f = (e.ln() - p_e.ln()) / (e1.ln() - p_e.ln());
            let lerp = |a: f64, b: f64| (a.ln() + f * (b.ln() - a.ln())).exp();
            Some((lerp(p_spp as f64, spp as f64), lerp(p_t, t)))
        }
        _ => Some((spp as f64, t)),
    }
}

fn stage_table(scene: &Scene, frames: u32) {
    println!("\n## Frame time by stage (Table 1)\n");
    println!(
        "Command: `cargo run -p gi-core --profile test --example bidir_bench -- --table-only` · \
         `cornell` (34 triangles, one point light) · defaults: 64 VPLs (cube shadow maps \
         128²), 16 ray bundles of 128², RSM 64² per face, 16 direct-light samples per pixel, \
         max_depth 64 (one- and two-bounce indirect light) · one warm-up frame, then the mean \
         of {frames} frames, each after a light update (shadow maps and direct light redrawn) \
         · GPU passes (rsm, shadow maps, gbuffer, direct light, vpl shadow maps, ray \
         bundles, bidir lighting, composite) are timestamp-query times; `rsm readback` and \
         `readback` are the CPU's waits for the GPU, so the GPU passes run inside them and \
         the rows do not add up to the frame · {}\n",
        gi_core::gpu::adapter_report(None)
            .unwrap_or_default()
            .lines()
            .next()
            .unwrap_or("")
    );
    let sizes = [(640u32, 480u32), (1280, 720)];
    let mut rows: Vec<(String, Vec<f64>)> = Vec::new();
    let mut totals = Vec::new();
    let mut order: Vec<String> = Vec::new();
    let mut per_size: Vec<BTreeMap<String, f64>> = Vec::new();
    for (w, h) in sizes {
        let s = gi_core::RenderOptions::defaults(Method::Bidir)
            .with("width", w)
            .with("height", h);
        let mut r = Renderer::new(scene, &s).expect("renderer");
        r.render(&FrameDesc::default(), &Silent).expect("warm-up");
        let mut sums: BTreeMap<String, f64> = BTreeMap::new();
        let mut total = 0.0;
        let light = scene.light_desc(0).expect("a light");
        for f in 0..frames {
            // The light "moves" (is set to itself) before every frame: shadow maps and the
            // direct light are redrawn too, the fully dynamic case of the paper's Table 1.
            r.update(&SceneUpdate::Light {
                index: 0,
                light: light.clone(),
            })
            .expect("update");
            let t = Instant::now();
            let out = r
                .render(
                    &FrameDesc {
                        seed: Some(100 + f as u64),
                        images: Images::default(),
                        serial: false,
                        readout: Default::default(),
                    },
                    &Silent,
                )
                .expect("frame");
            total += t.elapsed().as_secs_f64();
            for (name, sec) in out.stats.stages {
                if !order.contains(&name) {
                    order.push(name.clone());
                }
                *sums.entry(name).or_default() += sec;
            }
        }
        for v in sums.values_mut() {
            *v /= frames as f64;
        }
        per_size.push(sums);
        totals.push(total / frames as f64);
    }
    for name in &order {
        rows.push((
            name.clone(),
            per_size
                .iter()
                .map(|m| m.get(name).copied().unwrap_or(0.0))
                .collect(),
        ));
    }
    println!("| stage | 640×480 (ms) | 1280×720 (ms) |");
    println!("|---|---|---|");
    for (name, v) in &rows {
        println!("| {name} | {:.1} | {:.1} |", v[0] * 1e3, v[1] * 1e3);
    }
    println!(
        "| **frame** | **{:.1}** | **{:.1}** |",
        totals[0] * 1e3,
        totals[1] * 1e3
    );
}

fn equal_error_table(scene: &Scene) {
    let (w, h) = (160, 120);
    let base = gi_core::options!(Path, width: w, height: h, max_depth: 3);
    println!("\n## Equal error against `ispm` and `path` (cornell)\n");
    println!(
        "Command: `cargo run -p gi-core --profile test --example bidir_bench -- \
         --equal-error-only` · {w}×{h} · every method limited to two indirect bounces \
         (`max_depth` 3, what `bidir` computes) · converged image: `path` at 2048 spp · \
         frames timed on a warm renderer · wall-clock seconds on the same 2 shared cores \
         (lavapipe).\n"
    );
    let reference = render(scene, &base.clone().with("spp", 2048), &Silent)
        .expect("reference")
        .radiance;
    let mut entries: Vec<(String, f64, f64)> = Vec::new();
    for (vpls, bundles) in [(16u32, 8u32), (64, 16), (128, 32)] {
        let s = base
            .clone()
            .with_method(gi_core::Method::Bidir)
            .with("spp", 4)
            .with("vpls_per_light", vpls)
            .with("bundles", bundles)
            .with("bidir_strategy", BidirStrategy::Mis);
        let (t, img, _) = warm_frame(scene, &s, 11);
        entries.push((
            format!("`bidir` {vpls} VPLs, {bundles} bundles, 4 spp"),
            t,
            rmse(&img, &reference),
        ));
    }
    let s = gi_core::RenderOptions::defaults(Method::Ispm)
        .with("width", w)
        .with("height", h)
        .with("max_depth", 3);
    let (t, img, _) = warm_frame(scene, &s, 11);
    entries.push((
        "`ispm` defaults (200k photons)".into(),
        t,
        rmse(&img, &reference),
    ));
    let target = entries.iter().map(|e| e.2).fold(f64::INFINITY, f64::min);
    let mut curve = Vec::new();
    let mut spp = 1;
    loop {
        let s = base.clone().with("spp", spp).with("seed", 5);
        let t = Instant::now();
        let img = render(scene, &s, &Silent).expect("path").radiance;
        let e = rmse(&img, &reference);
        curve.push((spp, t.elapsed().as_secs_f64(), e));
        if e <= target || spp >= 1024 {
            break;
        }
        spp *= 2;
    }
    println!("| method | frame (s) | RMSE | `path` spp at equal RMSE | `path` time (s) | speed-up over `path` |");
    println!("|---|---|---|---|---|---|");
    for (name, t, e) in &entries {
        match equal_error(&curve, *e) {
            Some((spp, pt)) => println!(
                "| {name} | {t:.3} | {e:.4} | {spp:.1} | {pt:.3} | {:.2}× |",
                pt / t
            ),
            None => println!("| {name} | {t:.3} | {e:.4} | > 1024 | – | – |"),
        }
    }
    println!("\n`path` curve (spp, s, RMSE): {}", {
        let v: Vec<String> = curve
            .iter()
            .map(|(s, t, e)| format!("({s}, {t:.2}, {e:.4})"))
            .collect();
        v.join(", ")
    });
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let frames = args
        .iter()
        .position(|a| a == "--frames")
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    let scene = builtin::load("cornell").expect("built-in scene");
    if !args.iter().any(|a| a == "--equal-error-only") {
        stage_table(&scene, frames);
    }
    if !args.iter().any(|a| a == "--table-only") {
        equal_error_table(&scene);
    }
}
