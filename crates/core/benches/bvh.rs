//! BVH build rate (triangles/s) on a scene of ~246k triangles and on coincident copies of
//! one sphere (1.2M triangles; 164k with `GI_BENCH_QUICK`), and incoherent closest-hit
//! throughput (rays/s). `GI_BENCH_QUICK=1` shortens the measurement for CI-sized runs.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use gi_core::scene::bench::{dense_cornell, incoherent_rays, sphere_copies};
use gi_core::scene::SceneUpdate;
use gi_core::trace::bvh::{flat_triangles, MeshBvh};
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
    g.throughput(Throughput::Elements(scene.triangle_count() as u64));
    g.bench_function(format!("build {} triangles", scene.triangle_count()), |b| {
        b.iter(|| black_box(SceneBvh::build(&scene)))
    });
    // The degenerate input: copies of one 20k-triangle sphere at one place, flattened into
    // one mesh (quadratic in the copies before coincident triangles were told apart,
    // docs/bench/bvh-build.md). As instances they share one mesh's BVH.
    let copies = flat_triangles(&sphere_copies(if quick { 8 } else { 60 }, true));
    g.throughput(Throughput::Elements(copies.len() as u64));
    g.bench_function(
        format!("build {} coincident triangles", copies.len()),
        |b| b.iter(|| black_box(MeshBvh::from_triangles(&copies))),
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

/// Moving one object among 1000 instances of one sphere (the grid of
/// `scene::bench::sphere_copies`): the two-level BVH's update (its top level over the
/// instances; the sphere's BVH is kept), and the scene update that places the object's
/// flat copy. `GI_BENCH_QUICK=1`: 100 instances and a shorter measurement.
fn instances(c: &mut Criterion) {
    let quick = std::env::var_os("GI_BENCH_QUICK").is_some();
    let n = if quick { 100 } else { 1000 };
    let mut scene = sphere_copies(n, false);
    let object = scene.objects.len() - 1;
    let start = scene.objects[object].transform;
    let mut g = c.benchmark_group("instances");
    g.sample_size(20)
        .measurement_time(Duration::from_secs(if quick { 2 } else { 5 }));
    g.throughput(Throughput::Elements(scene.objects.len() as u64));
    let mut step = 0u32;
    let mut moved = |scene: &mut gi_core::Scene| {
        step = (step + 1) % 16;
        let transform =
            glam::Mat4::from_translation(glam::Vec3::new(0.01 * step as f32, 0.0, 0.0)) * start;
        scene
            .apply(&SceneUpdate::Transform { object, transform })
            .expect("a valid move");
    };
    moved(&mut scene);
    let mut bvh = SceneBvh::build(&scene);
    moved(&mut scene);
    g.bench_function(
        format!("move 1 of {} instances: BVH update", scene.objects.len()),
        |b| b.iter(|| bvh.update_instances(&scene)),
    );
    g.bench_function(
        format!("move 1 of {} instances: scene update", scene.objects.len()),
        |b| b.iter(|| moved(&mut scene)),
    );
    g.finish();
}

criterion_group!(benches, bvh, instances);
criterion_main!(benches);
