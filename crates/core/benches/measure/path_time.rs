//! `path` on the Cornell box with a point light of `docs/scenes/cornell-point/` (the scene of
//! `docs/bench/path-vs-mitsuba.md`), 64×64, `max_depth` 7: the best of 5 render times at
//! `SPP` samples per pixel (default 256), for before/after comparisons of the path tracer's
//! speed (`docs/bench/instancing.md`, section 6), and the best of 5 process CPU times (user +
//! system, all threads; from `/proc/self/stat`, 10 ms ticks), which other work on a shared
//! machine disturbs less than the wall clock. Run from the repository root:
//!
//! `cargo run --release -p gi-core --example path_time -- [SPP] [--error] [--scene NAME]
//! [--no-light-vertices]`
//!
//! With `--error` it also prints the five renders' mean relMSE (the measure of
//! `docs/bench/path-vs-mitsuba.md`: (x − ref)² / (ref² + 0.01) over pixels and channels)
//! against a reference of 8192 spp (rendered once and kept in
//! `target/path_time_reference.bin`) and the efficiency 1 / (CPU seconds × relMSE), for
//! before/after comparisons of changes that alter the noise (the sampler, Russian roulette).
//! On a machine shared with other work, `chrt -f 50` in front of the command gives it the
//! cores (as if idle) for the few seconds it runs.

use gi_core::{render, Method, RenderOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let builtin = args
        .iter()
        .position(|a| a == "--scene")
        .and_then(|i| args.get(i + 1))
        .cloned();
    let name = builtin.clone().unwrap_or_else(|| "cornell-point".into());
    let scene = match &builtin {
        Some(name) => gi_core::scene::builtin::load(name)?,
        None => {
            let json = std::fs::read_to_string("docs/scenes/cornell-point/cornell-point.json")?;
            gi_core::Scene::from_json(&json, "cornell-point", &Default::default())?
        }
    };
    let error = args.iter().any(|a| a == "--error");
    let light_vertices = !args.iter().any(|a| a == "--no-light-vertices");
    let spp: u32 = args
        .iter()
        .enumerate()
        .find(|(i, a)| !a.starts_with("--") && (*i == 0 || args[i - 1] != "--scene"))
        .map(|(_, a)| a)
        .map_or(Ok(256), |s| s.parse())?;
    let options = |spp: u32, seed: u64| {
        RenderOptions::defaults(Method::Path)
            .with("width", 64)
            .with("height", 64)
            .with("spp", spp)
            .with("max_depth", 7)
            .with("seed", seed)
            .with("light_vertices", light_vertices)
    };
    let reference = if error {
        let file = format!("target/path_time_reference-{name}.bin");
        Some(reference(&scene, &options(8192, 1 << 20), &file)?)
    } else {
        None
    };
    let (mut best, mut best_cpu, mut rel_mse) = (f64::MAX, f64::MAX, 0.0);
    for seed in 0..5 {
        let (t, c) = (std::time::Instant::now(), cpu_seconds());
        let out = render(&scene, &options(spp, seed), &gi_core::Silent)?;
        best = best.min(t.elapsed().as_secs_f64());
        best_cpu = best_cpu.min(cpu_seconds() - c);
        if let Some(r) = &reference {
            rel_mse += relative_mse(&out.radiance.pixels, r) / 5.0;
        }
        std::hint::black_box(out);
    }
    print!("path, {name} 64x64, {spp} spp: best of 5 {best:.3} s, CPU {best_cpu:.2} s");
    if error {
        let efficiency = 1.0 / (best_cpu * rel_mse);
        print!(", relMSE {rel_mse:.5}, efficiency (CPU) {efficiency:.1}");
    }
    println!();
    Ok(())
}

/// The reference image (RGB triples), rendered once and read back from `file`.
fn reference(
    scene: &gi_core::Scene,
    options: &RenderOptions,
    file: &str,
) -> Result<Vec<f32>, Box<dyn std::error::Error>> {
    if let Ok(bytes) = std::fs::read(file) {
        return Ok(bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect());
    }
    eprintln!("rendering the reference ({file}) once");
    let out = render(scene, options, &gi_core::Silent)?;
    let values: Vec<f32> = out
        .radiance
        .pixels
        .iter()
        .flat_map(|p| p.to_array())
        .collect();
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(file, bytes)?;
    Ok(values)
}

/// Mean of (x − ref)² / (ref² + 0.01) over pixels and channels.
fn relative_mse(pixels: &[glam::Vec3], reference: &[f32]) -> f64 {
    let values = pixels.iter().flat_map(|p| p.to_array());
    let sum: f64 = values
        .zip(reference)
        .map(|(x, &r)| {
            let (x, r) = (x as f64, r as f64);
            (x - r).powi(2) / (r * r + 0.01)
        })
        .sum();
    sum / reference.len() as f64
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
