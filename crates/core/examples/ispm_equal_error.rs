//! Equal-error speed-up of ISPM over the reference path tracer, and ISPM on a scene of
//! ≥100k triangles. Markdown to stdout:
//!
//! `cargo run -p gi-core --profile test --example ispm_equal_error >> docs/bench/ispm.md`
//!
//! For each scene: a converged image (`path`, 2048 spp); the ISPM frame's RMSE against it;
//! then `path` at 1, 2, 4, … spp until its RMSE is at most ISPM's, interpolating the time
//! log-linearly between the last two sample counts.

use gi_core::render::{render, Silent};
use gi_core::scene::{bench::dense_cornell, builtin};
use gi_core::{Image, Method, Scene, Settings};
use std::time::Instant;

const W: u32 = 160;
const H: u32 = 120;

fn rmse(a: &Image, b: &Image) -> f64 {
    let s: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(x, y)| (*x - *y).length_squared() as f64)
        .sum();
    (s / (3 * a.pixels.len()) as f64).sqrt()
}

fn timed(scene: &Scene, s: &Settings) -> (f64, Image) {
    let t = Instant::now();
    let out = render(scene, s, &Silent).expect("render");
    (t.elapsed().as_secs_f64(), out.radiance)
}

fn main() {
    println!("\n## Equal-error speed-up against `path`\n");
    println!("Command: `cargo run -p gi-core --profile test --example ispm_equal_error >> docs/bench/ispm.md`");
    println!(
        "· {W}×{H} · converged image: `path` at 2048 spp · ISPM: 200k photons, 4 direct-light"
    );
    println!(
        "samples per pixel, warm pipelines · wall-clock seconds on the same 2 cores (lavapipe).\n"
    );
    println!("| scene | triangles | ISPM frame (s) | ISPM RMSE | `path` spp at equal RMSE | `path` time (s) | speed-up |");
    println!("|---|---|---|---|---|---|---|");
    let scenes = [
        ("cornell", builtin::load("cornell").expect("built-in")),
        ("dense cornell", dense_cornell()),
    ];
    for (name, scene) in &scenes {
        let base = Settings {
            width: Some(W),
            height: Some(H),
            ..Default::default()
        };
        let (_, converged) = timed(
            scene,
            &Settings {
                spp: 2048,
                seed: 99,
                ..base.clone()
            },
        );
        let ispm = Settings {
            method: Method::Ispm,
            spp: 4,
            photons: 200_000,
            ..base.clone()
        };
        let _ = timed(scene, &ispm); // warm-up: pipelines, device
        let (t_ispm, img) = timed(scene, &ispm);
        let e_ispm = rmse(&img, &converged);
        let mut prev: Option<(u32, f64, f64)> = None;
        let mut found = None;
        for k in 0..11 {
            let spp = 1u32 << k;
            let (t, img) = timed(
                scene,
                &Settings {
                    spp,
                    seed: k as u64,
                    ..base.clone()
                },
            );
            let e = rmse(&img, &converged);
            if e <= e_ispm {
                // Interpolate log(time) against log(error) between the last two counts.
                let (spp_eq, t_eq) = match prev {
                    Some((p_spp, p_t, p_e)) if p_e > e => {
                        let f = (e_ispm.ln() - p_e.ln()) / (e.ln() - p_e.ln());
                        let spp_eq =
                            (p_spp as f64).ln() + f * ((spp as f64).ln() - (p_spp as f64).ln());
                        (spp_eq.exp(), (p_t.ln() + f * (t.ln() - p_t.ln())).exp())
                    }
                    _ => (spp as f64, t),
                };
                found = Some((spp_eq, t_eq));
                break;
            }
            prev = Some((spp, t, e));
        }
        match found {
            Some((spp_eq, t_eq)) => println!(
                "| {name} | {} | {t_ispm:.2} | {e_ispm:.4} | {spp_eq:.1} | {t_eq:.2} | {:.2}× |",
                scene.triangles.len(),
                t_eq / t_ispm
            ),
            None => println!(
                "| {name} | {} | {t_ispm:.2} | {e_ispm:.4} | > 1024 | – | – |",
                scene.triangles.len()
            ),
        }
    }
    println!("\nA speed-up below 1 means the path tracer reaches ISPM's error sooner on this machine, where");
    println!(
        "ISPM's photon-volume splat is software rasterization (lavapipe) on the same two cores."
    );
}
