//! Area lights, suns and skies in the CPU methods (issue 28):
//! - an emitting square over a Lambertian plane: the radiance is ρ·L·F by the form factor,
//!   for next-event estimation alone, BSDF sampling alone and both by MIS;
//! - the three strategies agree in an area-lit room with glossy surfaces and all bounces;
//! - a sun with an angular diameter: a floor facing it gets its irradiance E;
//! - thousands of small emitters of varied power: the light BVH and the power table beat
//!   uniform selection at equal samples;
//! - caustics of an area light through glass: the same with and without light tracing;
//! - `photon` and `gather` against `path` in an area-lit room, a sun-and-sky scene and an
//!   environment-lit scene.

mod common;

use gi_core::sampling::Rng;
use gi_core::scene::emitters::Selection;
use gi_core::trace::direct::{DirectLight, LightQuery};
use gi_core::trace::light_vertex::Connection;
use gi_core::trace::path::{self, PathSettings, Strategy};
use gi_core::trace::SceneBvh;
use gi_core::{render, Image, Scene, Silent};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::collections::HashMap;

fn scene(json: &str) -> Scene {
    Scene::from_json(json, "lights-test", &HashMap::new()).expect("scene")
}

fn mean(img: &Image) -> DVec3 {
    img.pixels.iter().map(|p| p.as_dvec3()).sum::<DVec3>() / img.pixels.len() as f64
}

/// The path tracer's image of `scene` at `spp` with `settings` and `lights` (pixels in
/// parallel, one generator per sample as `frame::path` does).
fn path_image(
    scene: &Scene,
    lights: &DirectLight,
    settings: &PathSettings,
    spp: u32,
    seed: u64,
) -> Image {
    path_image_jittered(scene, lights, settings, (spp, seed), true)
}

/// [`path_image`], the camera rays through random points of the pixels (`jitter`) or their
/// centres.
fn path_image_jittered(
    scene: &Scene,
    lights: &DirectLight,
    settings: &PathSettings,
    (spp, seed): (u32, u64),
    jitter: bool,
) -> Image {
    let bvh = SceneBvh::build(scene);
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let pixels: Vec<Vec3> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let mut sum = Vec3::ZERO;
            for s in 0..spp {
                let mut rng = Rng::new(seed, i as u64, s as u64);
                let j = if jitter {
                    rng.next_2d()
                } else {
                    glam::Vec2::splat(0.5)
                };
                let dir = cam.direction(x as f32 + j.x, y as f32 + j.y);
                let ray = (cam.position, dir);
                sum += path::radiance(scene, &bvh, lights, ray, &mut rng, settings);
            }
            sum / spp as f32
        })
        .collect();
    let mut img = Image::new(w, h);
    img.pixels = pixels;
    img
}

fn settings(max_depth: u32, strategy: Strategy) -> PathSettings {
    PathSettings {
        max_depth,
        rr_depth: 3,
        light_traced: false,
        strategy,
        light_vertex: Connection::Mis,
        first_ray_suns: true,
    }
}

/// Form factor from a point to a parallel rectangle with one corner straight above it at
/// height 1, of sides `a` and `b` (Howell's catalogue, C-11).
fn corner_form_factor(a: f64, b: f64) -> f64 {
    let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
    (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * std::f64::consts::PI)
}

/// A square of side 2 emitting L = 1 downwards from height 1 over a Lambertian floor of
/// albedo 0.5; the camera looks down at the floor under its centre through a 2° field of
/// view (the irradiance varies by under 0.1% across it). The floor's radiance is ρ·L·F with
/// F = 4·F_corner(1, 1) = 0.5541. Bounds 1.5%: the standard error of the image mean is
/// below 0.4% for BSDF sampling alone (each sample hits the square with probability F),
/// far below for the others.
#[test]
fn emitting_square_over_a_plane_gives_the_form_factor() {
    let s = scene(
        r#"{
        "camera": {"position": [0, 0.5, 0.0001], "look_at": [0, 0, 0], "fov": 2,
                   "width": 32, "height": 32},
        "materials": {"floor": {"diffuse": [0.5, 0.5, 0.5]},
                      "lamp": {"diffuse": [0, 0, 0], "emission": [1, 1, 1]}},
        "objects": [
            {"shape": {"type": "quad", "size": [20, 20]}, "material": "floor"},
            {"shape": {"type": "quad", "size": [2, 2]}, "material": "lamp",
             "transform": {"rotate": [180, 0, 0], "translate": [0, 1, 0]}}
        ]
    }"#,
    );
    let expected = 0.5 * 4.0 * corner_form_factor(1.0, 1.0);
    let lights = DirectLight::of(&s);
    for strategy in [Strategy::Mis, Strategy::Light, Strategy::Bsdf] {
        let img = path_image(&s, &lights, &settings(1, strategy), 64, 3);
        let m = mean(&img).x;
        eprintln!("{strategy:?}: {m:.5} vs {expected:.5}");
        assert!(
            (m / expected - 1.0).abs() < 0.015,
            "{strategy:?}: {m} vs {expected}"
        );
    }
    // The renderer's own path (MIS) agrees too.
    let out = render(
        &s,
        &gi_core::options!(Path, spp: 64, max_depth: 1, seed: 5),
        &Silent,
    )
    .unwrap();
    let m = mean(&out.radiance).x;
    assert!(
        (m / expected - 1.0).abs() < 0.015,
        "path: {m} vs {expected}"
    );
}

/// A closed emitter close to a surface facing it (a sphere of radius r = 0.2 and radiance
/// L = 5 whose lowest point is 5 cm over a Lambertian floor of albedo 0.5): next-event
/// estimation of the sphere at the floor point under its centre gives ρ·L·(r/h)², the
/// radiance under a Lambertian sphere at height h = 0.25 (irradiance πL(r/h)²). Here the
/// shadow ray's two offsets, off the floor and off the emitter, nearly cancel: a ray along
/// the direction to the sampled point from the moved origin found the emitter itself for
/// most samples (0.93 instead of 1.6, the emissive room of docs/scenes 2% dark). Bound 2%:
/// the 5120-triangle sphere's irradiance is 0.6% below the smooth one's (by direct sampling
/// without shadow rays), the mean of 400k samples has a standard error of about 0.3%.
#[test]
fn emitter_facing_a_close_surface_is_not_shadowed_by_itself() {
    let s = scene(
        r#"{
        "camera": {"position": [2, 0.3, 0], "look_at": [0, 0, 0], "width": 8, "height": 8},
        "materials": {"floor": {"diffuse": [0.5, 0.5, 0.5]},
                      "lamp": {"diffuse": [0, 0, 0], "emission": [5, 5, 5]}},
        "objects": [
            {"shape": {"type": "quad", "size": [4, 4]}, "material": "floor"},
            {"shape": {"type": "sphere", "radius": 0.2, "subdivisions": 4}, "material": "lamp",
             "transform": {"translate": [0, 0.25, 0]}}
        ]
    }"#,
    );
    let bvh = SceneBvh::build(&s);
    let down = Vec3::new(0.0, -1.0, 0.0);
    let hit = bvh.intersect(Vec3::new(0.0, 0.01, 0.0), down, 1.0).unwrap();
    let it = gi_core::trace::Interaction::new(&s, &hit, down);
    let expected = 0.5 * 5.0 * (0.2f64 / 0.25).powi(2);
    for selection in [Selection::Power, Selection::Bvh] {
        let lights = DirectLight::with_selection(&s, selection);
        let mut rng = Rng::new(1, 2, 3);
        let n = 400_000;
        let sum: f64 = (0..n)
            .map(|_| {
                let q = LightQuery {
                    bvh: &bvh,
                    it: &it,
                    wo: Vec3::Y,
                    mis: false,
                };
                lights.emitter_light(&s, q, &mut rng).x as f64
            })
            .sum();
        let m = sum / n as f64;
        eprintln!("{selection:?}: {m:.4} vs {expected:.4}");
        assert!(
            (m / expected - 1.0).abs() < 0.02,
            "{selection:?}: {m} vs {expected}"
        );
    }
}

/// What the area-lit box's two spheres are made of.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Spheres {
    /// Glass and a mirror.
    Glass,
    /// Two glossy materials.
    Glossy,
    /// Two Lambertian ones.
    Diffuse,
}

/// The Cornell box lit by a 0.5 m square in its ceiling instead of its point light.
fn area_cornell(spheres: Spheres, size: u32) -> Scene {
    let spheres = match spheres {
        Spheres::Glass => {
            r#""a": {"diffuse": [0, 0, 0], "transmission": [1, 1, 1], "ior": 1.5},
               "b": {"diffuse": [0, 0, 0], "specular": [0.95, 0.95, 0.95]}"#
        }
        Spheres::Glossy => {
            r#""a": {"diffuse": [0.2, 0.2, 0.5], "specular": [0.5, 0.5, 0.5], "roughness": 0.3,
                     "fresnel": true},
               "b": {"diffuse": [0.6, 0.6, 0.6], "specular": [0.9, 0.8, 0.5], "roughness": 0.15}"#
        }
        Spheres::Diffuse => {
            r#""a": {"diffuse": [0.2, 0.2, 0.5]}, "b": {"diffuse": [0.6, 0.6, 0.6]}"#
        }
    };
    let spheres_placed = r#"
        {"shape": {"type": "sphere", "radius": 0.4, "subdivisions": 4}, "material": "a",
         "transform": {"translate": [0.4, 0.4, 0.25]}},
        {"shape": {"type": "sphere", "radius": 0.4, "subdivisions": 4}, "material": "b",
         "transform": {"translate": [-0.45, 0.4, -0.4]}}"#;
    scene(&common::area_lit_box(size, "", spheres, spheres_placed))
}

/// Multiple importance sampling is consistent: in the area-lit box with glossy spheres, all
/// bounces (depth 5), next-event estimation alone, BSDF sampling alone and both together
/// (each with the light vertices by MIS) give the same image mean. Bound 2%: the means'
/// standard errors, measured over 4 seeds, are 0.1% with MIS at 256 spp, 0.6% next-event
/// estimation alone at 1024 (its glossy highlights are rare and bright) and 0.5% BSDF
/// sampling alone at 1024 (the lamp is 1.6% of the ceiling); at a quarter of these samples
/// the test had failed by chance (2.6%).
#[test]
fn light_bsdf_and_mis_sampling_agree() {
    let s = area_cornell(Spheres::Glossy, 24);
    let lights = DirectLight::of(&s);
    let mis = mean(&path_image(
        &s,
        &lights,
        &settings(5, Strategy::Mis),
        256,
        1,
    ));
    for (strategy, spp) in [(Strategy::Light, 1024), (Strategy::Bsdf, 1024)] {
        let other = mean(&path_image(&s, &lights, &settings(5, strategy), spp, 2));
        let rel = (other / mis - DVec3::ONE).abs();
        eprintln!("{strategy:?} {other:?} vs MIS {mis:?}: {rel:?}");
        assert!(
            rel.max_element() < 0.02,
            "{strategy:?}: {other:?} vs {mis:?}"
        );
    }
}

/// Light through rough glass (issue 42): an emitting square 1 below a rough glass plane
/// (Mitsuba's roughdielectric, α 0.49), seen from above through the plane, direct light
/// only. Next-event estimation samples the square across the glass (its transmission is a
/// non-delta lobe), so next-event estimation alone, BSDF sampling alone and both by MIS
/// agree. Before, light samples were reflection-only: next-event estimation alone gave 0
/// and MIS lost the weight it gave them (the caustic of the roughdielectric sphere 12–25%
/// dark in `path`). Bound 2%: over 6 seeds the means spread by 0.5% (next-event estimation
/// alone, 0.380–0.386) and 0.2% (the others), their averages agreeing within 0.1%. (At α
/// 0.09 next-event estimation alone is too heavy-tailed for a test: f·cos/pdf peaks near
/// 150 for a mean of 0.43.)
#[test]
fn light_through_rough_glass_is_found_by_every_strategy() {
    let s = scene(
        r#"{
        "camera": {"position": [0, 1, 0.0001], "look_at": [0, 0, 0], "fov": 20,
                   "width": 16, "height": 16},
        "materials": {"glass": {"diffuse": [0, 0, 0], "specular": [1, 1, 1],
                                "transmission": [1, 1, 1], "ior": 1.5, "roughness": 0.7,
                                "rough_glass": true},
                      "lamp": {"diffuse": [0, 0, 0], "emission": [1, 1, 1]}},
        "objects": [
            {"shape": {"type": "quad", "size": [6, 6]}, "material": "glass"},
            {"shape": {"type": "quad", "size": [1, 1]}, "material": "lamp",
             "transform": {"translate": [0, -1, 0]}}
        ]
    }"#,
    );
    let lights = DirectLight::of(&s);
    let means: Vec<f64> = [Strategy::Mis, Strategy::Light, Strategy::Bsdf]
        .into_iter()
        .map(|strategy| mean(&path_image(&s, &lights, &settings(1, strategy), 256, 4)).x)
        .collect();
    eprintln!("MIS, light, BSDF: {means:?}");
    assert!(means[0] > 0.1, "{means:?}");
    for m in &means[1..] {
        assert!((m / means[0] - 1.0).abs() < 0.02, "{means:?}");
    }
}

/// A sun of irradiance E = 2 with a 30° disc over a floor facing it: the floor receives E
/// (the disc's radiance is E/(π sin²α)), so its radiance is ρE/π, in `path` (the disc
/// sampled and hit by BSDF rays, by MIS), `photon` and `gather`. Bounds as the parallel
/// sun's test (tests/furnace.rs): 1% for `path` (noise of the disc samples), 3% for the
/// photon density estimate, 1% for `gather` (next-event estimation).
#[test]
fn sun_with_a_disc_gives_its_irradiance() {
    let s = scene(
        r#"{
        "camera": {"position": [0, 3, 0.001], "look_at": [0, 0, 0], "fov": 30,
                   "width": 32, "height": 32},
        "lights": [{"type": "directional", "direction": [0, -1, 0], "irradiance": [2, 2, 2],
                    "angular_diameter": 30}],
        "materials": {"floor": {"diffuse": [0.5, 0.5, 0.5]}},
        "objects": [{"shape": {"type": "quad", "size": [40, 40]}, "material": "floor"}]
    }"#,
    );
    let expected = 0.5 * 2.0 / std::f64::consts::PI;
    for (options, bound) in [
        (gi_core::options!(Path, spp: 16, max_depth: 1), 0.01),
        (
            gi_core::options!(Photon, spp: 1, photons: 400_000, max_depth: 1),
            0.03,
        ),
        (
            gi_core::options!(Gather, spp: 16, photons: 20_000, max_depth: 2),
            0.01,
        ),
    ] {
        let out = render(&s, &options, &Silent).unwrap();
        let m = mean(&out.radiance).x;
        eprintln!("{:?}: {m:.5} vs {expected:.5}", options.method());
        assert!(
            (m / expected - 1.0).abs() < bound,
            "{:?}: {m} vs {expected}",
            options.method()
        );
    }
}

/// `n` small emitting triangles of power varying over three orders of magnitude, scattered
/// 0.2–2 m above a grey floor, facing down or sideways.
fn many_emitters(n: usize) -> Scene {
    let mut rng = Rng::new(11, 0, 0);
    let mut materials = vec![r#""floor": {"diffuse": [0.5, 0.5, 0.5]}"#.to_string()];
    let mut objects =
        vec![r#"{"shape": {"type": "quad", "size": [8, 8]}, "material": "floor"}"#.to_string()];
    for i in 0..n {
        // Radiance log-uniform in [0.1, 100].
        let l = 0.1 * 1000f32.powf(rng.next_f32());
        materials.push(format!(
            r#""e{i}": {{"diffuse": [0, 0, 0], "emission": [{l}, {l}, {l}]}}"#
        ));
        let (x, y, z) = (
            8.0 * rng.next_f32() - 4.0,
            0.2 + 1.8 * rng.next_f32(),
            8.0 * rng.next_f32() - 4.0,
        );
        let tilt = 180.0 - 90.0 * rng.next_f32();
        let turn = 360.0 * rng.next_f32();
        objects.push(format!(
            r#"{{"shape": {{"type": "quad", "size": [0.04, 0.04]}}, "material": "e{i}",
                "transform": {{"rotate": [{tilt}, {turn}, 0], "translate": [{x}, {y}, {z}]}}}}"#
        ));
    }
    scene(&format!(
        r#"{{"camera": {{"position": [0, 6, 5], "look_at": [0, 0, 0], "fov": 60,
                        "width": 32, "height": 32}},
            "materials": {{{}}}, "objects": [{}]}}"#,
        materials.join(","),
        objects.join(",")
    ))
}

/// Light selection: 2000 small emitting squares (4000 triangles) of power varying 1000-fold
/// over a floor, direct light only, 16 samples a pixel. Against a reference of 1024 samples
/// (BVH), the relative RMSE of the floor's pixels is lower for the power table than for
/// uniform selection, and lower again for the light BVH (which also weighs distance and
/// orientation). Bounds: power ≤ 0.8 × uniform and BVH ≤ 0.6 × uniform; measured ratios are
/// given in the test's output (docs/bench/light-sampling.md has the full measurement).
#[test]
fn many_emitters_converge_faster_than_uniform_selection() {
    let s = many_emitters(2000);
    let opts = settings(1, Strategy::Mis);
    let bvh = DirectLight::with_selection(&s, Selection::Bvh);
    // Camera rays through the pixel centres: the error is the light sampling's alone.
    let reference = path_image_jittered(&s, &bvh, &opts, (1024, 99), false);
    let rmse = |img: &Image| {
        let (mut se, mut n) = (0.0f64, 0);
        for (a, b) in img.pixels.iter().zip(&reference.pixels) {
            // Pixels that see an emitter directly carry its radiance exactly: left out.
            if b.x > 0.0 && *a != *b {
                se += ((a.x - b.x) as f64 / b.x as f64).powi(2);
                n += 1;
            }
        }
        (se / n as f64).sqrt()
    };
    let errors: Vec<f64> = [Selection::Uniform, Selection::Power, Selection::Bvh]
        .into_iter()
        .map(|sel| {
            let lights = DirectLight::with_selection(&s, sel);
            let e = rmse(&path_image_jittered(&s, &lights, &opts, (16, 7), false));
            eprintln!("{sel:?}: relative RMSE {e:.4}");
            e
        })
        .collect();
    let (uniform, power, bvh) = (errors[0], errors[1], errors[2]);
    assert!(power <= 0.8 * uniform, "power {power} vs uniform {uniform}");
    assert!(bvh <= 0.6 * uniform, "BVH {bvh} vs uniform {uniform}");
}

/// Caustics of an area light: in the area-lit box with its glass and mirror spheres, the
/// path tracer with light tracing (which then leaves the emitter hits after a delta
/// scattering to it) and without (which finds them by its own rays) agree: image means
/// within 2%, and the floor's caustic in front of the glass sphere (the floor pixels within
/// x 0.25–0.75, z 0.3–0.7, where the light-traced image holds ~80% of their light) within
/// 10% (measured noise of the path tracer alone at 512 samples: about 3% there).
#[test]
fn area_light_caustics_agree_with_and_without_light_tracing() {
    let s = area_cornell(Spheres::Glass, 32);
    let with = render(&s, &gi_core::options!(Path, spp: 128, seed: 1), &Silent).unwrap();
    let without = render(
        &s,
        &gi_core::options!(Path, spp: 512, seed: 2, light_paths: 0),
        &Silent,
    )
    .unwrap();
    assert!(with.stats.light_paths > 0 && without.stats.light_paths == 0);
    let (a, b) = (mean(&with.radiance), mean(&without.radiance));
    let rel = (a / b - DVec3::ONE).abs();
    eprintln!("with light tracing {a:?}, without {b:?}: {rel:?}");
    assert!(rel.max_element() < 0.02, "{a:?} vs {b:?}");
    let caustic: Vec<usize> = (0..with.radiance.pixels.len())
        .filter(|&i| {
            let (p, n) = (with.position.pixels[i], with.normal.pixels[i]);
            n.y > 0.9 && p.y < 0.01 && (0.25..0.75).contains(&p.x) && (0.3..0.7).contains(&p.z)
        })
        .collect();
    let region = |img: &Image| caustic.iter().map(|&i| img.pixels[i].x as f64).sum::<f64>();
    let (ca, cb) = (region(&with.radiance), region(&without.radiance));
    let traced = region(&with.caustics) / ca;
    eprintln!(
        "caustic ({} px, {:.0}% light-traced): {ca:.3} vs {cb:.3}",
        caustic.len(),
        100.0 * traced
    );
    assert!(caustic.len() >= 4 && traced > 0.5);
    assert!((ca / cb - 1.0).abs() < 0.10, "caustic {ca} vs {cb}");
}

/// The mean of `img` over the pixels `keep`s.
fn masked_mean(img: &Image, keep: &[bool]) -> DVec3 {
    let (sum, n) = img
        .pixels
        .iter()
        .zip(keep)
        .filter(|(_, k)| **k)
        .fold((DVec3::ZERO, 0), |(s, n), (p, _)| (s + p.as_dvec3(), n + 1));
    sum / n as f64
}

/// `photon` and `gather` against `path` on `scene`: image means per channel within 3% (the
/// issue's bound for the methods other than `path`; the reference's own noise is below
/// 0.5%), over the pixels whose 3×3 neighbourhood sees no point that `lamp` says is an
/// emitter (a small lamp seen directly outshines the rest, and the few samples per pixel
/// of the photon methods find its edges with 5% of noise in the mean).
fn photon_methods_match_path(
    scene: &Scene,
    path_spp: u32,
    photons: u64,
    lamp: impl Fn(Vec3) -> bool,
) {
    let path = render(
        scene,
        &gi_core::options!(Path, spp: path_spp, seed: 1),
        &Silent,
    )
    .unwrap();
    let (w, h) = (path.radiance.width as i32, path.radiance.height as i32);
    let keep: Vec<bool> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            !(-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    let (u, v) = ((x + dx).clamp(0, w - 1), (y + dy).clamp(0, h - 1));
                    let j = (v * w + u) as usize;
                    path.depth[j] > 0.0 && lamp(path.position.pixels[j])
                })
            })
        })
        .collect();
    let reference = masked_mean(&path.radiance, &keep);
    for options in [
        gi_core::options!(Photon, spp: 4, photons: photons, seed: 2),
        gi_core::options!(Gather, spp: 16, photons: photons / 2, seed: 3),
    ] {
        let out = render(scene, &options, &Silent).unwrap();
        assert!(out.stats.light_paths > 0);
        let m = masked_mean(&out.radiance, &keep);
        let rel = (m / reference - DVec3::ONE).abs();
        eprintln!(
            "{:?}: {m:?} vs path {reference:?}: {rel:?}",
            options.method()
        );
        assert!(
            rel.max_element() < 0.03,
            "{:?}: {m:?} vs {reference:?}",
            options.method()
        );
    }
}

/// An area-lit room: the box lit by its ceiling square, Lambertian spheres (on glossy ones
/// the k-nearest photons, each evaluated with the query point's normal, misplace the
/// lamp's sharp highlights: `photon` measured 4% high there, a limit of the estimate, not
/// of the light).
#[test]
fn photon_and_gather_match_path_in_an_area_lit_room() {
    let lamp = |p: Vec3| p.y > 1.97 && p.x.abs() < 0.26 && p.z.abs() < 0.26;
    photon_methods_match_path(&area_cornell(Spheres::Diffuse, 24), 256, 800_000, lamp);
}

/// A sun (0.53°) and a constant sky over a floor with a box; the camera sees the sky.
#[test]
fn photon_and_gather_match_path_under_sun_and_sky() {
    let s = scene(
        r#"{
        "camera": {"position": [0, 2, 6], "look_at": [0, 0.5, 0], "fov": 50,
                   "width": 24, "height": 24},
        "lights": [{"type": "directional", "direction": [-0.3, -1, -0.5],
                    "irradiance": [3, 2.8, 2.5], "angular_diameter": 0.53}],
        "environment": {"radiance": [0.2, 0.3, 0.5]},
        "materials": {"floor": {"diffuse": [0.6, 0.6, 0.6]},
                      "box": {"diffuse": [0.7, 0.4, 0.3]}},
        "objects": [
            {"shape": {"type": "quad", "size": [6, 6]}, "material": "floor"},
            {"shape": {"type": "box", "size": [1, 1, 1]}, "material": "box",
             "transform": {"translate": [0, 0.5, 0], "rotate": [0, 30, 0]}}
        ]
    }"#,
    );
    photon_methods_match_path(&s, 256, 800_000, |_| false);
}

/// A sphere on a floor lit by an image environment (a dim sky with a bright patch low in
/// the west), seen in the background.
#[test]
fn photon_and_gather_match_path_under_an_image_environment() {
    let (w, h) = (32u32, 16u32);
    let mut texels = vec![Vec3::new(0.3, 0.35, 0.45); (w * h) as usize];
    for y in 4..7 {
        for x in 6..9 {
            texels[(y * w + x) as usize] = Vec3::new(40.0, 35.0, 30.0);
        }
    }
    let image = gi_core::scene::EnvImage {
        width: w,
        height: h,
        texels,
    };
    let json = r#"{
        "camera": {"position": [0, 1.5, 5], "look_at": [0, 0.5, 0], "fov": 50,
                   "width": 24, "height": 24},
        "environment": {"file": "sky.exr"},
        "materials": {"floor": {"diffuse": [0.5, 0.5, 0.5]},
                      "ball": {"diffuse": [0.3, 0.6, 0.3]}},
        "objects": [
            {"shape": {"type": "quad", "size": [6, 6]}, "material": "floor"},
            {"shape": {"type": "sphere", "radius": 0.6, "subdivisions": 3}, "material": "ball",
             "transform": {"translate": [0, 0.6, 0]}}
        ]
    }"#;
    let images = HashMap::from([("sky.exr".to_string(), image)]);
    let s =
        Scene::from_json_with_images(json, "env-test", &HashMap::new(), &images).expect("scene");
    photon_methods_match_path(&s, 256, 800_000, |_| false);
}

/// Bad input that reaches the light code renders finite images: emitters of zero area
/// (a mesh of degenerate triangles, collinear and with coincident corners, which the
/// scene format lets through from mesh files, and a quad scaled to 10⁻⁶ m, the smallest
/// scale the format takes: nothing or next to nothing to sample, they emit nothing), and
/// lights enclosed by a closed mesh (a point light and an emitting sphere
/// inside a closed box seen from outside: every photon and light path stays inside, the
/// box's outside is black), in every CPU method.
#[test]
fn degenerate_and_enclosed_lights_render_finite_images() {
    let flat = gi_core::scene::MeshData {
        mesh: gi_core::scene::primitives::TriMesh {
            positions: vec![
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(0.5, 1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            normals: Vec::new(),
            indices: vec![[0, 1, 2], [0, 3, 1], [2, 2, 2]],
        },
        materials: Vec::new(),
        face_materials: Vec::new(),
        material_textures: Vec::new(),
        uvs: Vec::new(),
        tangents: Vec::new(),
    };
    let degenerate = Scene::from_json(
        r#"{
        "camera": {"position": [0, 1, 4], "look_at": [0, 0, 0], "width": 12, "height": 12},
        "materials": {"floor": {"diffuse": [0.5, 0.5, 0.5]},
                      "lamp": {"diffuse": [0, 0, 0], "emission": [5, 5, 5], "two_sided": true}},
        "objects": [
            {"shape": {"type": "quad", "size": [4, 4]}, "material": "floor"},
            {"shape": {"type": "mesh", "file": "flat.obj"}, "material": "lamp"},
            {"shape": {"type": "quad", "size": [1, 1]}, "material": "lamp",
             "transform": {"translate": [0, 1, 0], "scale": 1e-6}}
        ]
    }"#,
        "lights-test",
        &HashMap::from([("flat.obj".to_string(), flat)]),
    )
    .expect("scene");
    let enclosed = scene(
        r#"{
        "camera": {"position": [0, 1, 4], "look_at": [0, 0, 0], "width": 12, "height": 12},
        "lights": [{"type": "point", "position": [0.2, 0, 0], "intensity": [3, 3, 3]}],
        "materials": {"box": {"diffuse": [0.8, 0.8, 0.8]},
                      "lamp": {"diffuse": [0, 0, 0], "emission": [5, 5, 5]},
                      "glass": {"diffuse": [0, 0, 0], "transmission": [1, 1, 1]}},
        "objects": [
            {"shape": {"type": "box", "size": [1, 1, 1]}, "material": "box"},
            {"shape": {"type": "sphere", "radius": 0.1, "subdivisions": 1}, "material": "lamp",
             "transform": {"translate": [-0.2, 0, 0]}},
            {"shape": {"type": "sphere", "radius": 0.1, "subdivisions": 1}, "material": "glass",
             "transform": {"translate": [0, 0.2, 0]}}
        ]
    }"#,
    );
    for options in [
        gi_core::options!(Path, spp: 4),
        gi_core::options!(Photon, spp: 1, photons: 20_000),
        gi_core::options!(Gather, spp: 1, photons: 20_000),
    ] {
        for (name, s) in [("degenerate", &degenerate), ("enclosed", &enclosed)] {
            let out = render(s, &options, &Silent).unwrap();
            assert!(
                out.radiance.pixels.iter().all(|p| p.is_finite()),
                "{name}: {:?}",
                options.method()
            );
            if name == "enclosed" {
                let m = mean(&out.radiance);
                assert!(
                    m == DVec3::ZERO,
                    "{:?}: outside of a closed box {m:?}",
                    options.method()
                );
            }
        }
    }
}

/// 163 840 emitting triangles (two finely tessellated spheres of many colours) render in
/// every CPU method: the light BVH is built once per frame (0.2 s here, docs/bench/
/// light-sampling.md) and the image is finite.
#[test]
fn many_emitting_triangles_render() {
    let s = scene(
        r#"{
        "camera": {"position": [0, 1, 4], "look_at": [0, 0.5, 0], "width": 8, "height": 8},
        "materials": {"floor": {"diffuse": [0.5, 0.5, 0.5]},
                      "a": {"diffuse": [0.2, 0.2, 0.2], "emission": [2, 1, 0.5]},
                      "b": {"diffuse": [0.2, 0.2, 0.2], "emission": [0.5, 1, 2]}},
        "objects": [
            {"shape": {"type": "quad", "size": [6, 6]}, "material": "floor"},
            {"shape": {"type": "sphere", "radius": 0.4, "subdivisions": 6}, "material": "a",
             "transform": {"translate": [-0.6, 0.5, 0]}},
            {"shape": {"type": "sphere", "radius": 0.4, "subdivisions": 6}, "material": "b",
             "transform": {"translate": [0.6, 0.5, 0]}}
        ]
    }"#,
    );
    assert!(gi_core::scene::Emitters::of(&s).len() >= 100_000);
    for options in [
        gi_core::options!(Path, spp: 2, max_depth: 3),
        gi_core::options!(Photon, spp: 1, photons: 20_000, max_depth: 3),
        gi_core::options!(Gather, spp: 1, photons: 20_000, max_depth: 3),
    ] {
        let t = std::time::Instant::now();
        let out = render(&s, &options, &Silent).unwrap();
        eprintln!("{:?}: {:.2} s", options.method(), t.elapsed().as_secs_f64());
        assert!(out.radiance.pixels.iter().all(|p| p.is_finite()));
        assert!(mean(&out.radiance).x > 0.0);
    }
}
