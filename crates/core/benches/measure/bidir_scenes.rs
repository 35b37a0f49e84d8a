//! `bidir` against `path` at `max_depth` 7 on the built-in scenes (issue 29): the image
//! means (RGB average) of `path` and of `bidir` frames (mean ± standard error over them), and
//! `path`'s image split into the terms that `bidir` draws on the CPU (its
//! `frame/bidir/specular_paths.rs`): the light tracer's (`path` minus `path` with
//! `light_paths` 0: the paths whose first bounce from the light is a delta lobe) and the
//! pixels whose camera ray meets a mirror or glass first (their share of the image mean).
//! Markdown to stdout:
//!
//! `cargo run -p gi-core --profile test --example bidir_scenes -- --frames 16 --spp 1024`
//!
//! Options: `--scenes a,b` (every built-in scene and `dense-cornell`), `--size N` (32),
//! `--frames N` (`bidir` frames, seeds 1…N, 16), `--spp N` (`path`, 1024), `--bundles N`
//! (`bidir`, 32), `--depth N` (7), `--stages 1` (the first `bidir` frame's stages to stderr), `--set KEY=N`
//! (repeatable: an integer setting of `bidir`).

mod common;

use gi_core::scene::{bench, builtin};
use gi_core::{render, Image, Scene, Silent};
use std::time::Instant;

fn mean(img: &Image) -> f64 {
    img.pixels
        .iter()
        .map(|p| p.as_dvec3().element_sum() / 3.0)
        .sum::<f64>()
        / img.pixels.len() as f64
}

/// Relative MSE of `img` against `reference`: mean of (a − b)² / (b² + 0.01), RGB averaged.
fn relmse(img: &Image, reference: &Image) -> f64 {
    img.pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(a, b)| {
            let (a, b) = (a.as_dvec3(), b.as_dvec3());
            ((a - b) * (a - b) / (b * b + 0.01)).element_sum() / 3.0
        })
        .sum::<f64>()
        / img.pixels.len() as f64
}

/// The image mean over the pixels whose first surface (through the pixel centre) has a
/// delta lobe, times their share of the pixels.
fn delta_share(scene: &Scene, img: &Image) -> f64 {
    let bvh = gi_core::trace::SceneBvh::build(scene);
    let cam = &scene.camera;
    let mut sum = 0.0;
    for y in 0..cam.height {
        for x in 0..cam.width {
            let d = cam.direction(x as f32 + 0.5, y as f32 + 0.5);
            let delta = bvh
                .intersect(cam.position, d, f32::INFINITY)
                .is_some_and(|h| {
                    gi_core::trace::Interaction::new(scene, &h, d)
                        .material
                        .has_delta_lobe()
                });
            if delta {
                let p = img.pixels[(y * cam.width + x) as usize];
                sum += p.as_dvec3().element_sum() / 3.0;
            }
        }
    }
    sum / img.pixels.len() as f64
}

fn main() {
    let args = common::Args::get();
    let all = "cornell,cornell-glass,cornell-anim,caustic-ring,mirror-shadow,ring-room,furnace,\
               dense-cornell";
    let scenes = args.value("--scenes").unwrap_or(all);
    let num = |flag: &str, default: u32| {
        args.value(flag)
            .map_or(default, |v| v.parse().expect("a number"))
    };
    let (size, frames, spp) = (num("--size", 32), num("--frames", 16), num("--spp", 1024));
    let (bundles, depth) = (num("--bundles", 32), num("--depth", 7));
    let stages = args.value("--stages").is_some();
    println!(
        "Command: `cargo run -p gi-core --profile test --example bidir_scenes -- --scenes \
         {scenes} --size {size} --frames {frames} --spp {spp} --bundles {bundles} --depth \
         {depth}` · {size}×{size} · max_depth {depth} · `bidir` {bundles} bundles, other \
         settings default, seeds 1…{frames} · `path` {spp} spp, seed 99 · means of RGB · \
         light-traced: `path` − `path` with light_paths 0 · through delta: the pixels whose \
         first surface is a mirror or glass (their sum over all pixels) · relMSE: of the \
         first `bidir` frame against `path`, (a − b)²/(b² + 0.01).\n"
    );
    println!(
        "| scene | path | light-traced | through delta | bidir (± se) | bidir / path | \
         bidir frame (s) | relMSE (seed 1) |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for name in scenes.split(',') {
        let scene = if name == "dense-cornell" {
            bench::dense_cornell()
        } else {
            builtin::load(name).expect("built-in scene")
        };
        let base = gi_core::options!(Path, spp: spp, width: size, height: size, seed: 99)
            .with("max_depth", depth);
        let full = render(&scene, &base, &Silent).expect("path").radiance;
        let none = render(&scene, &base.clone().with("light_paths", 0), &Silent)
            .expect("path")
            .radiance;
        let mut cam_scene = scene.clone();
        cam_scene.camera = scene.camera.with_size(size, size);
        let p = mean(&full);
        let traced = p - mean(&none);
        let through = delta_share(&cam_scene, &full);
        let t = Instant::now();
        let mut rel_mse = 0.0;
        let b: Vec<f64> = (1..=frames as u64)
            .map(|seed| {
                let mut o = gi_core::options!(Bidir, spp: 1, width: size, height: size, seed: seed)
                    .with("bundles", bundles)
                    .with("max_depth", depth);
                for kv in args.values("--set") {
                    let (k, v) = kv.split_once('=').expect("--set KEY=N");
                    o = o.with(k, v.parse::<i64>().expect("an integer"));
                }
                let out = render(&scene, &o, &Silent).expect("bidir");
                if stages && seed == 1 {
                    eprintln!("{name}: {:?}", out.stats.stages);
                }
                if seed == 1 {
                    rel_mse = relmse(&out.radiance, &full);
                }
                mean(&out.radiance)
            })
            .collect();
        let secs = t.elapsed().as_secs_f64() / frames as f64;
        let n = b.len() as f64;
        let m = b.iter().sum::<f64>() / n;
        let se = (b.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0) / n).sqrt();
        println!(
            "| {name} | {p:.5} | {traced:.5} | {through:.5} | {m:.5} ± {se:.5} | {:.4} ± {:.4} \
             | {secs:.2} | {rel_mse:.4} |",
            m / p,
            se / p
        );
    }
}
