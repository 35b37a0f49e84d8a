//! Ray queries on the GPU's BVH (`gpu::bvh`) against the CPU's (`SceneBvh`), as a markdown
//! table (`docs/bench/gpu-bvh.md`).
//!
//! `cargo run -p gi-core --profile test --example gpu_bvh_bench [-- --rays N]`
//!
//! Rays: `--rays` (2^18) of `gpu::bvh::query::random_rays` (incoherent: origins in the
//! scene's box, uniform directions; a third occlusion queries). CPU: the same queries with
//! `SceneBvh::intersect`/`occluded`, on one thread and on rayon's pool. GPU: one
//! `gpu::bvh::query` call (rays uploaded, one dispatch, hits read back), median of
//! 3 after one warm-up ("first query"). The query pipeline's creation and its
//! first 64-ray query (when lavapipe compiles it) are timed once before the rows (cold without a shader cache: set `MESA_SHADER_CACHE_DISABLE=true`).
//! Upload: the flattening and the upload of the BVH.
use gi_core::gpu::bvh::query::{query, random_rays, QueryPipeline, QueryRay};
use gi_core::gpu::bvh::GpuBvh;
use gi_core::gpu::Pipelines;
use gi_core::scene::bench::dense_cornell;
use gi_core::scene::builtin;
use gi_core::trace::SceneBvh;
use gi_core::{gpu, Scene};
use rayon::prelude::*;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// One CPU query (closest hit or occlusion); true when it hit.
fn cpu_query(bvh: &SceneBvh, r: &QueryRay) -> bool {
    let (o, d) = (r.origin(), r.dir());
    if r.any() {
        bvh.occluded(o, d, r.tmax())
    } else {
        bvh.intersect(o, d, r.tmax()).is_some()
    }
}

fn seconds(f: impl FnOnce()) -> f64 {
    let t = Instant::now();
    f();
    t.elapsed().as_secs_f64()
}

fn row(name: &str, scene: &Scene, nrays: usize, runs: usize) {
    let ctx = gpu::context(None).expect("a GPU adapter");
    let bvh = SceneBvh::build(scene);
    let rays = random_rays(scene, nrays, 3);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let cpu1 = median(
        (0..runs)
            .map(|_| {
                seconds(|| {
                    one.install(|| {
                        rays.iter().for_each(|r| {
                            std::hint::black_box(cpu_query(&bvh, r));
                        })
                    })
                })
            })
            .collect(),
    );
    let cpu_all = median(
        (0..runs)
            .map(|_| {
                seconds(|| {
                    rays.par_iter().for_each(|r| {
                        std::hint::black_box(cpu_query(&bvh, r));
                    })
                })
            })
            .collect(),
    );
    let mut gpu_bvh = None;
    let upload = seconds(|| gpu_bvh = Some(GpuBvh::upload(&ctx, &bvh).expect("upload")));
    let gpu_bvh = gpu_bvh.expect("uploaded");
    let first = seconds(|| drop(query(&ctx, &gpu_bvh, &rays).expect("query")));
    let gpu = median(
        (0..runs)
            .map(|_| seconds(|| drop(query(&ctx, &gpu_bvh, &rays).expect("query"))))
            .collect(),
    );
    let m = |s: f64| nrays as f64 / s / 1e6;
    println!(
        "| {name} | {} | {:.2} | {:.2} | {:.2} | {:.0} | {:.0} | {:.2} |",
        scene.triangle_count(),
        m(cpu1),
        m(cpu_all),
        m(gpu),
        upload * 1e3,
        first * 1e3,
        gpu_bvh.bytes as f64 / 1e6,
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let nrays = match args.iter().position(|a| a == "--rays") {
        Some(i) => args[i + 1].parse().expect("--rays N"),
        None => 1 << 18,
    };
    let runs = 3;
    let ctx = gpu::context(None).expect("a GPU adapter");
    println!("adapter: {} ({:?})", ctx.info.name, ctx.info.device_type);
    let compile = seconds(|| drop(QueryPipeline::get(&ctx)));
    let cornell = builtin::load("cornell").expect("built-in");
    let tiny = GpuBvh::upload(&ctx, &SceneBvh::build(&cornell)).expect("upload");
    let first = seconds(|| drop(query(&ctx, &tiny, &random_rays(&cornell, 64, 1))));
    println!(
        "query pipeline: created in {:.0} ms, first 64-ray query {:.0} ms (lavapipe compiles \
         at the first dispatch)",
        compile * 1e3,
        first * 1e3
    );
    println!(
        "CPU threads: {}, rays: {nrays}, median of {runs}\n",
        rayon::current_num_threads()
    );
    println!(
        "| scene | triangles | CPU 1 thread Mrays/s | CPU all threads Mrays/s | GPU Mrays/s | \
         GPU BVH upload ms | GPU first query ms | GPU BVH MB |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for name in ["cornell", "cornell-glass", "ring-room"] {
        row(name, &builtin::load(name).expect("built-in"), nrays, runs);
    }
    row("dense-cornell", &dense_cornell(), nrays, runs);
}
