//! `path` on the Cornell box with a point light of `docs/scenes/cornell-point/` (the scene of
//! `docs/bench/path-vs-mitsuba.md`), 64×64, `max_depth` 7: the best of 5 render times at
//! `SPP` samples per pixel (default 256), for before/after comparisons of the path tracer's
//! speed (`docs/bench/instancing.md`, section 6). Run from the repository root:
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
    let mut best = f64::MAX;
    for _ in 0..5 {
        let t = std::time::Instant::now();
        let out = render(&scene, &o, &gi_core::Silent)?;
        best = best.min(t.elapsed().as_secs_f64());
        std::hint::black_box(out);
    }
    println!("path, cornell-point 64x64, {spp} spp: best of 5 {best:.3} s");
    Ok(())
}
