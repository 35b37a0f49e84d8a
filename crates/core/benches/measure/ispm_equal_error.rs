//! Equal-error speed-up of ISPM over the reference path tracer, and ISPM on a scene of
//! ≥100k triangles. Markdown to stdout:
//!
//! `cargo run -p gi-core --profile test --example ispm_equal_error >> docs/bench/ispm.md`
//!
//! For each scene: a converged image (`path`, 2048 spp); the RMSE of ISPM frames against it
//! (subsample 1; `kernel_scale` 1/3, about the narrower volumes of diffuse photons
//! before boundary compensation; the defaults, subsample 2); then `path` at 1, 2, 4, … spp until its RMSE
//! is at most ISPM's, interpolating the time log-linearly between the last two counts.

use gi_core::scene::{bench::dense_cornell, builtin};
use gi_core::{render, Silent};
use gi_core::{Image, Scene};
use std::time::Instant;

const W: u32 = 160;
const H: u32 = 120;

fn timed(scene: &Scene, s: &gi_core::RenderOptions) -> (f64, Image) {
    let t = Instant::now();
    let out = render(scene, s, &Silent).expect("render");
    (t.elapsed().as_secs_f64(), out.radiance)
}

/// The path tracer's spp and time at error `e` on its measured curve (spp, time, error):
/// the first count at or below `e`, log(time) interpolated against log(error) from the
/// count before it.
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

fn main() {
    println!("\n## Equal-error speed-up against `path`\n");
    println!("Command: `cargo run -p gi-core --profile test --example ispm_equal_error >> docs/bench/ispm.md`");
    println!(
        "· {W}×{H} · converged image: `path` at 2048 spp · ISPM: 200k photons, 4 direct-light"
    );
    println!(
        "samples per pixel, warm pipelines · wall-clock seconds on the same 2 cores (lavapipe).\n"
    );
    println!("| scene | triangles | ISPM settings | ISPM frame (s) | ISPM RMSE | `path` spp at equal RMSE | `path` time (s) | speed-up |");
    println!("|---|---|---|---|---|---|---|---|");
    let scenes = [
        ("cornell", builtin::load("cornell").expect("built-in")),
        ("dense cornell", dense_cornell()),
    ];
    for (name, scene) in &scenes {
        let base = gi_core::options!(Path, width: W, height: H);
        let (_, converged) = timed(scene, &base.clone().with("spp", 2048).with("seed", 99));
        let configs = [
            ("subsample 1", 1.0, 1),
            ("kernel_scale 1/3, subsample 1", 1.0 / 3.0, 1),
            ("defaults (subsample 2)", 1.0, 2),
        ];
        let results: Vec<(&str, f64, f64)> = configs
            .iter()
            .map(|&(label, kernel_scale, subsample)| {
                let ispm = base
                    .clone()
                    .with_method(gi_core::Method::Ispm)
                    .with("spp", 4)
                    .with("photons", 200_000)
                    .with("kernel_scale", kernel_scale)
                    .with("subsample", subsample);
                let _ = timed(scene, &ispm); // warm-up: pipelines, device
                let (t, img) = timed(scene, &ispm);
                (label, t, img.rmse(&converged))
            })
            .collect();
        // The path tracer's error and time against spp, once per scene, down to the
        // smallest ISPM error.
        let target = results.iter().map(|r| r.2).fold(f64::INFINITY, f64::min);
        let mut curve: Vec<(u32, f64, f64)> = Vec::new();
        for k in 0..11 {
            let spp = 1u32 << k;
            let (t, img) = timed(scene, &base.clone().with("spp", spp).with("seed", k as u64));
            curve.push((spp, t, img.rmse(&converged)));
            if curve[curve.len() - 1].2 <= target {
                break;
            }
        }
        for (label, t_ispm, e_ispm) in results {
            let prefix = format!(
                "| {name} | {} | {label} | {t_ispm:.2} | {e_ispm:.4} |",
                scene.triangle_count()
            );
            match equal_error(&curve, e_ispm) {
                Some((spp_eq, t_eq)) => {
                    println!("{prefix} {spp_eq:.1} | {t_eq:.2} | {:.2}× |", t_eq / t_ispm)
                }
                None => println!("{prefix} > 1024 | – | – |"),
            }
        }
    }
    println!("\nA speed-up below 1 means the path tracer reaches ISPM's error sooner on this machine, where");
    println!(
        "ISPM's photon-volume splat is software rasterization (lavapipe) on the same two cores."
    );
}
