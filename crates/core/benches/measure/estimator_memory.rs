//! GPU memory of each indirect estimator beyond the image targets, by part, like Moreau et
//! al.'s Table 1: the Cornell box at the given size (default 1280×720, subsample 2) with
//! 200k photons, after one frame (so the photon lists have their measured size).
//!
//! `cargo run -p gi-core --profile test --example estimator_memory [-- --size WxH]`

use gi_core::estimate::Estimator;
use gi_core::scene::builtin;
use gi_core::Silent;
use gi_core::{render, Method};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (w, h) = match args.iter().position(|a| a == "--size") {
        Some(i) => {
            let s = args.get(i + 1).ok_or("--size WxH")?;
            let (a, b) = s.split_once('x').ok_or("--size WxH")?;
            (a.parse()?, b.parse()?)
        }
        None => (1280u32, 720u32),
    };
    let scene = builtin::load("cornell")?;
    println!("Cornell box, {w}×{h}, subsample 2, 200k photons.\n");
    println!("| estimator | part | MiB |");
    println!("|---|---|---|");
    for estimator in [
        Estimator::Volumes,
        Estimator::Tiled,
        Estimator::Cluster,
        Estimator::Directional,
    ] {
        let settings = gi_core::RenderOptions::defaults(Method::Ispm)
            .with("width", w)
            .with("height", h)
            .with("spp", 1)
            .with("estimator", estimator);
        let out = render(&scene, &settings, &Silent)?;
        let mut total = 0;
        for (part, bytes) in &out.stats.estimator_memory {
            println!(
                "| {} | {part} | {:.2} |",
                estimator.name(),
                *bytes as f64 / (1 << 20) as f64
            );
            total += bytes;
        }
        println!(
            "| {} | **total** | **{:.2}** |",
            estimator.name(),
            total as f64 / (1 << 20) as f64
        );
    }
    Ok(())
}
