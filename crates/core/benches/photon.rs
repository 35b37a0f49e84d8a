//! The photon pipeline of `gather`/`ispm` on `cornell-glass`, with throughput: the CPU photon
//! trace (photons emitted per second), the linear-BVH footprint map's build (photons per
//! second) and its gather (radiance queries per second at one camera hit per pixel), and a
//! small `ispm` frame on the default adapter, a new seed each (pixels per second; skipped
//! without an adapter).
//! `GI_BENCH_QUICK=1` (CI) runs 20k photons, a 32×32 frame and short measurements.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use gi_core::frame::gather::gather_trace_settings;
use gi_core::frame::{FrameDesc, Renderer};
use gi_core::photon::footprint_map::{FootprintMap, LeafSize};
use gi_core::photon::{emit_and_trace, Kernel};
use gi_core::scene::builtin;
use gi_core::trace::{Interaction, SceneBvh};
use gi_core::{Method, Silent};
use std::hint::black_box;
use std::time::Duration;

fn quick() -> bool {
    std::env::var_os("GI_BENCH_QUICK").is_some()
}

fn photons(c: &mut Criterion) {
    let scene = builtin::load("cornell-glass").expect("built-in scene");
    let bvh = SceneBvh::build(&scene);
    let n: u64 = if quick() { 20_000 } else { 400_000 };
    let settings = gather_trace_settings(&scene, &gi_core::options!(Gather, photons: n));
    let mut g = c.benchmark_group("photons");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(if quick() { 2 } else { 10 }));
    g.throughput(Throughput::Elements(n));
    g.bench_function(format!("trace {n} photons, cornell-glass"), |b| {
        b.iter(|| black_box(emit_and_trace(&scene, &bvh, n, &settings, 1)))
    });
    let set = emit_and_trace(&scene, &bvh, n, &settings, 1);
    let area = scene.surface_area();
    g.throughput(Throughput::Elements(set.photons.len() as u64));
    g.bench_function(
        format!("footprint LBVH build, {} photons", set.photons.len()),
        |b| {
            b.iter(|| {
                black_box(FootprintMap::build(
                    &set,
                    1,
                    area,
                    LeafSize::Auto,
                    Kernel::Epanechnikov,
                ))
            })
        },
    );
    let map = FootprintMap::build(&set, 1, area, LeafSize::Auto, Kernel::Epanechnikov);
    let size = if quick() { 32 } else { 128 };
    let cam = scene.camera.with_size(size, size);
    let hits: Vec<(Interaction, glam::Vec3)> = (0..size * size)
        .filter_map(|i| {
            let (x, y) = ((i % size) as f32 + 0.5, (i / size) as f32 + 0.5);
            let d = cam.direction(x, y);
            bvh.intersect(cam.position, d, f32::INFINITY)
                .map(|h| (Interaction::new(&scene, &h, d), -d))
        })
        .collect();
    g.throughput(Throughput::Elements(hits.len() as u64));
    g.bench_function(format!("footprint gather, {} points", hits.len()), |b| {
        b.iter(|| {
            hits.iter()
                .map(|(it, wo)| map.radiance(it, *wo))
                .fold(glam::Vec3::ZERO, |a, r| a + r)
        })
    });
    g.finish();
}

fn ispm_frame(c: &mut Criterion) {
    let scene = builtin::load("cornell").expect("built-in scene");
    let (size, n): (u32, u64) = if quick() {
        (32, 20_000)
    } else {
        (160, 100_000)
    };
    let options = gi_core::RenderOptions::defaults(Method::Ispm)
        .with("width", size)
        .with("height", size)
        .with("photons", n);
    let mut renderer = match Renderer::new(&scene, &options) {
        Ok(r) => r,
        Err(e) => return eprintln!("ispm frame skipped: {e}"),
    };
    if let Err(e) = renderer.render(&FrameDesc::default(), &Silent) {
        return eprintln!("ispm frame skipped (no adapter?): {e}");
    }
    let mut g = c.benchmark_group("ispm");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(if quick() { 3 } else { 15 }));
    g.throughput(Throughput::Elements(u64::from(size * size)));
    g.bench_function(format!("frame {size}×{size}, {n} photons, cornell"), |b| {
        let mut seed = 0;
        b.iter(|| {
            // A new seed per frame: the photons are traced and splatted again.
            seed += 1;
            let desc = FrameDesc {
                seed: Some(seed),
                ..FrameDesc::default()
            };
            black_box(renderer.render(&desc, &Silent).expect("frame"))
        })
    });
    g.finish();
}

criterion_group!(benches, photons, ispm_frame);
criterion_main!(benches);
