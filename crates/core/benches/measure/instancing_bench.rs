//! The instancing table (`docs/bench/instancing.md`): the 400-sphere grid
//! (`scene::bench::sphere_copies`) rendered with `path` at 64×64, 4 spp, load included,
//! against one sphere; the BVH update after moving one of 1000 instances; and the resident
//! memory of a loaded scene with its BVH, instanced or flattened.
//!
//! `cargo run --release -p gi-core --example instancing_bench -- time [copies...]`
//! `cargo run --release -p gi-core --example instancing_bench -- update 1000`
//! `cargo run --release -p gi-core --example instancing_bench -- memory 400 instanced|flattened`
//! (one process per memory row: peak resident set, VmHWM).
//! `cargo run --release -p gi-core --example instancing_bench -- trace`: closest-hit and
//! any-hit rays per second, two-level BVH against one flat BVH over the world-space
//! triangles, on the built-in scenes (one thread, 2^18 incoherent rays, best of 3).

use gi_core::scene::bench::sphere_copies;
use gi_core::scene::SceneUpdate;
use gi_core::trace::SceneBvh;
use gi_core::{render, Method, RenderOptions, Silent};
use std::time::Instant;

fn status_kib(key: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mode = args.first().map(String::as_str).unwrap_or("time");
    let options = RenderOptions::defaults(Method::Path)
        .with("width", 64)
        .with("height", 64)
        .with("spp", 4);
    match mode {
        "time" => {
            let counts: Vec<usize> = if args.len() > 1 {
                args[1..].iter().filter_map(|a| a.parse().ok()).collect()
            } else {
                vec![1, 400]
            };
            println!("| spheres | triangles | unique triangles | load s | render s | total s (median of 3) |");
            println!("|---:|---:|---:|---:|---:|---:|");
            for n in counts {
                let mut rows = Vec::new();
                let mut tris = (0, 0);
                for _ in 0..3 {
                    let t = Instant::now();
                    let scene = sphere_copies(n, false);
                    let load = t.elapsed().as_secs_f64();
                    let out = render(&scene, &options, &Silent).expect("render");
                    let total = t.elapsed().as_secs_f64();
                    assert!(out.radiance.pixels.iter().all(|p| p.is_finite()));
                    tris = (scene.triangle_count(), scene.unique_triangle_count());
                    rows.push((total, load));
                }
                rows.sort_by(|a, b| a.0.total_cmp(&b.0));
                let (total, load) = rows[1];
                println!(
                    "| {n} | {} | {} | {load:.3} | {:.3} | {total:.3} |",
                    tris.0,
                    tris.1,
                    total - load
                );
            }
        }
        "update" => {
            let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(1000);
            let mut scene = sphere_copies(n, false);
            let object = scene.objects.len() - 1;
            let start = scene.objects[object].transform;
            let mut bvh = SceneBvh::build(&scene);
            let (mut update, mut apply) = (Vec::new(), Vec::new());
            for i in 0..200 {
                let transform = glam::Mat4::from_translation(glam::Vec3::new(
                    0.001 * (i % 50) as f32,
                    0.0,
                    0.0,
                )) * start;
                let t = Instant::now();
                scene
                    .apply(&SceneUpdate::Transform { object, transform })
                    .expect("move");
                apply.push(t.elapsed().as_secs_f64());
                let t = Instant::now();
                bvh.update_instances(&scene);
                update.push(t.elapsed().as_secs_f64());
            }
            println!(
                "{} objects ({} instances of the sphere): BVH update median {:.3} ms, scene update {:.3} ms",
                scene.objects.len(),
                n,
                1e3 * median(update),
                1e3 * median(apply)
            );
        }
        "memory" => {
            let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(400);
            let flattened = args.get(2).map(String::as_str) == Some("flattened");
            let before = status_kib("VmRSS:");
            let scene = sphere_copies(n, false);
            let scene = if flattened { scene.flattened() } else { scene };
            let bvh = SceneBvh::build(&scene);
            let after = status_kib("VmRSS:");
            let (meshes, instances) = bvh.counts();
            println!(
                "{n} spheres {}: {} meshes, {} instances, {} unique triangles; resident {:.1} MiB after load + BVH (+{:.1} MiB), peak {:.1} MiB",
                if flattened { "flattened" } else { "instanced" },
                meshes,
                instances,
                scene.unique_triangle_count(),
                after as f64 / 1024.0,
                (after - before) as f64 / 1024.0,
                status_kib("VmHWM:") as f64 / 1024.0
            );
        }
        "trace" => trace_table(),
        "refit" => {
            // The frame benchmark's BVH table (docs/bench/frame.md): a full build against
            // the update after the last object moved (now the top level only).
            println!("| scene | triangles | objects | rebuild (ms) | update after a move (ms) |");
            println!("|---|---:|---:|---:|---:|");
            let mut scenes: Vec<(String, gi_core::Scene)> = ["cornell", "cornell-glass"]
                .iter()
                .map(|n| {
                    (
                        n.to_string(),
                        gi_core::scene::builtin::load(n).expect("built-in"),
                    )
                })
                .collect();
            scenes.push((
                "dense-cornell".into(),
                gi_core::scene::bench::dense_cornell(),
            ));
            for (name, scene) in scenes {
                let (rebuild, refit) = gi_core::trace::bvh::rebuild_vs_refit(&scene, 5);
                println!(
                    "| {name} | {} | {} | {:.2} | {:.3} |",
                    scene.triangle_count(),
                    scene.objects.len(),
                    1e3 * rebuild,
                    1e3 * refit
                );
            }
        }
        _ => eprintln!(
            "modes: time [copies...] | update N | memory N instanced|flattened | trace | refit"
        ),
    }
}

/// Rays per second (closest hit, any hit within 0.5 m), best of 3 runs.
fn rays_per_second(
    rays: &[(glam::Vec3, glam::Vec3)],
    f: &dyn Fn(glam::Vec3, glam::Vec3) -> bool,
) -> (f64, usize) {
    let mut best = f64::INFINITY;
    let mut hits = 0;
    for _ in 0..3 {
        let t = Instant::now();
        hits = rays.iter().filter(|(o, d)| f(*o, *d)).count();
        best = best.min(t.elapsed().as_secs_f64());
    }
    (rays.len() as f64 / best, hits)
}

fn trace_table() {
    use gi_core::scene::bench::{dense_cornell, incoherent_rays};
    use gi_core::trace::bvh::{flat_triangles, MeshBvh};
    let mut scenes: Vec<(String, gi_core::Scene)> = gi_core::scene::builtin::BUILTINS
        .iter()
        .map(|(n, _, _)| {
            (
                n.to_string(),
                gi_core::scene::builtin::load(n).expect("built-in"),
            )
        })
        .collect();
    scenes.push(("dense-cornell".into(), dense_cornell()));
    scenes.push(("sphere grid 100".into(), sphere_copies(100, false)));
    let rays = incoherent_rays(1 << 18, 1);
    println!("| scene | objects | unique meshes | triangles | closest Mrays/s flat | two-level | ratio | any-hit Mrays/s flat | two-level | ratio |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (name, scene) in scenes {
        let two = SceneBvh::build(&scene);
        let flat = MeshBvh::from_triangles(&flat_triangles(&scene));
        let (c_flat, h_flat) =
            rays_per_second(&rays, &|o, d| flat.intersect(o, d, f32::INFINITY).is_some());
        let (c_two, h_two) =
            rays_per_second(&rays, &|o, d| two.intersect(o, d, f32::INFINITY).is_some());
        // Rays meet instances in their mesh frames: a ray grazing an edge may round apart.
        assert!(
            h_flat.abs_diff(h_two) * 10_000 <= rays.len(),
            "{name}: the two BVHs hit {h_flat} and {h_two} rays"
        );
        let (a_flat, _) = rays_per_second(&rays, &|o, d| flat.occluded(o, d, 0.5));
        let (a_two, _) = rays_per_second(&rays, &|o, d| two.occluded(o, d, 0.5));
        println!(
            "| {name} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
            scene.objects.len(),
            scene.meshes.len(),
            scene.triangle_count(),
            c_flat / 1e6,
            c_two / 1e6,
            c_two / c_flat,
            a_flat / 1e6,
            a_two / 1e6,
            a_two / a_flat
        );
    }
}
