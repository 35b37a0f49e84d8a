//! CPU/GPU parity of the ray queries: the same rays traced by `SceneBvh` (obvhs's CWBVH on
//! the CPU) and by `gpu/shaders/bvh/bvh.wgsl` over the flattened binary trees
//! (`trace::bvh_flat`) must find the same closest triangle at the same distance, and agree
//! on occlusion.
//!
//! Both sides run the same Möller–Trumbore test on the same floats (the edges are computed
//! on the CPU and uploaded), so they differ only by rounding: fused multiply-adds the
//! shader compiler may form, and the instance transform (the CPU's SSE `Affine3A` against
//! the shader's dot products). Tolerances:
//! - distance: |t_gpu − t_cpu| ≤ 1e-5·(1 + t) (about 80 ulps of t; the scenes are metres,
//!   so 10 µm at 1 m);
//! - barycentrics of the same triangle: 1e-4;
//! - a different triangle is accepted only at the same distance (a ray through a shared
//!   edge or coplanar copies: a tie either side may break);
//! - a hit on one side only (or occlusion disagreeing) is accepted only where rounding can
//!   decide it: the hit's barycentrics within 1e-5 of an edge (a grazing ray), its
//!   distance within the tolerance of tmax, or within 2e-4 of the origin (both traversals
//!   cull boxes the ray leaves before t = 1e-4, obvhs's `EPSILON`; the CPU tests its
//!   quantised, slightly larger boxes). At most 1 ray in 1000 may be such a graze.
//!
//! Everything else must match exactly: any other difference fails the test.

use gi_core::gpu::bvh::query::{query, random_rays, QueryRay};
use gi_core::gpu::bvh::GpuBvh;
use gi_core::scene::builtin;
use gi_core::trace::{Hit, SceneBvh};
use gi_core::{gpu, Scene};
use std::collections::HashMap;

fn t_tolerance(t: f32) -> f32 {
    1e-5 * (1.0 + t.abs())
}

/// What the comparison found.
#[derive(Default, Debug)]
struct Tally {
    rays: usize,
    hits: usize,
    ties: usize,
    grazes: usize,
    max_dt: f32,
    mismatches: Vec<String>,
}

/// Whether rounding may decide a hit at `h` on one side only (see the module).
fn grazing(h: &Hit, tmax: f32) -> bool {
    let e = 1e-5;
    h.u < e
        || h.v < e
        || 1.0 - h.u - h.v < e
        || (tmax - h.t).abs() <= t_tolerance(tmax)
        || h.t < 2e-4
}

fn compare_closest(t: &mut Tally, r: &QueryRay, cpu: Option<Hit>, gpu: Option<Hit>) {
    match (cpu, gpu) {
        (None, None) => {}
        (Some(c), Some(g)) => {
            t.hits += 1;
            let dt = (c.t - g.t).abs();
            t.max_dt = t.max_dt.max(dt / (1.0 + c.t));
            let same_t = dt <= t_tolerance(c.t);
            if c.triangle == g.triangle {
                let duv = (c.u - g.u).abs().max((c.v - g.v).abs());
                if !same_t || duv > 1e-4 {
                    t.mismatches.push(format!("{r:?}: cpu {c:?} gpu {g:?}"));
                }
            } else if same_t {
                t.ties += 1;
            } else {
                t.mismatches.push(format!("{r:?}: cpu {c:?} gpu {g:?}"));
            }
        }
        (Some(h), None) | (None, Some(h)) if grazing(&h, r.tmax()) => t.grazes += 1,
        (c, g) => t.mismatches.push(format!("{r:?}: cpu {c:?} gpu {g:?}")),
    }
}

fn compare_occluded(t: &mut Tally, bvh: &SceneBvh, r: &QueryRay, gpu: Option<Hit>) {
    let (o, d) = (r.origin(), r.dir());
    let cpu = bvh.occluded(o, d, r.tmax());
    t.hits += cpu as usize;
    if cpu == gpu.is_some() {
        return;
    }
    // Disagreement: only a graze of the nearest blocker or one at tmax may explain it.
    match bvh.intersect(o, d, f32::INFINITY) {
        Some(h) if grazing(&h, r.tmax()) => t.grazes += 1,
        h => t.mismatches.push(format!(
            "{r:?}: cpu occluded {cpu}, gpu {gpu:?}, nearest {h:?}"
        )),
    }
}

/// Traces `n` rays over `scene` on both sides and asserts the module's tolerances.
fn check_scene(scene: &Scene, name: &str, n: usize) -> Tally {
    let ctx = gpu::context(None).expect("a GPU adapter (lavapipe in CI)");
    let bvh = SceneBvh::build(scene);
    let gpu_bvh = GpuBvh::upload(&ctx, &bvh).expect("upload");
    let rays = random_rays(scene, n, 11);
    let hits = query(&ctx, &gpu_bvh, &rays).expect("GPU query");
    assert_eq!(hits.len(), rays.len());
    let mut t = Tally {
        rays: n,
        ..Default::default()
    };
    for (r, g) in rays.iter().zip(&hits) {
        if r.any() {
            compare_occluded(&mut t, &bvh, r, *g);
        } else {
            let cpu = bvh.intersect(r.origin(), r.dir(), r.tmax());
            compare_closest(&mut t, r, cpu, *g);
        }
    }
    eprintln!(
        "{name}: {} rays, {} hits, {} ties, {} grazes, max |dt|/(1+t) {:.2e}",
        t.rays, t.hits, t.ties, t.grazes, t.max_dt
    );
    assert!(
        t.mismatches.is_empty(),
        "{name}: {} mismatches, e.g. {:?}",
        t.mismatches.len(),
        &t.mismatches[..t.mismatches.len().min(3)]
    );
    assert!(t.grazes * 1000 <= n, "{name}: {} grazes", t.grazes);
    // Not vacuous: most rays from inside a room hit something.
    assert!(t.hits * 3 >= n, "{name}: only {} hits", t.hits);
    t
}

/// The baked path (one world-space mesh under one identity instance): cornell, and the
/// glass box with its spheres.
#[test]
fn baked_scenes_match_the_cpu() {
    for name in ["cornell", "cornell-glass"] {
        let scene = builtin::load(name).unwrap();
        check_scene(&scene, name, 60_000);
    }
}

/// The two-level path: a room with four balls of one 20,480-triangle mesh (too many to
/// bake): one placed as it is, three instances of it turned, mirrored (swapped
/// barycentrics) and scaled.
#[test]
fn instanced_scene_matches_the_cpu() {
    let mut v: serde_json::Value =
        serde_json::from_str(builtin::json("cornell-glass").unwrap()).unwrap();
    let placements = [
        serde_json::json!({"translate": [-0.5, 0.15, 0.6]}),
        serde_json::json!({"translate": [0.5, 0.15, 0.75], "rotate": [10, 30, 0]}),
        serde_json::json!({"translate": [-0.05, 0.12, 0.8], "scale": [-0.8, 0.8, 0.8]}),
        serde_json::json!({"translate": [0.0, 1.3, 0.3], "scale": 0.6}),
    ];
    let objects = v["objects"].as_array_mut().unwrap();
    for (i, transform) in placements.into_iter().enumerate() {
        let shape = match i {
            0 => serde_json::json!({"type": "sphere", "radius": 0.15, "subdivisions": 5}),
            _ => serde_json::json!({"type": "instance", "object": "ball0"}),
        };
        objects.push(
            serde_json::json!({"name": format!("ball{i}"), "shape": shape,
            "transform": transform, "material": "white"}),
        );
    }
    let scene = Scene::from_json(&v.to_string(), "instanced", &HashMap::new()).unwrap();
    assert!(scene.triangle_count() > gi_core::trace::bvh::BAKE_TRIANGLES);
    let t = check_scene(&scene, "instanced", 60_000);
    assert!(t.hits > 20_000);
}

/// A scene with no triangles: every query misses, none fails.
#[test]
fn empty_bvh_misses() {
    let ctx = gpu::context(None).expect("a GPU adapter (lavapipe in CI)");
    let bvh = SceneBvh::from_triangles(&[]);
    let gpu_bvh = GpuBvh::upload(&ctx, &bvh).expect("upload");
    let (o, d) = (glam::Vec3::ZERO, glam::Vec3::Z);
    let rays = [false, true].map(|any| QueryRay::new(o, d, f32::INFINITY, any));
    let hits = query(&ctx, &gpu_bvh, &rays).unwrap();
    assert!(hits.iter().all(Option::is_none));
}
