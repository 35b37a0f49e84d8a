//! How to use the crate, first: render one frame of a built-in scene and look at the image.
//!
//! `cargo run -p gi-core --example render_scene [-- METHOD]` (default `path`, the CPU
//! reference; `ispm`, `direct`, `bidir` need a GPU adapter or Mesa lavapipe).

use gi_core::frame::options::Method;
use gi_core::scene::builtin;
use gi_core::{options, Silent};

fn main() -> gi_core::Result<()> {
    let method = std::env::args().nth(1).unwrap_or_else(|| "path".into());
    // A scene: a built-in one by name (or `Scene::from_json` for a description).
    let scene = builtin::load("cornell")?;
    // Render options: the method and the few settings that differ from the defaults
    // (`options!` panics on an invalid value; `RenderOptions::new` returns the error).
    let options = match method.as_str() {
        "path" => options!(Path, spp: 16, width: 64, height: 48),
        "ispm" => options!(Ispm, photons: 20_000, width: 64, height: 48),
        "direct" => options!(Direct, width: 64, height: 48),
        "bidir" => options!(Bidir, width: 64, height: 48),
        other => {
            let known: Vec<_> = Method::ALL.iter().map(|m| m.name()).collect();
            eprintln!("unknown method `{other}` (try {})", known.join(", "));
            std::process::exit(2);
        }
    };
    // One frame of a new renderer, every image read back; `Silent` reports no progress.
    let out = gi_core::render(&scene, &options, &Silent)?;
    let (w, h) = (out.radiance.width, out.radiance.height);
    println!("{method}: {w}x{h}, mean radiance {:?}", out.radiance.mean());
    for (stage, seconds) in &out.stats.stages {
        println!("  {stage}: {:.1} ms", seconds * 1e3);
    }
    Ok(())
}
