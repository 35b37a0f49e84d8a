//! BVH build rate (triangles/s) on a scene of ~246k triangles and on coincident copies of
//! one sphere (1.2M triangles; 164k with `GI_BENCH_QUICK`), and incoherent closest-hit
//! throughput (rays/s). `GI_BENCH_QUICK=1` shortens the measurement for CI-sized runs.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use gi_core::scene::bench::{dense_cornell, incoherent_rays, sphere_copies};
use gi_core::trace::SceneBvh;
use rayon::prelude::*;
use std::hint::black_box;
use std::time::Duration;

fn bvh(c: &mut Criterion) {
    let scene = dense_cornell();
    let quick = std::env::var_os("GI_BENCH_QUICK").is_some();
    let mut g = c.benchmark_group("bvh");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(if quick { 2 } else { 10 }));
    g.throughput(Throughput::Elements(scene.triangles.len() as u64));
    g.bench_function(format!("build {} triangles", scene.triangles.len()), |b| {
        b.iter(|| black_box(SceneBvh::build(&scene)))
    });
    // The degenerate input: copies of one 20k-triangle sphere at one place (quadratic in
    // the copies before coincident triangles were told apart, docs/bench/bvh-build.md).
    let copies = sphere_copies(if quick { 8 } else { 60 }, true);
    g.throughput(Throughput::Elements(copies.triangles.len() as u64));
    g.bench_function(
        format!("build {} coincident triangles", copies.triangles.len()),
        |b| b.iter(|| black_box(SceneBvh::build(&copies))),
    );
    drop(copies);
    let bvh = SceneBvh::build(&scene);
    let rays = incoherent_rays(1 << 18, 1);
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function("closest hit, incoherent, 1 thread", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|(o, d)| bvh.intersect(*o, *d, f32::INFINITY).is_some())
                .count()
        })
    });
    g.bench_function("closest hit, incoherent, all threads", |b| {
        b.iter(|| {
            rays.par_iter()
                .filter(|(o, d)| bvh.intersect(*o, *d, f32::INFINITY).is_some())
                .count()
        })
    });
    g.bench_function("any hit (shadow, t<0.5), incoherent, 1 thread", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|(o, d)| bvh.occluded(*o, *d, 0.5))
                .count()
        })
    });
    g.finish();
}

criterion_group!(benches, bvh);
criterion_main!(benches);
