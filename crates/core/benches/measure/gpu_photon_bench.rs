//! The photon continuation on the GPU (`gpu::photon::trace`) against the CPU trace
//! (`photon::trace::continue_paths`, rayon's pool) on the same first-scatter rays (the
//! bounce maps traced in the CPU BVH), as a markdown table (`docs/bench/gpu-photon.md`).
//!
//! `cargo run -p gi-core --profile test --example gpu_photon_bench [-- --photons N]`
//!
//! Before the rows: the cold compile of the continuation pass and of the scatter parity
//! query (pipeline creation plus the first small dispatch, where lavapipe compiles; cold
//! without a shader cache: `MESA_SHADER_CACHE_DISABLE=true`). Per scene: rays, photons
//! stored by each, the CPU trace, the GPU trace (rays uploaded, one dispatch, records read
//! back and sorted; median of 3 after a warm-up), the GPU scene's upload and bytes.
//!
//! `--sources [--photons N]`: instead, the photons of area lights, the sun and the sky
//! (`tests/scenes/openings/`: `glass_room.json`'s lamp, `window_room.json`'s sky, and its
//! sky replaced by a low sun through the window), N of each (default 50k), every hit
//! after the first stored as in `ispm`: emitted and traced on the CPU
//! (`emit_and_trace_sources`) against emitted on the CPU and traced on the GPU
//! (`gpu::photon::emitted::trace_sources`), with the emission's own time; median of 3.

use gi_core::gpu::photon::emitted;
use gi_core::gpu::photon::scatter_query::{scatter, ScatterInput};
use gi_core::gpu::photon::scene::GpuPhotonScene;
use gi_core::gpu::photon::trace::{compile, continue_paths as gpu_continue};
use gi_core::photon::bounce::trace_bounce_maps;
use gi_core::photon::focus::Focus;
use gi_core::photon::trace::{emit_and_trace_sources, emitted_rays, Checked};
use gi_core::photon::{continue_paths, PhotonRay, PhotonTraceSettings};
use gi_core::scene::bench::dense_cornell;
use gi_core::scene::builtin;
use gi_core::scene::light_views::light_views;
use gi_core::scene::{Source, Sources};
use gi_core::trace::SceneBvh;
use gi_core::{gpu, Scene, Silent};
use glam::{Vec3, Vec4};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn seconds(f: impl FnOnce()) -> f64 {
    let t = Instant::now();
    f();
    t.elapsed().as_secs_f64()
}

const SETTINGS: PhotonTraceSettings = PhotonTraceSettings {
    max_bounces: 8,
    store_direct: false,
    differentials: None,
};

fn rays_of(scene: &Scene, bvh: &SceneBvh, photons: u64) -> Vec<PhotonRay> {
    let control = Checked::new(&Silent, "bounce maps");
    trace_bounce_maps(scene, bvh, &light_views(scene, photons), 1, &control)
        .expect("bounce maps")
        .rays
}

fn row(ctx: &gpu::GpuContext, name: &str, scene: &Scene, photons: u64) {
    let bvh = SceneBvh::build(scene);
    let rays = rays_of(scene, &bvh, photons);
    let mut gs = None;
    let upload = seconds(|| gs = Some(GpuPhotonScene::upload(ctx, scene, &bvh).expect("upload")));
    let gs = gs.expect("uploaded");
    let (mut n_cpu, mut n_gpu) = (0, 0);
    let cpu = median(
        (0..3)
            .map(|_| {
                seconds(|| {
                    n_cpu = continue_paths(scene, &bvh, &rays, &SETTINGS, 1)
                        .photons
                        .len()
                })
            })
            .collect(),
    );
    let trace = || gpu_continue(ctx, &gs, &rays, &SETTINGS, 1).expect("GPU trace");
    trace();
    let gpu_s = median(
        (0..3)
            .map(|_| seconds(|| n_gpu = trace().photons.len()))
            .collect(),
    );
    println!(
        "| {name} | {} | {} | {n_cpu} | {n_gpu} | {:.1} | {:.1} | {:.2}× | {:.0} | {:.2} |",
        scene.triangle_count(),
        rays.len(),
        cpu * 1e3,
        gpu_s * 1e3,
        cpu / gpu_s,
        upload * 1e3,
        gs.bytes as f64 / 1e6,
    );
}

/// A scene of the repository's `tests/scenes/openings/`, its environment replaced by
/// `sun` (a light's JSON) where given.
fn openings(file: &str, sun: Option<&str>) -> Scene {
    let path = format!(
        "{}/../../tests/scenes/openings/{file}",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(path).expect("scene file");
    let mut desc: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    if let Some(sun) = sun {
        let o = desc.as_object_mut().expect("a scene object");
        o.remove("environment");
        o.insert("lights".into(), serde_json::from_str(sun).expect("JSON"));
    }
    Scene::from_json(&desc.to_string(), file, &Default::default()).expect("scene")
}

fn source_row(ctx: &gpu::GpuContext, name: &str, scene: &Scene, source: Source, n: u64) {
    let s = PhotonTraceSettings {
        store_direct: false,
        ..SETTINGS
    };
    let bvh = SceneBvh::build(scene);
    let gs = GpuPhotonScene::upload(ctx, scene, &bvh).expect("upload");
    let only = Sources::filtered(scene, |x| x == source);
    let (focus, control) = (Focus::default(), Checked::new(&Silent, "cpu trace"));
    let (mut n_cpu, mut n_gpu) = (0, 0);
    let cpu = median(
        (0..3)
            .map(|_| {
                seconds(|| {
                    let set =
                        emit_and_trace_sources(scene, &bvh, &only, n, &s, 1, &control, &focus);
                    n_cpu = set.expect("CPU trace").photons.len();
                })
            })
            .collect(),
    );
    let emit = median(
        (0..3)
            .map(|_| seconds(|| drop(emitted_rays(scene, &only, n, 1, &focus))))
            .collect(),
    );
    let trace = || emitted::trace_sources(ctx, &gs, scene, &only, n, &s, 1, &focus);
    trace().expect("GPU trace");
    let gpu_s = median(
        (0..3)
            .map(|_| seconds(|| n_gpu = trace().expect("GPU trace").photons.len()))
            .collect(),
    );
    println!(
        "| {name} | {} | {n} | {n_cpu} | {n_gpu} | {:.1} | {:.1} | {:.1} | {:.2}× |",
        scene.triangle_count(),
        cpu * 1e3,
        emit * 1e3,
        gpu_s * 1e3,
        cpu / gpu_s,
    );
}

fn sources_table(ctx: &gpu::GpuContext, n: u64) {
    println!(
        "CPU threads: {}, photons per source: {n}, max 8 bounces, stored from bounce 1, \
         median of 3\n",
        rayon::current_num_threads()
    );
    println!(
        "| scene, source | triangles | photons | CPU photons | GPU photons | CPU emit + trace ms | \
         emission alone ms | GPU trace ms (emission included) | GPU speed-up |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let sun =
        r#"[{"type": "directional", "direction": [-1.0, -0.8, 0.3], "irradiance": [6, 6, 6]}]"#;
    let rows = [
        (
            "glass room, area lamp",
            openings("glass_room.json", None),
            Source::Emitters,
        ),
        (
            "window room, sky",
            openings("window_room.json", None),
            Source::Environment,
        ),
        (
            "window room, sun",
            openings("window_room.json", Some(sun)),
            Source::Light(0),
        ),
    ];
    for (name, scene, source) in rows {
        source_row(ctx, name, &scene, source, n);
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let photons = match args.iter().position(|a| a == "--photons") {
        Some(i) => args[i + 1].parse().expect("--photons N"),
        None => 50_000,
    };
    let ctx = gpu::context(None).expect("a GPU adapter");
    println!("adapter: {} ({:?})", ctx.info.name, ctx.info.device_type);
    if args.iter().any(|a| a == "--sources") {
        return sources_table(&ctx, photons);
    }
    let cornell = builtin::load("cornell").expect("built-in");
    let bvh = SceneBvh::build(&cornell);
    let gs = GpuPhotonScene::upload(&ctx, &cornell, &bvh).expect("upload");
    let few = &rays_of(&cornell, &bvh, 2_000)[..64];
    let cont = seconds(|| {
        compile(&ctx);
        gpu_continue(&ctx, &gs, few, &SETTINGS, 1).expect("first trace");
    });
    let m = gi_core::bsdf::Material::default();
    let one = [ScatterInput::new(
        &m,
        Vec3::Z,
        Vec3::Z,
        Vec3::ONE,
        Vec4::splat(0.5),
    )];
    let query = seconds(|| drop(scatter(&ctx, &one).expect("scatter query")));
    println!(
        "cold compile (pipeline + first 64-path dispatch): continuation pass {:.0} ms, \
         scatter parity query {:.0} ms",
        cont * 1e3,
        query * 1e3
    );
    println!(
        "CPU threads: {}, bounce-map photons: {photons}, max 8 bounces, median of 3\n",
        rayon::current_num_threads()
    );
    println!(
        "| scene | triangles | rays | CPU photons | GPU photons | CPU trace ms | GPU trace ms | \
         GPU speed-up | GPU scene upload ms | GPU scene MB |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for name in ["cornell", "cornell-glass", "ring-room"] {
        row(&ctx, name, &builtin::load(name).expect("built-in"), photons);
    }
    row(&ctx, "dense-cornell", &dense_cornell(), photons);
}
