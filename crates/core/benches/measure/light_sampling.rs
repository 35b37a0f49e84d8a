//! Where the light BVH pays: next-event estimation of emitting triangles chosen uniformly,
//! by power (alias table) or by the light BVH (power, distance, orientation), on scenes of
//! 1 to thousands of emitters, as a markdown table (docs/bench/light-sampling.md).
//!
//! `cargo run -p gi-core --profile test --example light_sampling [-- --spp N --ref-spp N]`
//!
//! Direct light only (`max_depth` 1, MIS with BSDF sampling), 96×96, camera rays through the
//! pixel centres so that the error is the light sampling's. Per scene and selection: the
//! RMSE over the pixels that do not see an emitter, relative to their mean, against a
//! reference of `--ref-spp` (default 512) samples with the BVH (mean squared errors of two
//! seeds averaged); the render time (the faster of the two); and the efficiency
//! 1/(MSE·time) relative to the power table's (above 1: the BVH pays).

mod common;

use gi_core::sampling::Rng;
use gi_core::scene::emitters::Selection;
use gi_core::trace::direct::DirectLight;
use gi_core::trace::light_vertex::Connection;
use gi_core::trace::path::{self, PathSettings, Strategy};
use gi_core::trace::SceneBvh;
use gi_core::{Image, Scene};
use glam::Vec3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::time::Instant;

/// `n` small squares emitting radiance log-uniform in [0.1, 100], 0.2–2 m over an 8 m
/// floor, facing down or sideways (the test's scene, tests/lights.rs).
fn scattered(n: usize) -> String {
    let mut rng = Rng::new(11, 0, 0);
    let mut materials = vec![r#""floor": {"diffuse": [0.5, 0.5, 0.5]}"#.to_string()];
    let mut objects =
        vec![r#"{"shape": {"type": "quad", "size": [8, 8]}, "material": "floor"}"#.to_string()];
    for i in 0..n {
        let l = 0.1 * 1000f32.powf(rng.next_f32());
        materials.push(format!(
            r#""e{i}": {{"diffuse": [0, 0, 0], "emission": [{l}, {l}, {l}]}}"#
        ));
        let (x, y, z) = (
            8.0 * rng.next_f32() - 4.0,
            0.2 + 1.8 * rng.next_f32(),
            8.0 * rng.next_f32() - 4.0,
        );
        let (tilt, turn) = (180.0 - 90.0 * rng.next_f32(), 360.0 * rng.next_f32());
        objects.push(format!(
            r#"{{"shape": {{"type": "quad", "size": [0.04, 0.04]}}, "material": "e{i}",
                "transform": {{"rotate": [{tilt}, {turn}, 0], "translate": [{x}, {y}, {z}]}}}}"#
        ));
    }
    format!(
        r#"{{"camera": {{"position": [0, 6, 5], "look_at": [0, 0, 0], "fov": 60,
                        "width": 96, "height": 96}},
            "materials": {{{}}}, "objects": [{}]}}"#,
        materials.join(","),
        objects.join(",")
    )
}

/// A closed white room lit by `lamp` (JSON objects of material "lamp").
fn room(lamp: &str) -> String {
    format!(
        r#"{{"camera": {{"position": [0, 1, 3.4], "look_at": [0, 1, 0], "fov": 40,
                        "width": 96, "height": 96}},
            "materials": {{"white": {{"diffuse": [0.73, 0.73, 0.73]}},
                          "lamp": {{"diffuse": [0, 0, 0], "emission": [10, 10, 10]}}}},
            "objects": [
              {{"shape": {{"type": "quad", "size": [2, 2]}}, "material": "white"}},
              {{"shape": {{"type": "quad", "size": [2, 2]}}, "material": "white",
                "transform": {{"rotate": [180, 0, 0], "translate": [0, 2, 0]}}}},
              {{"shape": {{"type": "quad", "size": [2, 2]}}, "material": "white",
                "transform": {{"rotate": [90, 0, 0], "translate": [0, 1, -1]}}}},
              {{"shape": {{"type": "quad", "size": [2, 2]}}, "material": "white",
                "transform": {{"rotate": [0, 0, -90], "translate": [-1, 1, 0]}}}},
              {{"shape": {{"type": "quad", "size": [2, 2]}}, "material": "white",
                "transform": {{"rotate": [0, 0, 90], "translate": [1, 1, 0]}}}},
              {lamp}
            ]}}"#
    )
}

fn scenes() -> Vec<(String, Scene)> {
    let mut out = Vec::new();
    let load = |json: &str| Scene::from_json(json, "bench", &HashMap::new()).expect("scene");
    out.push((
        "room, ceiling square (2 triangles)".into(),
        load(&room(
            r#"{"shape": {"type": "quad", "size": [0.5, 0.5]}, "material": "lamp",
                "transform": {"rotate": [180, 0, 0], "translate": [0, 1.98, 0]}}"#,
        )),
    ));
    out.push((
        "room, sphere lamp (320 triangles)".into(),
        load(&room(
            r#"{"shape": {"type": "sphere", "radius": 0.15, "subdivisions": 2},
                "material": "lamp", "transform": {"translate": [0, 1.6, 0]}}"#,
        )),
    ));
    out.push((
        "room, four lamps in the ceiling's corners (8 triangles)".into(),
        load(&room(
            &[(-0.7, -0.7), (-0.7, 0.7), (0.7, -0.7), (0.7, 0.7)]
                .map(|(x, z)| {
                    format!(
                        r#"{{"shape": {{"type": "quad", "size": [0.2, 0.2]}}, "material": "lamp",
                            "transform": {{"rotate": [180, 0, 0], "translate": [{x}, 1.98, {z}]}}}}"#
                    )
                })
                .join(","),
        )),
    ));
    for n in [1, 4, 16, 32, 64, 128, 512, 2048] {
        out.push((
            format!("{n} scattered squares ({} triangles)", 2 * n),
            load(&scattered(n)),
        ));
    }
    out
}

/// Direct light through the pixel centres at `spp`, and the seconds it took.
fn render(
    scene: &Scene,
    bvh: &SceneBvh,
    lights: &DirectLight,
    spp: u32,
    seed: u64,
) -> (Image, f64) {
    let settings = PathSettings {
        max_depth: 1,
        rr_depth: 3,
        light_traced: false,
        strategy: Strategy::Mis,
        light_vertex: Connection::Mis,
        first_ray_suns: true,
    };
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let t = Instant::now();
    let pixels: Vec<Vec3> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let dir = cam.direction((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            let mut sum = Vec3::ZERO;
            for s in 0..spp {
                let mut rng = Rng::new(seed, i as u64, s as u64);
                sum += path::radiance(scene, bvh, lights, (cam.position, dir), &mut rng, &settings);
            }
            sum / spp as f32
        })
        .collect();
    let seconds = t.elapsed().as_secs_f64();
    let mut img = Image::new(w, h);
    img.pixels = pixels;
    (img, seconds)
}

/// Mean squared error of `img` against `reference` over the pixels lit but not an emitter
/// (an emitter seen through a pixel centre is the same in every render), over their mean
/// squared.
fn rel_mse(img: &Image, reference: &Image) -> f64 {
    let (mut se, mut sum, mut n) = (0.0f64, 0.0f64, 0u64);
    for (a, b) in img.pixels.iter().zip(&reference.pixels) {
        let (a, b) = (a.element_sum() as f64, b.element_sum() as f64);
        if b > 0.0 && a != b {
            se += (a - b).powi(2);
            sum += b;
            n += 1;
        }
    }
    let mean = sum / n.max(1) as f64;
    se / n.max(1) as f64 / (mean * mean).max(1e-30)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::get();
    let spp: u32 = args.value("--spp").unwrap_or("32").parse()?;
    let ref_spp: u32 = args.value("--ref-spp").unwrap_or("512").parse()?;
    println!(
        "| scene | selection | RMSE / mean | seconds | efficiency vs power |\n|---|---|---:|---:|---:|"
    );
    for (name, scene) in scenes() {
        let bvh = SceneBvh::build(&scene);
        let (reference, _) = render(
            &scene,
            &bvh,
            &DirectLight::with_selection(&scene, Selection::Bvh),
            ref_spp,
            99,
        );
        let auto = DirectLight::of(&scene).emitters.selection();
        let mut rows = Vec::new();
        for selection in [Selection::Uniform, Selection::Power, Selection::Bvh] {
            let lights = DirectLight::with_selection(&scene, selection);
            // Warm-up, then two seeds.
            render(&scene, &bvh, &lights, 1, 1);
            let (a, ta) = render(&scene, &bvh, &lights, spp, 7);
            let (b, tb) = render(&scene, &bvh, &lights, spp, 8);
            let mse = 0.5 * (rel_mse(&a, &reference) + rel_mse(&b, &reference));
            rows.push((selection, mse, ta.min(tb)));
        }
        let power = rows[1];
        for (selection, mse, s) in rows {
            let efficiency = (power.1 * power.2) / (mse * s);
            let rmse = mse.sqrt();
            let chosen = if selection == auto { " (auto)" } else { "" };
            println!("| {name} | {selection:?}{chosen} | {rmse:.4} | {s:.3} | {efficiency:.2} |");
        }
    }
    Ok(())
}
