//! Temporal photon reuse (Jozwowski 2002) on a scene with a static light and one moving
//! object: ISPM with and without reuse, each frame against a converged path-traced image of
//! the same pose, and the frame times, as a markdown table.
//!
//! `cargo run -p gi-core --profile test --example temporal_bench [-- --frames N --ref-spp S
//!  --size WxH --ref-photons P]`
//!
//! Built-in `cornell` (default 96×72); its tall box slides 2 cm a frame; 20k photons traced
//! per frame in both runs; reuse keeps the last 4 frames (`temporal_frames` = 4), so it
//! splats up to 4× the photons with kernels sized for them. RMSE per frame against `path` at
//! `--ref-spp` samples (default 512), or with `--ref-photons P` against ISPM with P photons
//! (converged for the estimator: isolates the noise that reuse averages); mean over the
//! frames after the ring filled (4..N).

use gi_core::frame::{FrameDesc, Renderer};
use gi_core::render;
use gi_core::scene::{builtin, SceneUpdate};
use gi_core::Silent;
use glam::{Mat4, Vec3};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |name: &str, default: u32| -> Result<u32, Box<dyn std::error::Error>> {
        Ok(match args.iter().position(|a| a == name) {
            Some(i) => args.get(i + 1).ok_or("missing value")?.parse()?,
            None => default,
        })
    };
    let frames = arg("--frames", 10)?;
    let ref_spp = arg("--ref-spp", 512)?;
    let ref_photons = arg("--ref-photons", 0)?;
    let (width, height) = match args.iter().position(|a| a == "--size") {
        Some(i) => {
            let v = args.get(i + 1).ok_or("--size needs WxH")?;
            let (w, h) = v.split_once('x').ok_or("--size needs WxH")?;
            (w.parse()?, h.parse()?)
        }
        None => (96, 72),
    };
    let scene = builtin::load("cornell")?;
    let object = scene.objects.len() - 1;
    let start = scene.objects[object].transform;
    let pose = |f: u32| SceneUpdate::Transform {
        object,
        transform: Mat4::from_translation(Vec3::new(0.02 * f as f32, 0.0, -0.01 * f as f32))
            * start,
    };
    let base = gi_core::options!(Ispm, width: width, height: height, spp: 4, photons: 20_000);
    // Converged references, one per pose.
    let mut references = Vec::new();
    for f in 0..frames {
        let mut posed = scene.clone();
        posed.apply(&pose(f))?;
        let s = if ref_photons > 0 {
            base.clone().with("photons", ref_photons as u64)
        } else {
            base.clone()
                .with_method(gi_core::Method::Path)
                .with("spp", ref_spp)
        };
        references.push(render(&posed, &s, &Silent)?.radiance);
    }
    println!("| frame | RMSE without reuse | RMSE with reuse (4 frames) | ms without | ms with |");
    println!("|---|---|---|---|---|");
    let run = |s: &gi_core::RenderOptions| -> Result<Vec<(f64, f64)>, Box<dyn std::error::Error>> {
        let mut r = Renderer::new(&scene, s)?;
        let mut rows = Vec::new();
        for f in 0..frames {
            r.update(&pose(f))?;
            let t = Instant::now();
            let out = r.render(&FrameDesc::default(), &Silent)?;
            let ms = t.elapsed().as_secs_f64() * 1e3;
            rows.push((out.radiance.rmse(&references[f as usize]), ms));
        }
        Ok(rows)
    };
    let mut runs = Vec::new();
    for temporal_frames in [1, 4] {
        runs.push(run(&base.clone().with("temporal_frames", temporal_frames))?);
    }
    for (f, (a, b)) in runs[0].iter().zip(&runs[1]).enumerate() {
        println!(
            "| {f} | {:.4} | {:.4} | {:.0} | {:.0} |",
            a.0, b.0, a.1, b.1
        );
    }
    let mean = |rows: &[(f64, f64)], i: usize| {
        let tail = &rows[4.min(rows.len() - 1)..];
        tail.iter()
            .map(|r| if i == 0 { r.0 } else { r.1 })
            .sum::<f64>()
            / tail.len() as f64
    };
    println!(
        "| mean of frames 4.. | {:.4} | {:.4} | {:.0} | {:.0} |",
        mean(&runs[0], 0),
        mean(&runs[1], 0),
        mean(&runs[0], 1),
        mean(&runs[1], 1)
    );
    // Equal frame time: no reuse, with the photons scaled by the time ratio.
    let scale = mean(&runs[1], 1) / mean(&runs[0], 1);
    let gi_core::MethodOptions::Ispm(o) = &base.method else {
        unreachable!("ispm options")
    };
    let photons = (o.photons as f64 * scale).round() as u64;
    let equal = run(&base.clone().with("photons", photons))?;
    println!(
        "\nEqual time: without reuse at {photons} photons a frame ({scale:.2}× the photons, the \
         reuse run's time ratio): mean RMSE of frames 4.. {:.4} in {:.0} ms, against {:.4} with \
         reuse.",
        mean(&equal, 0),
        mean(&equal, 1),
        mean(&runs[1], 0)
    );
    Ok(())
}
