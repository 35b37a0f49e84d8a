//! The CPU specular paths of method `ispm` (mirrors and glass seen by the camera) on
//! `cornell-glass`: `SpecularSampling::Full` (`spp` paths through every pixel, a photon
//! gather at every landing point: the implementation before) against `Adaptive`
//! (`render::delta_paths`), in the same run, as markdown tables.
//!
//! `cargo run -p gi-core --profile test --example specular_bench [-- --runs N --quick]`
//!
//! 1. Steady-state frames of a `Renderer` whose light moves a little before every frame (so
//!    photons, shadows and the specular image are redone, as in `frame_bench`), 16 samples
//!    per pixel: frame time, the "specular paths" stage and its share of the frame; median
//!    of N frames after a warm-up, at 640×480 and 1280×720 for 20k, 50k and 200k photons.
//! 2. Noise at 320×240, 20k photons: RMS error of the `specular` image against a
//!    256-sample `Full` image of the same photons (same seed), and the stage time.
//!
//! `--quick`: 640×480 and 20k photons only, no noise table.

mod common;

use gi_core::frame::options::SpecularSampling;
use gi_core::frame::{FrameDesc, Renderer};
use gi_core::scene::desc::LightDesc;
use gi_core::scene::{builtin, SceneUpdate};
use gi_core::Silent;
use gi_core::{render, Image, RenderOutput, Scene};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn specular_seconds(out: &RenderOutput) -> f64 {
    out.stats
        .stages
        .iter()
        .filter(|(n, _)| n == "specular paths")
        .map(|(_, s)| s)
        .sum()
}

/// Light 0 (a point light in `cornell-glass`) moved by `t` metres along x.
fn nudge(scene: &Scene, t: f32) -> Result<SceneUpdate, Box<dyn std::error::Error>> {
    match scene.light_desc(0).ok_or("no light")? {
        LightDesc::Point {
            position,
            intensity,
        } => Ok(SceneUpdate::Light {
            index: 0,
            light: LightDesc::Point {
                position: [position[0] + t, position[1], position[2]],
                intensity,
            },
        }),
        _ => Err("light 0 is not a point light".into()),
    }
}

/// Median (frame, specular stage) seconds of `runs` steady-state frames.
fn frames(
    scene: &Scene,
    settings: &gi_core::RenderOptions,
    runs: usize,
) -> Result<(f64, f64), Box<dyn std::error::Error>> {
    let mut r = Renderer::new(scene, settings)?;
    r.render(&FrameDesc::default(), &Silent)?;
    let (mut wall, mut stage) = (Vec::new(), Vec::new());
    for i in 0..runs {
        r.update(&nudge(scene, 0.01 * (i + 1) as f32)?)?;
        let t = Instant::now();
        let out = r.render(&FrameDesc::default(), &Silent)?;
        wall.push(t.elapsed().as_secs_f64());
        stage.push(specular_seconds(&out));
    }
    Ok((median(wall), median(stage)))
}

fn specular_image(
    scene: &Scene,
    settings: &gi_core::RenderOptions,
) -> Result<(Image, f64), Box<dyn std::error::Error>> {
    let out = render(scene, settings, &Silent)?;
    let seconds = specular_seconds(&out);
    let img = out
        .aovs
        .into_iter()
        .find(|(n, _)| n == "specular")
        .ok_or("no specular image")?
        .1;
    Ok((img, seconds))
}

fn rmse(a: &Image, b: &Image) -> f64 {
    let sum: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(x, y)| (*x - *y).length_squared() as f64 / 3.0)
        .sum();
    (sum / a.pixels.len() as f64).sqrt()
}

fn mean(a: &Image) -> f64 {
    a.pixels
        .iter()
        .map(|p| (p.x + p.y + p.z) as f64 / 3.0)
        .sum::<f64>()
        / a.pixels.len() as f64
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::get();
    let runs = args.runs(2)?;
    let quick = args.quick();
    common::print_adapter()?;
    let scene = builtin::load("cornell-glass")?;
    let sizes: &[(u32, u32)] = if quick {
        &[(640, 480)]
    } else {
        &[(640, 480), (1280, 720)]
    };
    let budgets: &[u64] = if quick {
        &[20_000]
    } else {
        &[20_000, 50_000, 200_000]
    };
    println!(
        "| size | photons | full: frame (ms) | full: specular (ms) | full: share | \
         adaptive: frame (ms) | adaptive: specular (ms) | adaptive: share | stage speed-up |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for &(w, h) in sizes {
        for &photons in budgets {
            let base = gi_core::options!(Ispm, width: w, height: h, spp: 16, photons: photons);
            let full = base
                .clone()
                .with("specular_sampling", SpecularSampling::Full);
            let (f_frame, f_spec) = frames(&scene, &full, runs)?;
            let (a_frame, a_spec) = frames(&scene, &base, runs)?;
            println!(
                "| {w}×{h} | {photons} | {:.0} | {:.0} | {:.1}% | {:.0} | {:.0} | {:.1}% | {:.1}× |",
                f_frame * 1e3,
                f_spec * 1e3,
                100.0 * f_spec / f_frame,
                a_frame * 1e3,
                a_spec * 1e3,
                100.0 * a_spec / a_frame,
                f_spec / a_spec,
            );
        }
    }
    if quick {
        return Ok(());
    }

    println!("\n| sampling | samples per pixel | specular (ms) | RMS error | mean |");
    println!("|---|---|---|---|---|");
    let base = gi_core::options!(Ispm, width: 320, height: 240, spp: 16, photons: 20_000, seed: 99);
    let full = |spp| {
        base.clone()
            .with("spp", spp)
            .with("specular_sampling", SpecularSampling::Full)
    };
    let (reference, seconds) = specular_image(&scene, &full(256))?;
    println!(
        "| full (reference) | 256 | {:.0} | 0 | {:.5} |",
        seconds * 1e3,
        mean(&reference)
    );
    for (name, settings) in [("full", full(16)), ("adaptive", base.clone())] {
        let (img, seconds) = specular_image(&scene, &settings)?;
        println!(
            "| {name} | 16 | {:.0} | {:.5} | {:.5} |",
            seconds * 1e3,
            rmse(&img, &reference),
            mean(&img)
        );
    }
    Ok(())
}
