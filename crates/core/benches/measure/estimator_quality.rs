//! Image quality of each indirect estimator against the `path` reference, like Moreau et
//! al.'s Table 2: PSNR and SSIM (luminance, `Image::psnr`/`ssim`) of the final `ispm` image
//! at the default settings (200k photons, 16 direct samples, subsample 2) with each
//! estimator, on `cornell`, `cornell-glass` and the ~246k-triangle `dense-cornell`.
//!
//! `cargo run -p gi-core --profile test --example estimator_quality [-- --spp N --size WxH]`
//!
//! The reference is the mean of two `path` renders of N spp each (default 256; light paths
//! add the caustics) with different seeds; the row "reference (one half vs the other)" is
//! the PSNR/SSIM of one half against the other: the reference's own noise, the ceiling of
//! what the table can resolve.

use gi_core::estimate::Estimator;
use gi_core::scene::{bench::dense_cornell, builtin};
use gi_core::Silent;
use gi_core::{render, Image, Method, Scene};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
    };
    let spp: u32 = arg("--spp").map(|s| s.parse()).transpose()?.unwrap_or(256);
    let (w, h): (u32, u32) = match arg("--size") {
        Some(s) => {
            let (a, b) = s.split_once('x').ok_or("--size WxH")?;
            (a.parse()?, b.parse()?)
        }
        None => (256, 192),
    };
    let scenes: Vec<(&str, Scene)> = vec![
        ("cornell", builtin::load("cornell")?),
        ("cornell-glass", builtin::load("cornell-glass")?),
        ("dense-cornell", dense_cornell()),
    ];
    println!("Size {w}×{h}; reference: `path`, 2 × {spp} spp.\n");
    println!("| scene | estimator | PSNR (dB) | SSIM | estimate (ms) |");
    println!("|---|---|---|---|---|");
    for (name, scene) in &scenes {
        let path = |seed| gi_core::options!(Path, spp: spp, seed: seed, width: w, height: h);
        let a = render(scene, &path(1), &Silent)?.radiance;
        let b = render(scene, &path(2), &Silent)?.radiance;
        let reference = Image {
            pixels: a
                .pixels
                .iter()
                .zip(&b.pixels)
                .map(|(x, y)| 0.5 * (*x + *y))
                .collect(),
            ..a.clone()
        };
        println!(
            "| {name} | reference (one half vs the other) | {:.2} | {:.4} | |",
            a.psnr(&b),
            a.ssim(&b)
        );
        for estimator in [
            Estimator::Volumes,
            Estimator::Tiled,
            Estimator::Cluster,
            Estimator::Directional,
        ] {
            let settings = gi_core::RenderOptions::defaults(Method::Ispm)
                .with("width", w)
                .with("height", h)
                .with("estimator", estimator);
            let out = render(scene, &settings, &Silent)?;
            let ms: f64 = out
                .stats
                .stages
                .iter()
                .filter(|(n, _)| {
                    [
                        "photon volumes",
                        "tiled binning",
                        "tiled shading",
                        "cluster hierarchy",
                        "cluster binning",
                        "cluster shading",
                        "directional shading",
                    ]
                    .contains(&n.as_str())
                })
                .map(|(_, s)| s * 1e3)
                .sum();
            println!(
                "| {name} | {} | {:.2} | {:.4} | {ms:.0} |",
                estimator.name(),
                reference.psnr(&out.radiance),
                reference.ssim(&out.radiance)
            );
        }
    }
    Ok(())
}
