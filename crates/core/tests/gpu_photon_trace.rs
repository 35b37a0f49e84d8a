//! The GPU photon trace (`gpu::photon::trace::continue_paths`) against the CPU trace
//! (`photon::trace::continue_paths`) on the same first-scatter rays (the bounce maps traced
//! in the CPU BVH, as `ispm` gets them on lavapipe): the two use different random numbers,
//! so they agree in distribution, not photon by photon. The sources the bounce maps do not
//! see (area lights, the sun, the sky plain and aimed, and photon focusing's aimed caustic
//! photons) are compared the same way from their emission (`check_source` and the aimed
//! tests): emitted alike on both sides (`gpu::photon::emitted` emits on the CPU with the CPU
//! trace's draws), so their first hits (bounce 0, stored there) must agree to 1e-3 and the
//! later bounces pair up batch by batch (batch k: seed 100 + k on both sides).
//!
//! Per surface (photons grouped by the material of the triangle they lie on) and per
//! bounce 1, 2, ≥3: the number of stored photons and their power (summed over RGB). Bounce
//! 1 (the rays' first hits, no random number involved) must agree in count and power to
//! 1e-3 (rays grazing an edge may hit either side: tests/gpu_bvh.rs allows 1 in 1000). For the later bounces the rays are split into K = 16 interleaved batches, independent paths each; per batch the
//! CPU and GPU sums differ by d_k, and t = Σd_k / √(K/(K−1)·Σ(d_k − d̄)²) follows Student's
//! t with 15 degrees of freedom when both traces have the same expectation. Bound: |t| ≤ 4.5
//! (two-sided p ≈ 4e-4 per comparison; 148 comparisons over the module's tests: a 6% chance
//! of one false alarm for a correct trace, and the seeds are fixed, so the run is
//! reproducible; measured |t| ≤ 2.31).
//! Only groups with at least 200 CPU photons are tested (the t statistic needs many paths
//! per batch). The test is not vacuous: it prints each group's relative standard error
//! and requires it under 4% for the two largest groups after the first hits (measured
//! 0.7–3.2% for the bounce maps' rays), so a bias of 4.5·√2·se (4–20%) in a main surface's
//! power fails it. Controls of the source tests (each then reverted): the GPU scatter's
//! power ×1.05 fails all five (|t| up to 70); the emitted rays' power ×1.02 fails their
//! first hits (1.96% apart). Absorbed + escaped + truncated paths add up to the rays on
//! both sides.

mod common;

use gi_core::gpu;
use gi_core::gpu::photon::emitted;
use gi_core::gpu::photon::scene::GpuPhotonScene;
use gi_core::photon::bounce::trace_bounce_maps;
use gi_core::photon::focus::Focus;
use gi_core::photon::sky_guide::SkyGuide;
use gi_core::photon::trace::{
    emit_aimed_caustics, emit_aimed_sky, emit_and_trace_sources, sky_pilot, Checked,
};
use gi_core::photon::{continue_paths, Photon, PhotonRay, PhotonSet, PhotonTraceSettings};
use gi_core::scene::builtin;
use gi_core::scene::light_views::light_views;
use gi_core::scene::{SceneUpdate, Source, Sources};
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
    compare(name, scene, &bvh, &cpu, &gpu_sets, 1)
}

/// The per-batch photon sets `cpu` and `gpu` of `scene` compared per surface and bounce
/// class (the module's tests; `first`: the bounce of the rays' first hits, which must agree
/// to 1e-3); the CPU's sums.
fn compare(
    name: &str,
    scene: &Scene,
    bvh: &SceneBvh,
    cpu: &[PhotonSet],
    gpu_sets: &[PhotonSet],
    first: u32,
) -> Sums {
    let (cs, gsums) = (sums(scene, bvh, cpu), sums(scene, bvh, gpu_sets));
    let zero = [[0.0; 2]; BATCHES];
    let mut failures = Vec::new();
    let mut errors = Vec::new();
    for (key, c) in &cs {
        let n: f64 = c.iter().map(|b| b[0]).sum();
        if n < 200.0 {
            continue;
        }
        let g = gsums.get(key).unwrap_or(&zero);
        if key.1 == first {
            // The continued rays' first hits: no random number decides them, so both
            // sides store the same photons up to rays that graze an edge, where rounding
            // decides the hit (tests/gpu_bvh.rs allows 1 in 1000).
            let total = |s: &[[f64; 2]; BATCHES], i: usize| s.iter().map(|b| b[i]).sum::<f64>();
            let (dn, dp) = (
                (total(c, 0) - total(g, 0)).abs() / total(c, 0),
                (total(c, 1) / total(g, 1) - 1.0).abs(),
            );
            println!(
                "{name} surface {} bounce {first}: count {dn:.2e}, power {dp:.2e} apart",
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

/// The photons of `source` (`n` a batch) from `scene`, emitted and traced on the CPU
/// (`emit_and_trace_sources`) against emitted on the CPU and traced on the GPU
/// (`gpu::photon::emitted`), 16 batches of seeds 100–115, first hits (bounce 0) stored: the
/// same emission on both sides, so the first hits agree to 1e-3 and the later bounces pair
/// up batch by batch.
fn check_source(name: &str, scene: &Scene, source: Source, n: u64) -> Sums {
    let ctx = gpu::context(None).expect("a GPU adapter (lavapipe in CI)");
    let bvh = SceneBvh::build(scene);
    let gs = GpuPhotonScene::upload(&ctx, scene, &bvh).expect("a scene the GPU trace supports");
    let only = Sources::filtered(scene, |s| s == source);
    assert!(!only.is_empty(), "{name}: no {source:?}");
    let focus = Focus::default();
    let control = Checked::new(&Silent, "cpu trace");
    let (mut cpu, mut gpu_sets) = (Vec::new(), Vec::new());
    for k in 0..BATCHES as u64 {
        let seed = 100 + k;
        let c =
            emit_and_trace_sources(scene, &bvh, &only, n, &SOURCE_TRACE, seed, &control, &focus)
                .expect("CPU trace");
        let g = emitted::trace_sources(&ctx, &gs, scene, &only, n, &SOURCE_TRACE, seed, &focus)
            .expect("GPU trace");
        for set in [&c, &g] {
            assert_eq!(set.absorbed + set.escaped + set.truncated, n, "{name}");
        }
        cpu.push(c);
        gpu_sets.push(g);
    }
    compare(name, scene, &bvh, &cpu, &gpu_sets, 0)
}

/// The source tests' trace: every hit stored, from the first (direct light).
const SOURCE_TRACE: PhotonTraceSettings = PhotonTraceSettings {
    max_bounces: 8,
    store_direct: true,
    differentials: None,
};

/// A scene of the repository's `tests/scenes/openings/`.
fn openings(file: &str) -> Scene {
    let path = format!(
        "{}/../../tests/scenes/openings/{file}",
        env!("CARGO_MANIFEST_DIR")
    );
    let json = std::fs::read_to_string(&path).expect("scene file");
    Scene::from_json(&json, file, &Default::default()).expect("scene")
}

/// Outdoors: a glossy floor, a wall, a rough metal box, a glossy ball and a glass ball
/// under `lights` (JSON list items) and `environment` (a JSON member, or empty).
fn outdoor(lights: &str, environment: &str) -> Scene {
    let json = format!(
        r#"{{
  "camera": {{ "position": [0, 1.6, 3.6], "look_at": [0, 0.35, 0], "fov": 45, "width": 48, "height": 36 }},
  "lights": [{lights}],
  {environment}
  "materials": {{
    "floor": {{ "diffuse": [0.7, 0.7, 0.7], "specular": [0.04, 0.04, 0.04], "roughness": 0.5, "fresnel": true }},
    "wall": {{ "diffuse": [0.6, 0.55, 0.5] }},
    "ball": {{ "diffuse": [0.2, 0.35, 0.6], "specular": [0.05, 0.05, 0.05], "roughness": 0.3, "fresnel": true }},
    "metal": {{ "specular": [0.9, 0.7, 0.4], "roughness": 0.2 }},
    "glass": {{ "diffuse": [0, 0, 0], "transmission": [1, 1, 1], "ior": 1.5 }}
  }},
  "objects": [
    {{ "shape": {{ "type": "quad", "size": [4, 4] }}, "material": "floor" }},
    {{ "shape": {{ "type": "quad", "size": [4, 3] }}, "transform": {{ "rotate": [90, 0, 0], "translate": [0, 1.5, -1.5] }},
      "material": "wall" }},
    {{ "shape": {{ "type": "box", "size": [0.5, 0.7, 0.5] }}, "transform": {{ "rotate": [0, 30, 0], "translate": [-0.6, 0.35, -0.2] }},
      "material": "metal" }},
    {{ "shape": {{ "type": "sphere", "radius": 0.4, "subdivisions": 3 }}, "transform": {{ "translate": [0.5, 0.4, 0.2] }},
      "material": "ball" }},
    {{ "shape": {{ "type": "sphere", "radius": 0.3, "subdivisions": 3 }}, "transform": {{ "translate": [-0.1, 0.3, 0.9] }},
      "material": "glass" }}
  ]
}}"#
    );
    Scene::from_json(&json, "outdoor", &Default::default()).expect("scene")
}

const SUN: &str =
    r#"{"type": "directional", "direction": [-0.5, -1, -0.4], "irradiance": [3, 2.8, 2.5]}"#;
const SKY: &str = r#""environment": {"radiance": [0.3, 0.4, 0.6]},"#;

/// Area lights: `glass_room.json`'s ceiling lamp (an emitting quad) over a glass slab in a
/// closed room (diffuse and caustic paths).
#[test]
fn gpu_trace_matches_the_cpu_from_area_lights() {
    check_source(
        "glass room, area lamp",
        &openings("glass_room.json"),
        Source::Emitters,
        32_000,
    );
}

/// The sun: a directional light's photons from the bounding disc over a glossy floor, a
/// metal box, a glossy and a glass ball.
#[test]
fn gpu_trace_matches_the_cpu_from_the_sun() {
    check_source("outdoor, sun", &outdoor(SUN, ""), Source::Light(0), 32_000);
}

/// The sky: a constant environment's photons over the same objects (the sun there too: the
/// sky's photons alone are traced).
#[test]
fn gpu_trace_matches_the_cpu_from_the_sky() {
    check_source(
        "outdoor, sky",
        &outdoor(SUN, SKY),
        Source::Environment,
        32_000,
    );
}

/// The sky through a window (`window_room.json`): the plain photons and the ones aimed at
/// the window by a CPU pilot (`photon::sky_guide`), each emitted alike on both sides.
#[test]
fn gpu_trace_matches_the_cpu_from_the_sky_through_a_window() {
    let scene = openings("window_room.json");
    let ctx = gpu::context(None).expect("a GPU adapter (lavapipe in CI)");
    let bvh = SceneBvh::build(&scene);
    let gs = GpuPhotonScene::upload(&ctx, &scene, &bvh).expect("a scene the GPU trace supports");
    let control = Checked::new(&Silent, "cpu trace");
    let (pilot, n) = (8_192, 4_000);
    // The pilot as `ispm` runs it: paths that store past their first hit mark their rays.
    let pts = PhotonTraceSettings {
        store_direct: false,
        ..SOURCE_TRACE
    };
    let rays = sky_pilot(&scene, &bvh, pilot, &pts, 7, &control).expect("pilot");
    let guide = SkyGuide::new(&rays, pilot, scene.bounds(), n, n).expect("the window aims");
    let (mut cpu, mut gpu_sets) = (Vec::new(), Vec::new());
    for k in 0..BATCHES as u64 {
        let seed = 100 + k;
        let c = emit_aimed_sky(&scene, &bvh, &guide, n, &SOURCE_TRACE, seed, &control)
            .expect("CPU trace");
        let g = emitted::trace_aimed_sky(&ctx, &gs, &scene, &guide, &SOURCE_TRACE, seed)
            .expect("GPU trace");
        for set in [&c, &g] {
            assert_eq!(set.absorbed + set.escaped + set.truncated, guide.aimed());
        }
        cpu.push(c);
        gpu_sets.push(g);
    }
    compare("window room, aimed sky", &scene, &bvh, &cpu, &gpu_sets, 0);
    check_source(
        "window room, plain sky",
        &scene,
        Source::Environment,
        32_000,
    );
}

/// Photon focusing: `cornell-glass`'s light's photons aimed at the glass and the mirror
/// sphere (`Focus`), emitted alike (the CPU's first-hit test included) and traced on each
/// side; only paths whose first hit is specular go on, so nothing is stored at bounce 0
/// (asserted on the CPU: the test is not of first hits here).
#[test]
fn gpu_trace_matches_the_cpu_on_aimed_caustics() {
    let scene = builtin::load("cornell-glass").unwrap();
    let ctx = gpu::context(None).expect("a GPU adapter (lavapipe in CI)");
    let bvh = SceneBvh::build(&scene);
    let gs = GpuPhotonScene::upload(&ctx, &scene, &bvh).expect("a scene the GPU trace supports");
    let control = Checked::new(&Silent, "cpu trace");
    let focus = Focus::of_scene(&scene, 1.0);
    assert!(focus.covers_all(0), "the light's map holds both spheres");
    let n = 4_000;
    let (mut cpu, mut gpu_sets) = (Vec::new(), Vec::new());
    for k in 0..BATCHES as u64 {
        let seed = 100 + k;
        let c = emit_aimed_caustics(&scene, &bvh, 0, n, &SOURCE_TRACE, seed, &control, &focus)
            .expect("CPU trace");
        let g = emitted::trace_aimed_caustics(
            &ctx,
            &gs,
            &scene,
            &bvh,
            0,
            n,
            &SOURCE_TRACE,
            seed,
            &focus,
        )
        .expect("GPU trace");
        for set in [&c, &g] {
            assert_eq!(set.absorbed + set.escaped + set.truncated, n);
        }
        assert!(c.photons.iter().all(|p| p.bounce >= 1));
        cpu.push(c);
        gpu_sets.push(g);
    }
    compare(
        "cornell-glass, aimed caustics",
        &scene,
        &bvh,
        &cpu,
        &gpu_sets,
        0,
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

/// `ispm` images with the GPU and the CPU trace: the same mean within the seeds' noise, with
/// point lights (`cornell`, `cornell-glass`), an area light, the sun and the sky as sources.
/// Four seeds each; bound |mean_gpu − mean_cpu| ≤ 4·√(s²_cpu/4 + s²_gpu/4) + 0.2%, s² the
/// seeds' sample variances (the 0.2% floor: below the direct light's share, where the
/// photon noise that s measures vanishes in the mean).
#[test]
fn ispm_image_mean_is_the_same_with_the_gpu_trace() {
    use gi_core::gpu::photon::PhotonTrace;
    let scenes = [
        ("cornell", builtin::load("cornell").unwrap()),
        ("cornell-glass", builtin::load("cornell-glass").unwrap()),
        ("glass room (area)", openings("glass_room.json")),
        ("outdoor (sun, sky)", outdoor(SUN, SKY)),
        ("window room (sky)", openings("window_room.json")),
    ];
    for (name, mut scene) in scenes {
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
