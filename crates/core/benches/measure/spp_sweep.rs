//! Default direct-light samples per pixel of the GPU methods, chosen by measurement: ISPM at
//! several `spp` against a converged path-traced image of the same scene (RMSE and mean
//! relative error of 8×8 blocks), with the frame time, as a markdown table.
//!
//! `cargo run -p gi-core --profile test --example spp_sweep [-- --ref-spp N]`
//!
//! 160×120, 200k photons, other settings default; reference: `path` at `--ref-spp`
//! (default 2048) samples per pixel.

use gi_core::Silent;
use gi_core::{render, scene::builtin, Image};
use std::time::Instant;

fn block_error(a: &Image, b: &Image) -> f64 {
    let (w, h) = (a.width as usize, a.height as usize);
    let mut sum = 0.0;
    let mut n = 0;
    for by in (0..h).step_by(8) {
        for bx in (0..w).step_by(8) {
            let (mut sa, mut sb) = (0.0f64, 0.0f64);
            for y in by..(by + 8).min(h) {
                for x in bx..(bx + 8).min(w) {
                    sa += a.pixels[y * w + x].element_sum() as f64;
                    sb += b.pixels[y * w + x].element_sum() as f64;
                }
            }
            if sb > 0.0 {
                sum += (sa - sb).abs() / sb;
                n += 1;
            }
        }
    }
    sum / n.max(1) as f64
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let ref_spp: u32 = match args.iter().position(|a| a == "--ref-spp") {
        Some(i) => args.get(i + 1).ok_or("--ref-spp needs a value")?.parse()?,
        None => 2048,
    };
    println!("| scene | spp | RMSE vs path | block error | frame (ms) |");
    println!("|---|---|---|---|---|");
    for name in ["cornell", "cornell-glass"] {
        let scene = builtin::load(name)?;
        let base = gi_core::options!(Path, width: 160, height: 120);
        let reference = render(
            &scene,
            &base
                .clone()
                .with_method(gi_core::Method::Path)
                .with("spp", ref_spp),
            &Silent,
        )?;
        for spp in [1, 4, 16, 64] {
            let s = base
                .clone()
                .with_method(gi_core::Method::Ispm)
                .with("spp", spp)
                .with("photons", 200_000);
            render(&scene, &s, &Silent)?;
            let t = Instant::now();
            let out = render(&scene, &s, &Silent)?;
            let ms = t.elapsed().as_secs_f64() * 1e3;
            println!(
                "| {name} | {spp} | {:.4} | {:.2}% | {ms:.0} |",
                out.radiance.rmse(&reference.radiance),
                100.0 * block_error(&out.radiance, &reference.radiance)
            );
        }
    }
    Ok(())
}
