//! GPU times of the raster passes of method `direct` (timestamp queries), as a markdown table.
//!
//! `cargo run -p gi-core --profile test --example raster_bench [-- --runs N]`
//!
//! Built-in Cornell box (one point light: six cube shadow faces of 1024²), one sample per
//! pixel, median of N frames after one warm-up frame (pipelines compiled).

mod common;

use gi_core::Silent;
use gi_core::{render, scene::builtin};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::get();
    let runs = args.runs(5)?;
    let scene = builtin::load("cornell")?;
    common::print_adapter()?;
    let stages = [
        "shadow maps",
        "gbuffer",
        "direct light",
        "edge shading",
        "readback",
    ];
    println!(
        "| resolution | {} | frame (wall) |",
        stages.map(|s| format!("{s} (ms)")).join(" | ")
    );
    println!("|---|{}---|", "---|".repeat(stages.len()));
    for (w, h) in [(640, 480), (1280, 720)] {
        let settings =
            gi_core::options!(Direct, spp: 1, width: w, height: h, shadow_map_size: 1024);
        render(&scene, &settings, &Silent)?;
        let mut samples: Vec<Vec<f64>> = vec![Vec::new(); stages.len() + 1];
        for _ in 0..runs {
            let out = render(&scene, &settings, &Silent)?;
            for (i, stage) in stages.iter().enumerate() {
                let t: f64 = out
                    .stats
                    .stages
                    .iter()
                    .filter(|(n, _)| n == stage)
                    .map(|(_, t)| t)
                    .sum();
                samples[i].push(t * 1e3);
            }
            samples[stages.len()].push(out.stats.total_seconds * 1e3);
        }
        let medians: Vec<String> = samples
            .iter_mut()
            .map(|v| {
                v.sort_by(f64::total_cmp);
                format!("{:.2}", v[v.len() / 2])
            })
            .collect();
        println!("| {w}×{h} | {} |", medians.join(" | "));
    }
    Ok(())
}
