//! The GPU instancing table of `frame_bench --instancing` (`docs/bench/instancing.md`, section 7): method `ispm` on the
//! large scenes, each instanced (the unique meshes uploaded once, one record per object)
//! and flattened (`Scene::flattened()`: every object's world-space triangles as a mesh of
//! its own, which is what main uploaded and drew), in the same run:
//! - the GPU geometry's bytes (vertex + instance buffers; main's flat vertex list was
//!   3 × 64 bytes per placed triangle, equal to the flattened scene's vertex buffer);
//! - triangles per pass before culling (every placed triangle into every view) and after
//!   (what the culled draws rasterize): the G-buffer (the eye view), the shadow maps (six
//!   cube faces of the point light) and the bounce maps (the light's views for `photons`;
//!   these scenes have one point light, which takes all of them);
//! - the engine frame (the light moving a little every frame, median of `runs`) and its
//!   stages in serial frames (a second renderer waits after each stage: wall-clock split).
//!
//! `cargo run -p gi-core --profile test --example frame_bench -- --instancing [--size WxH]
//! [--runs N] [--photons N] [--scenes grid100,grid400,dense] [--no-flattened NAME,...]`
//! (default: 640x480, 3 runs, 50k photons, all three scenes, the flattened 400-sphere grid
//! not rendered: ~1.6 GB of vertices, minutes a frame on lavapipe)

use super::{median, nudge};
use gi_core::frame::{FrameDesc, Renderer};
use gi_core::raster::instances::{buffer_bytes, triangles_drawn};
use gi_core::raster::{eye_cull_view, shadow::ShadowViews, CullUnits};
use gi_core::scene::bench::{dense_cornell, sphere_copies};
use gi_core::scene::light_views::light_views;
use gi_core::{RenderOutput, Scene, Silent};
use glam::Mat4;
use std::time::Instant;

/// "drawn / unculled" triangles of `views` (millions).
fn pass_triangles(cull: &CullUnits, views: &[Mat4]) -> String {
    let all = triangles_drawn(&cull.all()) as f64 * views.len() as f64;
    let drawn: u64 = cull.draws(views).iter().map(|d| triangles_drawn(d)).sum();
    format!("{:.2} / {:.2}", drawn as f64 / 1e6, all / 1e6)
}

/// Median engine frame (ms) and the serial frames' stages (ms, median per stage).
fn frames(
    scene: &Scene,
    options: &gi_core::RenderOptions,
    runs: usize,
) -> Result<(f64, String), Box<dyn std::error::Error>> {
    let serial = FrameDesc {
        serial: true,
        ..Default::default()
    };
    let mut r = Renderer::new(scene, options)?;
    let mut o = Renderer::new(scene, options)?;
    r.render(&FrameDesc::default(), &Silent)?;
    o.render(&serial, &Silent)?;
    let mut wall = Vec::new();
    let mut outs: Vec<RenderOutput> = Vec::new();
    for i in 0..runs {
        let u = nudge(scene, 0.01 * (i + 1) as f32);
        r.update(&u)?;
        o.update(&u)?;
        let t = Instant::now();
        r.render(&FrameDesc::default(), &Silent)?;
        wall.push(t.elapsed().as_secs_f64() * 1e3);
        outs.push(o.render(&serial, &Silent)?);
    }
    let mut names: Vec<String> = Vec::new();
    for (n, _) in outs.iter().flat_map(|o| &o.stats.stages) {
        if !names.contains(n) {
            names.push(n.clone());
        }
    }
    let stages = names
        .iter()
        .map(|n| {
            let ms = median(
                outs.iter()
                    .map(|o| {
                        let s = o.stats.stages.iter().filter(|(m, _)| m == n);
                        s.map(|(_, s)| s).sum::<f64>()
                    })
                    .collect(),
            );
            format!("{n} {:.0}", ms * 1e3)
        })
        .collect::<Vec<_>>()
        .join(", ");
    Ok((median(wall), stages))
}

/// Prints the table for the command line's `--size`, `--photons`, `--scenes`,
/// `--no-flattened`.
pub fn table(args: &super::Args, runs: usize) -> Result<(), Box<dyn std::error::Error>> {
    let arg = |name: &str| args.value(name);
    let (w, h) = arg("--size")
        .and_then(|s| s.split_once('x'))
        .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
        .unwrap_or((640u32, 480u32));
    let photons: u64 = arg("--photons")
        .and_then(|s| s.parse().ok())
        .unwrap_or(50_000);
    let names = arg("--scenes").unwrap_or("grid100,grid400,dense");
    let no_flat = arg("--no-flattened").unwrap_or("grid400");
    let options = gi_core::options!(Ispm, width: w, height: h, photons: photons);
    let shadow_size = match options.get("shadow_map_size") {
        Some(gi_core::frame::options::Value::Int(n)) => n as u32,
        _ => 1024,
    };
    println!("ispm {w}x{h}, {photons} photons, median of {runs} frames (the light moving)\n");
    println!("| scene | geometry | placed triangles | GPU geometry MiB | G-buffer Mtri drawn / unculled | shadow maps | bounce maps | engine frame ms | serial stages ms |");
    println!("|---|---|---:|---:|---|---|---|---:|---|");
    for name in names.split(',') {
        let base = match name {
            "grid100" => sphere_copies(100, false),
            "grid400" => sphere_copies(400, false),
            "dense" => dense_cornell(),
            other => gi_core::scene::builtin::load(other)?,
        };
        let mut base = base;
        base.camera = base.camera.with_size(w, h);
        for flattened in [false, true] {
            let scene = if flattened {
                base.flattened()
            } else {
                base.clone()
            };
            let cull = CullUnits::of(&scene);
            let (v, i) = buffer_bytes(&cull);
            let eye = pass_triangles(&cull, &[eye_cull_view(&scene)]);
            let shadow =
                pass_triangles(&cull, &ShadowViews::new(&scene, shadow_size, None).matrices);
            let bounce: Vec<Mat4> = light_views(&scene, photons)
                .iter()
                .map(|l| l.view_proj)
                .collect();
            let bounce = pass_triangles(&cull, &bounce);
            let (frame, stages) = if flattened && no_flat.split(',').any(|n| n == name) {
                (f64::NAN, "not rendered".to_string())
            } else {
                frames(&scene, &options, runs)?
            };
            println!(
                "| {name} | {} | {} | {:.1} | {eye} | {shadow} | {bounce} | {frame:.0} | {stages} |",
                if flattened { "flattened" } else { "instanced" },
                scene.triangle_count(),
                (v + i) as f64 / (1u64 << 20) as f64,
            );
        }
    }
    Ok(())
}
