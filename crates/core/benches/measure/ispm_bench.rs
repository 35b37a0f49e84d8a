//! Frame time of method `ispm` split by stage (wall-clock seconds per stage as recorded in
//! `RenderStats::stages`), as a markdown table.
//!
//! `cargo run -p gi-core --profile test --example ispm_bench [-- --runs N]`
//!
//! Built-in `cornell` and `cornell-glass` at 640×480, one direct sample per pixel, shadow
//! maps 1024², several photon budgets and subsample 1 and 2; median of N frames after one
//! warm-up frame (pipelines compiled).

mod common;

use gi_core::Silent;
use gi_core::{render, scene::builtin};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::get();
    let runs = args.runs(3)?;
    common::print_adapter()?;
    // Stage groups: (column, stage names summed). GPU passes are timestamp times; the
    // readbacks are the CPU's waits, which include GPU work still running.
    let groups: [(&str, &[&str]); 9] = [
        (
            "direct light (GPU)",
            &["shadow maps", "gbuffer", "direct light", "edge shading"],
        ),
        ("bounce maps (GPU)", &["bounce maps"]),
        ("bounce readback", &["bounce readback"]),
        ("cpu trace", &["cpu trace"]),
        ("boundary compensation", &["boundary compensation"]),
        ("specular paths", &["specular paths"]),
        (
            "indirect estimate (GPU)",
            &["photon volumes", "tiled binning", "tiled shading"],
        ),
        ("upsample + composite (GPU)", &["upsample", "composite"]),
        ("readback", &["readback"]),
    ];
    println!(
        "| scene | photons | subsample | stored | {} | frame |",
        groups.map(|g| format!("{} (ms)", g.0)).join(" | ")
    );
    println!("|---|---|---|---|{}---|", "---|".repeat(groups.len()));
    // `--scene NAME` (repeatable) picks scenes; "dense-cornell" is the ~246k-triangle
    // Cornell box of `scene::bench`.
    let mut names = args.values("--scene");
    if names.is_empty() {
        names = vec!["cornell", "cornell-glass"];
    }
    for name in names {
        let scene = if name == "dense-cornell" {
            gi_core::scene::bench::dense_cornell()
        } else {
            builtin::load(name)?
        };
        for photons in [50_000u64, 100_000, 200_000] {
            for subsample in [1u32, 2] {
                let settings = gi_core::options!(Ispm, spp: 1, width: 640, height: 480, photons: photons, subsample: subsample);
                render(&scene, &settings, &Silent)?;
                let mut samples: Vec<Vec<f64>> = vec![Vec::new(); groups.len() + 1];
                let mut present = vec![false; groups.len() + 1];
                present[groups.len()] = true;
                let mut stored = 0;
                for _ in 0..runs {
                    let out = render(&scene, &settings, &Silent)?;
                    stored = out.stats.photons_stored;
                    for (i, (_, names)) in groups.iter().enumerate() {
                        present[i] |= out
                            .stats
                            .stages
                            .iter()
                            .any(|(n, _)| names.contains(&n.as_str()));
                        let t: f64 = out
                            .stats
                            .stages
                            .iter()
                            .filter(|(n, _)| names.contains(&n.as_str()))
                            .map(|(_, t)| t)
                            .sum();
                        samples[i].push(t * 1e3);
                    }
                    samples[groups.len()].push(out.stats.total_seconds * 1e3);
                }
                let medians: Vec<String> = samples
                    .iter_mut()
                    .zip(&present)
                    .map(|(v, &p)| {
                        v.sort_by(f64::total_cmp);
                        if p {
                            format!("{:.1}", v[v.len() / 2])
                        } else {
                            "–".to_string()
                        }
                    })
                    .collect();
                println!(
                    "| {name} | {photons} | {subsample} | {stored} | {} |",
                    medians.join(" | ")
                );
            }
        }
    }
    Ok(())
}
