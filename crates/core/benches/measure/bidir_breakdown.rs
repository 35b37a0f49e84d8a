//! Where `bidir` loses light against `path` (issue 29): both rendered limited to the same
//! `max_depth` (1, 2, 3, 7) and the image differences between successive depths taken as the
//! terms (direct light; one bounce; two bounces; bounces 3–6), per image region. Markdown to
//! stdout:
//!
//! `cargo run -p gi-core --profile test --example bidir_breakdown -- --frames 16 --spp 1024`
//!
//! Options: `--scenes a,b` (`cornell,cornell-anim`), `--size N` (32), `--frames N` (`bidir`
//! frames, seeds 1…N, 16), `--spp N` (`path`, 1024), `--bundles N` (32), `--set KEY=N`
//! (repeatable: an integer setting of `bidir`, e.g. `shadow_map_size=2048`).
//!
//! - Regions, from each pixel-centre point x and its normal: the nearest other surface over
//!   64 stratified cosine-hemisphere rays (the CPU BVH), as a fraction of the scene's bounding
//!   diagonal: "corners" (< 3%), "near walls" (3–15%), "far field" (≥ 15%).
//! - Per term and region: the term's mean (RGB average) for `path` and `bidir` (± the standard
//!   error over the `bidir` frames), their ratio, and the term's share of the whole deficit
//!   (bidir − path of the term over `path`'s depth-7 mean of the region).
//! - The one-bounce term is also given per strategy (`bidir_strategy` vpl / bundle, no MIS).
//! - `path` renders each depth with the same seed, so successive depths share their first
//!   bounces and the differences are less noisy than the images.

mod common;

use gi_core::frame::options::BidirStrategy;
use gi_core::scene::builtin;
use gi_core::trace::bvh::{flat_triangles, MeshBvh};
use gi_core::{render, Image, Scene, Silent};

const REGIONS: [&str; 4] = ["all", "corners", "near walls", "far field"];

/// Per-frame region means.
type Frames<'a> = &'a [[f64; 4]];

/// A table row: label, the frames of the image, those of the image subtracted, and the
/// term's index in `path`'s depths (0 direct, 1–3 the bounce terms, 4 all).
type Row<'a> = (&'a str, Frames<'a>, Option<Frames<'a>>, usize);

/// Region of each pixel (1 corners, 2 near walls, 3 far field; 0 background).
fn regions(scene: &Scene, position: &Image, normal: &Image, depth: &[f32]) -> Vec<usize> {
    let bvh = MeshBvh::from_triangles(&flat_triangles(scene));
    let (lo, hi) = scene.vertex_box();
    let diag = (hi - lo).length();
    let n = 8u32;
    position
        .pixels
        .iter()
        .zip(&normal.pixels)
        .zip(depth)
        .map(|((&p, &nrm), &d)| {
            if d <= 0.0 {
                return 0;
            }
            let nrm = nrm.normalize_or_zero();
            let (t, bt) = nrm.any_orthonormal_pair();
            let mut nearest = f32::INFINITY;
            for i in 0..n {
                for j in 0..n {
                    let (u, v) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    let r = u.sqrt();
                    let phi = std::f32::consts::TAU * v;
                    let dir = t * (r * phi.cos())
                        + bt * (r * phi.sin())
                        + nrm * (1.0 - u).max(0.0).sqrt();
                    let o = p + nrm * (1e-4 * diag);
                    if let Some((_, hit, _, _)) = bvh.intersect(o, dir, nearest) {
                        nearest = nearest.min(hit);
                    }
                }
            }
            let f = nearest / diag;
            if f < 0.03 {
                1
            } else if f < 0.15 {
                2
            } else {
                3
            }
        })
        .collect()
}

/// Mean (RGB average) of `img` over each region (index 0: all covered pixels).
fn region_means(img: &Image, region: &[usize]) -> [f64; 4] {
    let mut sum = [0.0; 4];
    let mut n = [0usize; 4];
    for (p, &r) in img.pixels.iter().zip(region) {
        if r == 0 {
            continue;
        }
        let v = p.as_dvec3().element_sum() / 3.0;
        for k in [0, r] {
            sum[k] += v;
            n[k] += 1;
        }
    }
    std::array::from_fn(|k| sum[k] / n[k].max(1) as f64)
}

/// Per-frame region means of `bidir` at `depth` (and `strategy`).
fn bidir_frames(
    scene: &Scene,
    base: &gi_core::RenderOptions,
    depth: u32,
    strategy: BidirStrategy,
    frames: u64,
    region: &[usize],
) -> Vec<[f64; 4]> {
    (1..=frames)
        .map(|seed| {
            let s = base
                .clone()
                .with("max_depth", depth)
                .with("bidir_strategy", strategy)
                .with("seed", seed);
            region_means(&render(scene, &s, &Silent).expect("bidir").radiance, region)
        })
        .collect()
}

/// Mean and standard error of `a − b` over frames, per region.
fn diff_stats(a: &[[f64; 4]], b: Option<&[[f64; 4]]>) -> [(f64, f64); 4] {
    std::array::from_fn(|k| {
        let d: Vec<f64> = a
            .iter()
            .enumerate()
            .map(|(i, x)| x[k] - b.map_or(0.0, |b| b[i][k]))
            .collect();
        let n = d.len() as f64;
        let m = d.iter().sum::<f64>() / n;
        let var = d.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
        (m, (var / n).sqrt())
    })
}

fn main() {
    let args = common::Args::get();
    let scenes = args.value("--scenes").unwrap_or("cornell,cornell-anim");
    let num = |flag: &str, default: u32| {
        args.value(flag)
            .map_or(default, |v| v.parse().expect("a number"))
    };
    let size = num("--size", 32);
    let frames = num("--frames", 16) as u64;
    let spp = num("--spp", 1024);
    let bundles = num("--bundles", 32);
    println!(
        "Command: `cargo run -p gi-core --profile test --example bidir_breakdown -- --scenes \
         {scenes} --size {size} --frames {frames} --spp {spp} --bundles {bundles}` · {size}×{size} \
         · `bidir` {bundles} bundles, other settings default, mean of {frames} frames (± standard \
         error over them) · `path` {spp} spp, each depth with the same seed · term = image(depth) \
         − image(previous depth), mean of RGB · share = (bidir − path) of the term / path's \
         depth-7 mean of the region.\n"
    );
    for name in scenes.split(',') {
        let scene = builtin::load(name).expect("built-in scene");
        let mut base = gi_core::options!(Bidir, spp: 1, width: size, height: size, seed: 1)
            .with("bundles", bundles);
        for kv in args.values("--set") {
            let (k, v) = kv.split_once('=').expect("--set KEY=N");
            base = base.with(k, v.parse::<i64>().expect("an integer"));
        }
        let probe = render(&scene, &base, &Silent).expect("bidir");
        let region = regions(&scene, &probe.position, &probe.normal, &probe.depth);
        let counts: Vec<usize> = (0..4)
            .map(|k| {
                region
                    .iter()
                    .filter(|&&r| r != 0 && (k == 0 || r == k))
                    .count()
            })
            .collect();
        let depths = [1u32, 2, 3, 7];
        let path: Vec<[f64; 4]> = depths
            .iter()
            .map(|&d| {
                let s = base
                    .clone()
                    .with_method(gi_core::Method::Path)
                    .with("spp", spp)
                    .with("seed", 99)
                    .with("max_depth", d);
                region_means(
                    &render(&scene, &s, &Silent).expect("path").radiance,
                    &region,
                )
            })
            .collect();
        let mis: Vec<Vec<[f64; 4]>> = depths
            .iter()
            .map(|&d| bidir_frames(&scene, &base, d, BidirStrategy::Mis, frames, &region))
            .collect();
        let vpl = bidir_frames(&scene, &base, 2, BidirStrategy::Vpl, frames, &region);
        let bundle = bidir_frames(&scene, &base, 2, BidirStrategy::Bundle, frames, &region);
        println!("## {name}\n");
        println!(
            "Pixels: {}.\n",
            (0..4)
                .map(|k| format!("{} {}", REGIONS[k], counts[k]))
                .collect::<Vec<_>>()
                .join(", ")
        );
        println!("| term | region | path | bidir | bidir / path | share of depth 7 |");
        println!("|---|---|---|---|---|---|");
        let total = &path[3];
        let rows: [Row; 7] = [
            ("direct (depth 1)", &mis[0], None, 0),
            ("one bounce (MIS)", &mis[1], Some(&mis[0]), 1),
            ("one bounce, VPLs only", &vpl, Some(&mis[0]), 1),
            ("one bounce, bundles only", &bundle, Some(&mis[0]), 1),
            ("two bounces", &mis[2], Some(&mis[1]), 2),
            ("bounces 3–6", &mis[3], Some(&mis[2]), 3),
            ("all (depth 7)", &mis[3], None, 4),
        ];
        for (label, a, b, term) in rows {
            let stats = diff_stats(a, b);
            for k in 0..4 {
                let p = match term {
                    0 => path[0][k],
                    4 => path[3][k],
                    t => path[t][k] - path[t - 1][k],
                };
                let (m, se) = stats[k];
                println!(
                    "| {label} | {} | {p:.5} | {m:.5} ± {se:.5} | {:.4} | {:+.2}% |",
                    REGIONS[k],
                    m / p,
                    100.0 * (m - p) / total[k]
                );
            }
        }
        println!();
    }
}
