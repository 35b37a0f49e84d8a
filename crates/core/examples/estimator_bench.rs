//! Time of the indirect estimators (`Settings::estimator`) over the same photons, as a
//! markdown table: photon count × kernel scale × image size, one `Renderer` per row and
//! estimator. After the frame that traces the photons, the camera moves by a hair every
//! frame, so every frame splats the same photons again (the trace is reused); the time is the
//! estimator's GPU passes from timestamp queries (volumes: "photon volumes"; tiled: "tiled
//! binning" + "tiled shading"; the upsampling, the same for all, is left out), median of N.
//!
//! `cargo run -p gi-core --profile test --example estimator_bench [-- --runs N --quick]`

use gi_core::estimate::Estimator;
use gi_core::frame::{FrameDesc, Renderer};
use gi_core::render::Silent;
use gi_core::scene::{builtin, SceneUpdate};
use gi_core::{Method, RenderOutput, Scene, Settings};
use std::time::Instant;

const ESTIMATORS: [Estimator; 2] = [Estimator::Volumes, Estimator::Tiled];

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn stage(out: &RenderOutput, names: &[&str]) -> f64 {
    out.stats
        .stages
        .iter()
        .filter(|(n, _)| names.contains(&n.as_str()))
        .map(|(_, s)| s)
        .sum()
}

fn estimate_seconds(out: &RenderOutput) -> f64 {
    stage(out, &["photon volumes", "tiled binning", "tiled shading"])
}

struct Measured {
    estimate: f64,
    /// Tiled: binning and shading separately.
    binning: f64,
    shading: f64,
    frame: f64,
    photons: u64,
    memory: u64,
}

fn measure(
    scene: &Scene,
    settings: &Settings,
    runs: usize,
) -> Result<Measured, Box<dyn std::error::Error>> {
    let mut r = Renderer::new(scene, settings)?;
    let first = r.render(&FrameDesc::default(), &Silent)?;
    let mut camera = r.scene().camera_desc();
    let (mut est, mut wall, mut bin, mut shade) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for i in 0..runs {
        camera.fov += if i % 2 == 0 { 1e-3 } else { -1e-3 };
        r.update(&SceneUpdate::Camera(camera.clone()))?;
        let t = Instant::now();
        let out = r.render(&FrameDesc::default(), &Silent)?;
        wall.push(t.elapsed().as_secs_f64());
        est.push(estimate_seconds(&out));
        bin.push(stage(&out, &["tiled binning"]));
        shade.push(stage(&out, &["tiled shading"]));
    }
    Ok(Measured {
        estimate: median(est),
        binning: median(bin),
        shading: median(shade),
        frame: median(wall),
        photons: first.stats.photons_stored,
        memory: first.stats.estimator_memory.iter().map(|(_, b)| b).sum(),
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let runs: usize = match args.iter().position(|a| a == "--runs") {
        Some(i) => args.get(i + 1).ok_or("--runs needs a value")?.parse()?,
        None => 3,
    };
    let quick = args.iter().any(|a| a == "--quick");
    println!(
        "{}\n",
        gi_core::gpu::adapter_report(None)?
            .lines()
            .take(4)
            .collect::<Vec<_>>()
            .join("; ")
    );
    let scene = builtin::load("cornell")?;
    let sizes: &[(u32, u32)] = if quick {
        &[(640, 480)]
    } else {
        &[(640, 480), (1280, 720)]
    };
    let budgets: &[u64] = if quick {
        &[20_000, 200_000]
    } else {
        &[10_000, 50_000, 200_000, 1_000_000]
    };
    let scales: &[f32] = if quick { &[1.0] } else { &[0.5, 1.0, 2.0] };
    println!(
        "| size | photons | kernel scale | stored | volumes (ms) | tiled (ms) | tiled / volumes \
         | fastest | tiled binning (ms) | tiled shading (ms) | volumes frame (ms) | tiled frame (ms) \
         | volumes memory (MiB) | tiled memory (MiB) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    for &(w, h) in sizes {
        for &photons in budgets {
            for &kernel_scale in scales {
                let mut m = Vec::new();
                for estimator in ESTIMATORS {
                    let settings = Settings {
                        method: Method::Ispm,
                        width: Some(w),
                        height: Some(h),
                        spp: 16,
                        photons,
                        kernel_scale,
                        estimator,
                        ..Default::default()
                    };
                    m.push(measure(&scene, &settings, runs)?);
                }
                let (v, t) = (&m[0], &m[1]);
                let fastest = if t.estimate < v.estimate {
                    "tiled"
                } else {
                    "volumes"
                };
                println!(
                    "| {w}×{h} | {photons} | {kernel_scale} | {} | {:.1} | {:.1} | {:.2} | {fastest} \
                     | {:.1} | {:.1} | {:.0} | {:.0} | {:.1} | {:.1} |",
                    v.photons,
                    v.estimate * 1e3,
                    t.estimate * 1e3,
                    t.estimate / v.estimate,
                    t.binning * 1e3,
                    t.shading * 1e3,
                    v.frame * 1e3,
                    t.frame * 1e3,
                    mib(v.memory),
                    mib(t.memory),
                );
            }
        }
    }
    Ok(())
}
