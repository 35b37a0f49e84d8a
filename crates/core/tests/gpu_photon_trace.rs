//! The GPU photon trace (`gpu::photon::trace::continue_paths`) against the CPU trace
//! (`photon::trace::continue_paths`) on the same first-scatter rays (the bounce maps traced
//! in the CPU BVH, as `ispm` gets them on lavapipe): the two use different random numbers,
//! so they agree in distribution, not photon by photon.
//!
//! Per surface (photons grouped by the material of the triangle they lie on) and per
//! bounce 1, 2, ≥3: the number of stored photons and their power (summed over RGB). Bounce
//! 1 (the rays' first hits, no random number involved) must agree in count and power to
//! 1e-3 (rays grazing an edge may hit either side: tests/gpu_bvh.rs allows 1 in 1000). For the later bounces the rays are split into K = 16 interleaved batches, independent paths each; per batch the
//! CPU and GPU sums differ by d_k, and t = Σd_k / √(K/(K−1)·Σ(d_k − d̄)²) follows Student's
//! t with 15 degrees of freedom when both traces have the same expectation. Bound: |t| ≤ 4.5
//! (two-sided p ≈ 4e-4 per comparison; ~60 comparisons over the three scenes: a 2% chance of
//! a false alarm for a correct trace, and the seeds are fixed, so the run is reproducible).
//! Only groups with at least 200 CPU photons are tested (the t statistic needs many paths
//! per batch). The test is not vacuous: it prints each group's relative standard error
//! and requires it under 4% for the two largest groups of bounce ≥ 2 (measured 0.7–3.2%),
//! so a bias of 4.5·√2·se (4–20%) in a main surface's power fails it. Absorbed + escaped + truncated paths add up to the rays on
//! both sides.

mod common;

use gi_core::gpu;
use gi_core::gpu::photon::scene::GpuPhotonScene;
use gi_core::photon::bounce::trace_bounce_maps;
use gi_core::photon::trace::Checked;
use gi_core::photon::{continue_paths, Photon, PhotonRay, PhotonSet, PhotonTraceSettings};
use gi_core::scene::builtin;
use gi_core::scene::light_views::light_views;
use gi_core::scene::SceneUpdate;
use gi_core::trace::SceneBvh;
use gi_core::{Scene, Silent};
use glam::{Mat4, Vec3};
use std::collections::BTreeMap;

const BATCHES: usize = 16;
const T_BOUND: f64 = 4.5;

/// The surface a photon lies on: the material of the triangle a short ray back along its
/// normal hits (`u32::MAX`: none found).
fn surface_of(scene: &Scene, bvh: &SceneBvh, p: &Photon) -> u32 {
    let n = p.normal();
    let o = p.position() + n * 1e-3;
    bvh.intersect(o, -n, 1e-2)
        .map_or(u32::MAX, |h| scene.triangle_material(h.triangle as usize))
}

/// Per (surface, bounce class) and batch: photon count and power.
type Sums = BTreeMap<(u32, u32), [[f64; 2]; BATCHES]>;

fn sums(scene: &Scene, bvh: &SceneBvh, sets: &[PhotonSet]) -> Sums {
    let mut out = Sums::new();
    for (k, set) in sets.iter().enumerate() {
        for p in &set.photons {
            let key = (surface_of(scene, bvh, p), p.bounce.min(3));
            let e = out.entry(key).or_insert([[0.0; 2]; BATCHES]);
            e[k][0] += 1.0;
            e[k][1] += p.power().element_sum() as f64;
        }
    }
    out
}

/// Student's t of the batch differences, and the relative standard error of the CPU total.
fn t_of(cpu: &[[f64; 2]; BATCHES], gpu: &[[f64; 2]; BATCHES], i: usize) -> (f64, f64) {
    let d: Vec<f64> = (0..BATCHES).map(|k| cpu[k][i] - gpu[k][i]).collect();
    let mean = d.iter().sum::<f64>() / BATCHES as f64;
    let ss: f64 = d.iter().map(|x| (x - mean).powi(2)).sum();
    let se = (ss * BATCHES as f64 / (BATCHES as f64 - 1.0)).sqrt();
    let total: f64 = cpu.iter().map(|b| b[i]).sum();
    (
        mean * BATCHES as f64 / se.max(1e-30),
        se / 2f64.sqrt() / total.max(1e-30),
    )
}

/// The first-scatter rays of `scene`'s bounce maps with `photons` texels.
fn first_scatter(scene: &Scene, bvh: &SceneBvh, photons: u64) -> Vec<PhotonRay> {
    let layers = light_views(scene, photons);
    let control = Checked::new(&Silent, "bounce maps");
    trace_bounce_maps(scene, bvh, &layers, 3, &control)
        .expect("bounce maps")
        .rays
}

fn check_scene(name: &str, scene: &Scene, photons: u64) -> Sums {
    let ctx = gpu::context(None).expect("a GPU adapter (lavapipe in CI)");
    let bvh = SceneBvh::build(scene);
    let rays = first_scatter(scene, &bvh, photons);
    let gs = GpuPhotonScene::upload(&ctx, scene, &bvh).expect("a scene the GPU trace supports");
    let s = PhotonTraceSettings {
        max_bounces: 8,
        store_direct: false,
        differentials: None,
    };
    let batch =
        |k: usize| -> Vec<PhotonRay> { rays.iter().skip(k).step_by(BATCHES).copied().collect() };
    let (mut cpu, mut gpu_sets) = (Vec::new(), Vec::new());
    for k in 0..BATCHES {
        let b = batch(k);
        let c = continue_paths(scene, &bvh, &b, &s, 100 + k as u64);
        let g = gpu::photon::trace::continue_paths(&ctx, &gs, &b, &s, 200 + k as u64)
            .expect("GPU trace");
        for set in [&c, &g] {
            assert_eq!(
                set.absorbed + set.escaped + set.truncated,
                b.len() as u64,
                "{name}"
            );
        }
        cpu.push(c);
        gpu_sets.push(g);
    }
    let (cs, gsums) = (sums(scene, &bvh, &cpu), sums(scene, &bvh, &gpu_sets));
    let zero = [[0.0; 2]; BATCHES];
    let mut failures = Vec::new();
    let mut errors = Vec::new();
    for (key, c) in &cs {
        let n: f64 = c.iter().map(|b| b[0]).sum();
        if n < 200.0 {
            continue;
        }
        let g = gsums.get(key).unwrap_or(&zero);
        if key.1 == 1 {
            // The continued rays' first hits: no random number decides them, so both
            // sides store the same photons up to rays that graze an edge, where rounding
            // decides the hit (tests/gpu_bvh.rs allows 1 in 1000).
            let total = |s: &[[f64; 2]; BATCHES], i: usize| s.iter().map(|b| b[i]).sum::<f64>();
            let (dn, dp) = (
                (total(c, 0) - total(g, 0)).abs() / total(c, 0),
                (total(c, 1) / total(g, 1) - 1.0).abs(),
            );
            println!(
                "{name} surface {} bounce 1: count {dn:.2e}, power {dp:.2e} apart",
                key.0
            );
            if dn > 1e-3 || dp > 1e-3 {
                failures.push(format!("{key:?}: first hits differ: {dn}, {dp}"));
            }
            continue;
        }
        for (i, what) in [(0, "count"), (1, "power")] {
            let (t, rel) = t_of(c, g, i);
            let gt: f64 = g.iter().map(|b| b[i]).sum();
            let ct: f64 = c.iter().map(|b| b[i]).sum();
            println!(
                "{name} surface {} bounce {}: {what} cpu {ct:.4} gpu {gt:.4} ({:+.2}%, se {:.2}%), t {t:.2}",
                key.0,
                key.1,
                100.0 * (gt / ct - 1.0),
                100.0 * rel
            );
            if i == 1 {
                errors.push((ct, rel));
            }
            if t.abs() > T_BOUND {
                failures.push(format!("{key:?} {what}: t {t:.2}"));
            }
        }
    }
    // Surfaces the GPU stores on that the CPU never does (a side or material mix-up).
    for (key, g) in &gsums {
        let n: f64 = g.iter().map(|b| b[0]).sum();
        if !cs.contains_key(key) && n >= 50.0 {
            failures.push(format!("{key:?}: {n} GPU photons, none on the CPU"));
        }
    }
    assert!(failures.is_empty(), "{name}: {failures:#?}");
    errors.sort_by(|a, b| b.0.total_cmp(&a.0));
    assert!(
        errors.len() >= 2,
        "{name}: {} surfaces tested",
        errors.len()
    );
    for (total, rel) in &errors[..2] {
        assert!(
            *rel < 0.04,
            "{name}: a main surface's power ({total}) has se {rel}"
        );
    }
    cs
}

#[test]
fn gpu_trace_matches_the_cpu_on_cornell() {
    check_scene("cornell", &builtin::load("cornell").unwrap(), 60_000);
}

#[test]
fn gpu_trace_matches_the_cpu_on_a_glossy_scene() {
    check_scene("glossy", &common::spot_scene("glossy", 0.2, 3), 150_000);
}

/// A one-sided material's back stores and scatters nothing on both sides (`one_sided`,
/// `continue.wgsl`'s `one_sided_back`): `cornell`'s red wall one-sided and turned half a
/// turn about its own in-plane axis, so it stays in place but faces out and every photon
/// meets its back. The CPU stores no photon on it (two-sided it holds a main share), and
/// `check_scene` fails on any GPU surface the CPU never stores on (50 photons or more).
#[test]
fn gpu_trace_meets_one_sided_backs_as_the_cpu() {
    let mut scene = builtin::load("cornell").unwrap();
    let red = scene
        .material_names
        .iter()
        .position(|n| n == "red")
        .unwrap();
    scene.materials[red].one_sided = true;
    let wall = (scene.objects.iter())
        .position(|o| scene.triangle_material(o.triangles.start as usize) == red as u32)
        .unwrap();
    let transform = scene.objects[wall].transform * Mat4::from_rotation_x(std::f32::consts::PI);
    scene
        .apply(&SceneUpdate::Transform {
            object: wall,
            transform,
        })
        .unwrap();
    let cpu = check_scene("cornell, red wall one-sided from behind", &scene, 60_000);
    let on_red: f64 = (cpu.iter())
        .filter(|(k, _)| k.0 == red as u32)
        .map(|(_, b)| b.iter().map(|x| x[0]).sum::<f64>())
        .sum();
    assert_eq!(on_red, 0.0, "CPU photons on the one-sided back");
}

#[test]
fn gpu_trace_matches_the_cpu_on_caustics() {
    // A glass and a mirror sphere: refraction, Fresnel reflection and mirror paths.
    check_scene(
        "cornell-glass",
        &builtin::load("cornell-glass").unwrap(),
        60_000,
    );
}

#[test]
fn gpu_trace_refuses_what_it_cannot_trace() {
    let ctx = gpu::context(None).expect("a GPU adapter (lavapipe in CI)");
    let mut scene = builtin::load("cornell").unwrap();
    scene.materials[0].rough_glass = true;
    scene.materials[0].transmission = Vec3::ONE;
    let bvh = SceneBvh::build(&scene);
    let e = GpuPhotonScene::upload(&ctx, &scene, &bvh)
        .err()
        .expect("refused");
    assert!(e.to_string().contains("photon_trace"), "{e}");
}

/// The mean of an `ispm` frame of `scene` traced by `trace` with `seed`.
fn ispm_mean(scene: &Scene, trace: gi_core::gpu::photon::PhotonTrace, seed: u64) -> f64 {
    let settings =
        gi_core::options!(Ispm, photons: 20_000, spp: 1, seed: seed, photon_trace: trace);
    let out = gi_core::render(scene, &settings, &Silent).expect("ispm frame");
    assert_eq!(out.stats.photon_trace, trace.name());
    assert!(out.stats.stages.iter().any(|(s, _)| s == "gpu trace") == (trace.name() == "gpu"));
    out.radiance.mean().element_sum() as f64
}

/// `ispm` images with the GPU and the CPU trace: the same mean within the seeds' noise.
/// Four seeds each; bound |mean_gpu − mean_cpu| ≤ 4·√(s²_cpu/4 + s²_gpu/4) + 0.2%, s² the
/// seeds' sample variances (the 0.2% floor: below the direct light's share, where the
/// photon noise that s measures vanishes in the mean).
#[test]
fn ispm_image_mean_is_the_same_with_the_gpu_trace() {
    use gi_core::gpu::photon::PhotonTrace;
    for name in ["cornell", "cornell-glass"] {
        let mut scene = builtin::load(name).unwrap();
        scene.camera = scene.camera.with_size(48, 36);
        let stats = |t: PhotonTrace| {
            let m: Vec<f64> = (1..=4).map(|s| ispm_mean(&scene, t, s)).collect();
            let mean = m.iter().sum::<f64>() / 4.0;
            let var = m.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 3.0;
            (mean, var, m)
        };
        let (c, vc, mc) = stats(PhotonTrace::Cpu);
        let (g, vg, mg) = stats(PhotonTrace::Gpu);
        let bound = 4.0 * (vc / 4.0 + vg / 4.0).sqrt() + 0.002 * c;
        println!(
            "{name}: cpu {c:.5} {mc:?}, gpu {g:.5} {mg:?}, diff {:+.3}%, bound {:.3}%",
            100.0 * (g / c - 1.0),
            100.0 * bound / c
        );
        assert!(
            (g - c).abs() <= bound,
            "{name}: cpu {c} gpu {g}, bound {bound}"
        );
    }
}

#[test]
fn photon_trace_names_parse_and_gpu_refuses_footprints() {
    use gi_core::gpu::photon::PhotonTrace;
    for t in PhotonTrace::ALL {
        assert_eq!(t.name().parse::<PhotonTrace>().unwrap(), *t);
    }
    let e = "cuda".parse::<PhotonTrace>().unwrap_err().to_string();
    assert!(e.contains("photon_trace"), "{e}");
    let scene = builtin::load("cornell").unwrap();
    let settings = gi_core::options!(Ispm, photons: 2_000, spp: 1, footprint_volumes: true, photon_trace: PhotonTrace::Gpu);
    let e = gi_core::render(&scene, &settings, &Silent).expect_err("refused");
    assert!(e.to_string().contains("photon_trace"), "{e}");
}
