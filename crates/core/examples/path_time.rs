//! `path` on the Cornell box with a point light of `docs/scenes/cornell-point/` (the scene of
//! `docs/bench/path-vs-mitsuba.md`), 64×64, `max_depth` 7: the best of 5 render times at
//! `SPP` samples per pixel (default 256), for before/after comparisons of the path tracer's
//! speed (`docs/bench/instancing.md`, section 6), and the best of 5 process CPU times (user +
//! system, all threads; from `/proc/self/stat`, 10 ms ticks), which other work on a shared
//! machine disturbs less than the wall clock. Run from the repository root:
//!
//! `cargo run --release -p gi-core --example path_time -- [SPP]`

use gi_core::{render, Method, RenderOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let json = std::fs::read_to_string("docs/scenes/cornell-point/cornell-point.json")?;
    let scene = gi_core::Scene::from_json(&json, "cornell-point", &Default::default())?;
    let spp: u32 = std::env::args().nth(1).map_or(Ok(256), |s| s.parse())?;
    let o = RenderOptions::defaults(Method::Path)
        .with("width", 64)
        .with("height", 64)
        .with("spp", spp)
        .with("max_depth", 7);
    let (mut best, mut best_cpu) = (f64::MAX, f64::MAX);
    for _ in 0..5 {
        let (t, c) = (std::time::Instant::now(), cpu_seconds());
        let out = render(&scene, &o, &gi_core::Silent)?;
        best = best.min(t.elapsed().as_secs_f64());
        best_cpu = best_cpu.min(cpu_seconds() - c);
        std::hint::black_box(out);
    }
    println!("path, cornell-point 64x64, {spp} spp: best of 5 {best:.3} s, CPU {best_cpu:.2} s");
    Ok(())
}

/// The process's user + system time (`/proc/self/stat` fields 14 and 15, at the usual 100
/// ticks a second); NaN where it cannot be read.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the command name (which is in parentheses and may hold spaces).
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<f64> = rest
        .split_whitespace()
        .skip(11)
        .take(2)
        .filter_map(|x| x.parse().ok())
        .collect();
    if f.len() == 2 {
        (f[0] + f[1]) / 100.0
    } else {
        f64::NAN
    }
}
