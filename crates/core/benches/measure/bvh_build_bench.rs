//! CPU BVH build settings: build time against trace time, as a markdown table
//! (`docs/bench/bvh-build.md`).
//!
//! `cargo run -p gi-core --profile test --example bvh_build_bench [-- --runs N --rays N
//! --coincident N,N --grid N --settings NAME,NAME]`
//!
//! Scenes: the built-in scenes, `dense-cornell` (~246k triangles), the Cornell box with
//! `--coincident` copies of a 20,480-triangle sphere at one place (default 24,121) and with
//! `--grid` copies on a grid (default 100). Settings: obvhs's PLOC search distance, the depth
//! below which it searches one neighbour, the share of nodes reinserted, and whether
//! coincident boxes are told apart ("sep") first (`BuildSettings`). Build: median of
//! `--runs` (3) builds (one for scenes of over 1M triangles), wall clock and CPU seconds
//! (all threads, from /proc/self/stat: the machine is shared, and the work done is steadier
//! than the wall clock). Trace: `--rays` (2^18) incoherent closest-hit rays (origins uniform
//! in the Cornell box, directions uniform) on one thread, CPU time, median of 3. "build +
//! 10M rays": the build plus the time of 10M such rays (a 640×480 `path` frame at 4 spp,
//! depth 4, traces ~5–10M).
use gi_core::scene::bench::{dense_cornell, incoherent_rays, sphere_copies};
use gi_core::scene::builtin;
use gi_core::trace::bvh::{BuildSettings, PlocSearchDistance};
use gi_core::trace::SceneBvh;
use gi_core::Scene;
use std::time::Instant;

fn arg<T: std::str::FromStr>(name: &str) -> Option<T> {
    let a: Vec<String> = std::env::args().collect();
    a.iter()
        .position(|x| x == name)
        .and_then(|i| a.get(i + 1))
        .and_then(|v| v.parse().ok())
}

fn list(name: &str, default: &str) -> Vec<String> {
    arg::<String>(name)
        .unwrap_or_else(|| default.to_string())
        .split(',')
        .filter(|s| !s.is_empty())
        .map(str::to_string)
        .collect()
}

fn settings(name: &str) -> BuildSettings {
    let (search, threshold, reinsertion) = match name.trim_end_matches("+sep") {
        "medium" => (PlocSearchDistance::Medium, 3, 0.05),
        "medium-noreins" => (PlocSearchDistance::Medium, 3, 0.0),
        "fast" => (PlocSearchDistance::Low, 2, 0.02),
        "fastest" => (PlocSearchDistance::Minimum, 0, 0.01),
        "fastest-noreins" => (PlocSearchDistance::Minimum, 0, 0.0),
        "high" => (PlocSearchDistance::High, 2, 0.2),
        other => panic!("unknown settings `{other}`"),
    };
    BuildSettings {
        search,
        search_depth_threshold: threshold,
        reinsertion,
        separate_coincident: name.ends_with("+sep"),
    }
}

/// CPU seconds of this process (all threads; user + system) from /proc/self/stat: on a
/// shared, loaded machine the work done is steadier than the wall clock.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<f64> = after
        .split_whitespace()
        .map(|x| x.parse().unwrap_or(0.0))
        .collect();
    // Fields 14 and 15 (utime, stime) are 11 and 12 after the command name; 100 ticks/s.
    (f.get(11).unwrap_or(&0.0) + f.get(12).unwrap_or(&0.0)) / 100.0
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let runs: usize = arg("--runs").unwrap_or(3);
    let nrays: usize = arg("--rays").unwrap_or(1 << 18);
    let names = list(
        "--settings",
        "medium,medium+sep,medium-noreins+sep,fast+sep,fastest+sep,fastest-noreins+sep,high+sep",
    );
    let mut scenes: Vec<(String, Box<dyn Fn() -> Scene>)> = Vec::new();
    for name in list("--builtin", "cornell,cornell-glass,ring-room") {
        let n = name.clone();
        scenes.push((name, Box::new(move || builtin::load(&n).expect("built-in"))));
    }
    scenes.push(("dense-cornell".into(), Box::new(dense_cornell)));
    for c in list("--grid", "100") {
        let n: usize = c.parse().expect("--grid N");
        scenes.push((
            format!("grid ×{n}"),
            Box::new(move || sphere_copies(n, false)),
        ));
    }
    for c in list("--coincident", "24,121") {
        let n: usize = c.parse().expect("--coincident N");
        scenes.push((
            format!("coincident ×{n}"),
            Box::new(move || sphere_copies(n, true)),
        ));
    }
    let rays = incoherent_rays(nrays, 1);
    println!(
        "| scene | triangles | settings | build wall (s) | build CPU (s) | Mtri per CPU s \
         | trace (Mrays per CPU s) | build + 10M rays (CPU s) |"
    );
    println!("|---|---:|---|---:|---:|---:|---:|---:|");
    for (scene_name, make) in &scenes {
        let scene = make();
        let n = scene.triangle_count();
        for name in &names {
            let s = settings(name);
            let big = n > 1_000_000;
            let (mut times, mut cpu) = (Vec::new(), Vec::new());
            let mut bvh = None;
            for _ in 0..if big { 1 } else { runs } {
                drop(bvh.take());
                let (t, c) = (Instant::now(), cpu_seconds());
                bvh = Some(SceneBvh::build_with(&scene, &s));
                times.push(t.elapsed().as_secs_f64());
                cpu.push(cpu_seconds() - c);
            }
            let (build, build_cpu) = (median(times), median(cpu));
            let bvh = bvh.expect("built");
            let trace = median(
                (0..3)
                    .map(|_| {
                        let t = cpu_seconds();
                        let hits = rays
                            .iter()
                            .filter(|(o, d)| bvh.intersect(*o, *d, f32::INFINITY).is_some())
                            .count();
                        std::hint::black_box(hits);
                        cpu_seconds() - t
                    })
                    .collect(),
            );
            let rate = nrays as f64 / trace;
            println!(
                "| {scene_name} | {n} | {name} | {build:.3} | {build_cpu:.2} | {:.2} | {:.2} | {:.2} |",
                n as f64 / build_cpu / 1e6,
                rate / 1e6,
                build_cpu + 1e7 / rate
            );
        }
    }
}
