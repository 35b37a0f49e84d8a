//! Frame time of method `ispm`: the one-shot path (`gi_core::render`, a new renderer per
//! frame: every buffer, target, BVH and bind group rebuilt, everything read back) against
//! the frame engine's steady state (one `Renderer`, the light moving a little every frame
//! so that every frame re-traces and re-splats its photons, radiance read back only), in the
//! same run, as a markdown table.
//!
//! `cargo run -p gi-core --profile test --example frame_bench [-- --runs N --quick --scene NAME
//! --size WxH --ispm-only --estimator NAME --photons N ... --spp N --shadow-map-size N
//! --stages --no-one-shot --table-only --method bidir]`
//!
//! Scenes `cornell`, `cornell-glass` and the ~246k-triangle `dense-cornell`, at 640×480 and
//! 1280×720, 20k / 50k / 200k photons (or each `--photons`), 16 direct samples per pixel
//! (`--spp`), subsample 2, defaults otherwise (`--shadow-map-size`). Median of N frames
//! after a warm-up frame. `--quick` runs 640×480 and 20k only; `--size` one size;
//! `--ispm-only` leaves out the direct-light and BVH sections.
//!
//! Stages are wall-clock: lavapipe takes a compute pass's timestamps when it flushes its
//! queued work, not around the pass (measured: the tiled estimator's shading pass "took"
//! 0.02 ms while a 2 s gap opened before it), so GPU timestamps cannot split a frame there.
//! A second renderer renders the same frames serially (`FrameDesc::serial`: the GPU waited
//! on after each stage, each ispm frame followed by the serial one so that both see the same
//! load), and its stages split the frame: the splat (the photons' upload and the estimate
//! at the estimate's resolution), the CPU photon trace (with the first hits where they are
//! traced, `FirstBounce::Traced`, and the boundary compensation), the
//! CPU specular paths, and everything else: the direct light (shadow maps, lighting, edge
//! supersampling), the bounce maps, the upsampling, the composite and the readback, the
//! uploads. The shares are of the serial frame. A second table times the first bounce
//! rasterized (bounce maps) and traced in the CPU BVH, in serial frames of the same run.
//! Also: the direct light alone with every pixel supersampled against edge-adaptive
//! supersampling (method `direct`), and CPU BVH rebuild against a refit of the same tree
//! after moving one object.
//!
//! For real GPUs, whose timestamp queries do place each pass: `--stages` adds a last column,
//! the engine frames' own stages (median per stage name: GPU timestamp sums, and the CPU
//! stages and waits by their names) after the estimator and first bounce that ran;
//! `--no-one-shot` leaves out the one-shot frames (`–` in their columns); `--table-only` the
//! tables after the first. `--method bidir` times method `bidir` instead (its defaults, the
//! direct light's options above, the light moving): engine frame, still frame and its stages
//! per scene and size (`scripts/ci/gpu_check.sh` runs these).
//!
//! `--photon-trace cpu|gpu|auto ...`: `photon_trace` (each given value a row of the first
//! table, its scene cell naming the trace; the "CPU photon trace" column then holds the
//! GPU trace's stages, "gpu trace" and its upload, where it ran on the GPU).
//!
//! `--photon-records gpu|readback ...`: each value a row (after `--photon-trace`'s): the
//! GPU-traced photons kept on the GPU for the binned estimator (`gpu`) or read back into the
//! CPU ring and uploaded again (`readback`, `gpu::photon::resident::force_readback`), under
//! the options that let them stay there (`subsample` 1, no boundary compensation, no caustic
//! density bound, no photon focus); the stage cell names the path (`photon_records`).
//!
//! `--readback`: the readback table instead (`readback_table`): the radiance read back as
//! 32-bit floats (what every frame read before issue 45), half floats, and the 8-bit
//! display image tone-mapped on the GPU alone, a still frame and a frame after the light
//! moved each, with their "readback" stage (`docs/bench/frame.md`).
//!
//! `--instancing`: the GPU instancing table instead (`common/instancing.rs`: instanced
//! against flattened geometry, triangles per pass before and after culling, GPU geometry
//! bytes, `ispm` frame and its stages; `docs/bench/instancing.md` section 7).
//!
//! `--lights` times instead the direct light of each kind of light (method `direct`, default
//! options, 640×480 or `--size`) in the same run: a point light against an area light
//! (`area_samples` points), the sun (parallel-ish and with a 5° disc) and the sky
//! (`sky_samples` directions), on an open yard and on `cornell` with its point light or an
//! emitting ceiling quad: a frame after the camera moved (G-buffer, edges, direct light;
//! the shadow maps kept), and a progressive pass (new light samples: their shadow maps and
//! the direct light), with the GPU-timestamp stages of each (`--stages`: a last column with
//! every stage of the camera-moved frame).
mod common;

use common::{median, nudge};
use gi_core::estimate::Estimator;
use gi_core::frame::options::{FirstBounce, PhotonTrace};
use gi_core::frame::{FrameDesc, Renderer};
use gi_core::scene::{bench::dense_cornell, builtin, SceneUpdate};
use gi_core::Silent;
use gi_core::{render, RenderOutput, Scene};
use std::time::Instant;

fn stage(out: &RenderOutput, names: &[&str]) -> f64 {
    out.stats
        .stages
        .iter()
        .filter(|(n, _)| names.contains(&n.as_str()))
        .map(|(_, s)| s)
        .sum()
}

/// Median wall-clock seconds of `runs` frames of `settings` on one renderer, the light
/// moving before each (after a warm-up frame), and the frames.
fn moving_light(
    scene: &Scene,
    settings: &gi_core::RenderOptions,
    runs: usize,
) -> Result<(f64, Vec<RenderOutput>), Box<dyn std::error::Error>> {
    let mut r = Renderer::new(scene, settings)?;
    r.render(&FrameDesc::default(), &Silent)?;
    let mut frames = Vec::new();
    let mut wall = Vec::new();
    for i in 0..runs {
        r.update(&nudge(scene, 0.01 * (i + 1) as f32))?;
        let t = Instant::now();
        frames.push(r.render(&FrameDesc::default(), &Silent)?);
        wall.push(t.elapsed().as_secs_f64());
    }
    Ok((median(wall), frames))
}

/// The frames of [`moving_light_serial`]: the two medians, taken under the same load, and the
/// serial and the engine's own frames.
type SerialRun = (f64, f64, Vec<RenderOutput>, Vec<RenderOutput>);

/// As [`moving_light`], with the same frame rendered serially after each frame (a second
/// renderer, [`FrameDesc::serial`]).
fn moving_light_serial(
    scene: &Scene,
    settings: &gi_core::RenderOptions,
    runs: usize,
) -> Result<SerialRun, Box<dyn std::error::Error>> {
    let serial = FrameDesc {
        serial: true,
        ..Default::default()
    };
    let mut r = Renderer::new(scene, settings)?;
    let mut o = Renderer::new(scene, settings)?;
    r.render(&FrameDesc::default(), &Silent)?;
    o.render(&serial, &Silent)?;
    let (mut frames, mut engine) = (Vec::new(), Vec::new());
    let (mut wall, mut serial_wall) = (Vec::new(), Vec::new());
    for i in 0..runs {
        let u = nudge(scene, 0.01 * (i + 1) as f32);
        r.update(&u)?;
        o.update(&u)?;
        let t = Instant::now();
        engine.push(r.render(&FrameDesc::default(), &Silent)?);
        wall.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        frames.push(o.render(&serial, &Silent)?);
        serial_wall.push(t.elapsed().as_secs_f64());
    }
    Ok((median(wall), median(serial_wall), frames, engine))
}

/// The stages of `frames`, median per stage name in the order first seen, as
/// "name 1.23, name 4.56" (milliseconds).
fn stage_list(frames: &[RenderOutput]) -> String {
    let mut names: Vec<&str> = Vec::new();
    for (n, _) in frames.iter().flat_map(|o| &o.stats.stages) {
        if !names.contains(&n.as_str()) {
            names.push(n);
        }
    }
    names
        .iter()
        .map(|n| {
            let ms = median(frames.iter().map(|o| stage(o, &[n])).collect()) * 1e3;
            format!("{n} {ms:.2}")
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Method `bidir` per scene and size (`--method bidir`): the engine frame with the light
/// moving, a still frame, and the engine frames' stages.
fn bidir_table(
    scenes: &[(&str, Scene)],
    sizes: &[(u32, u32)],
    runs: usize,
    d: DirectOptions,
) -> Result<(), Box<dyn std::error::Error>> {
    println!(
        "| scene | size | engine frame (ms) | still frame (ms) | stages of the engine frame (ms) |"
    );
    println!("|---|---|---|---|---|");
    for (name, scene) in scenes {
        for &(w, h) in sizes {
            let settings = gi_core::options!(Bidir, width: w, height: h, spp: d.spp,
                shadow_map_size: d.shadow_map_size);
            let (frame, frames) = moving_light(scene, &settings, runs)?;
            let mut r = Renderer::new(scene, &settings)?;
            r.render(&FrameDesc::default(), &Silent)?;
            let t = Instant::now();
            r.render(&FrameDesc::default(), &Silent)?;
            let still = t.elapsed().as_secs_f64();
            println!(
                "| {name} | {w}×{h} | {:.1} | {:.1} | {} |",
                frame * 1e3,
                still * 1e3,
                stage_list(&frames)
            );
        }
    }
    Ok(())
}

/// `--readback`: method `ispm` (`--photons`, 20k; `--scene`, cornell; `--size`, 640×480)
/// with each readout of the radiance in the same run, interleaved frame by frame on
/// renderers of their own: a still frame (nothing changed: the composite, the encoding and
/// the readback) and a frame after the light moved, wall-clock medians and their
/// "readback" stage (the wait for the GPU and the copy out of the mapped buffers); and the
/// first still frame with each readout after a float32 frame, which compiles the
/// encoding's pipeline (the cold compile with `MESA_SHADER_CACHE_DISABLE=true`).
fn readback_table(
    scenes: &[(&str, Scene)],
    (w, h): (u32, u32),
    photons: u64,
    runs: usize,
    d: DirectOptions,
) -> Result<(), Box<dyn std::error::Error>> {
    use gi_core::frame::readout::{Display, Precision, Readout, Tonemap};
    let display = Some(Display {
        tonemap: Tonemap::Clip,
        exposure: 0.0,
    });
    let readouts = [
        ("float32 (before)", 16, Readout::default()),
        (
            "float16",
            8,
            Readout {
                radiance: Some(Precision::Float16),
                display: None,
            },
        ),
        (
            "8-bit display (clip) only",
            4,
            Readout {
                radiance: None,
                display,
            },
        ),
    ];
    println!(
        "| scene | size | photons | radiance read back | bytes/pixel | first still frame \
         with it (ms) | still frame (ms) | still: readback (ms) | light moved: frame (ms) | \
         light moved: readback (ms) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let settings = ispm_settings(w, h, photons, Estimator::Auto, d);
    for (name, scene) in scenes {
        let mut renderers = readouts
            .iter()
            .map(|_| Renderer::new(scene, &settings))
            .collect::<Result<Vec<_>, _>>()?;
        // [readout] -> (still wall, still readback, moved wall, moved readback) samples.
        let mut samples = vec![[Vec::new(), Vec::new(), Vec::new(), Vec::new()]; readouts.len()];
        // A frame reading back float32, then a still frame with the renderer's readout:
        // its first, which compiles the encoding's pipeline (cold with
        // MESA_SHADER_CACHE_DISABLE=true).
        let mut first = Vec::new();
        for (r, (_, _, readout)) in renderers.iter_mut().zip(&readouts) {
            r.render(&FrameDesc::default(), &Silent)?;
            let desc = FrameDesc {
                readout: *readout,
                ..Default::default()
            };
            let t = Instant::now();
            r.render(&desc, &Silent)?;
            first.push(t.elapsed().as_secs_f64() * 1e3);
        }
        for i in 0..runs {
            let u = nudge(scene, 0.01 * (i + 1) as f32);
            for (k, (r, (_, _, readout))) in renderers.iter_mut().zip(&readouts).enumerate() {
                let desc = FrameDesc {
                    readout: *readout,
                    ..Default::default()
                };
                r.update(&u)?;
                // The frame after the light moved (slots 2, 3), then a still frame (0, 1).
                for slot in [2, 0] {
                    let t = Instant::now();
                    let out = r.render(&desc, &Silent)?;
                    samples[k][slot].push(t.elapsed().as_secs_f64());
                    samples[k][slot + 1].push(stage(&out, &["readback"]));
                }
            }
        }
        for (((label, bytes, _), s), first) in readouts.iter().zip(samples).zip(first) {
            let [a, b, c, e] = s.map(|v| median(v) * 1e3);
            println!(
                "| {name} | {w}×{h} | {photons} | {label} | {bytes} | {first:.1} | {a:.1} | {b:.2} | {c:.0} | {e:.2} |"
            );
        }
    }
    Ok(())
}

/// The direct light's settings of the `ispm` tables: sub-pixel samples (`--spp`, 16) and
/// shadow-map size (`--shadow-map-size`, the default).
#[derive(Clone, Copy)]
struct DirectOptions {
    spp: u32,
    shadow_map_size: u32,
}

impl DirectOptions {
    fn get(args: &common::Args) -> Result<Self, Box<dyn std::error::Error>> {
        Ok(DirectOptions {
            spp: args.value("--spp").map_or(Ok(16), str::parse)?,
            shadow_map_size: args.value("--shadow-map-size").map_or(
                Ok(gi_core::frame::options::DirectOptions::default()
                    .direct
                    .shadow_map_size),
                str::parse,
            )?,
        })
    }
}

/// The table's `ispm` settings: the direct light's `d`, defaults otherwise.
fn ispm_settings(
    w: u32,
    h: u32,
    photons: u64,
    estimator: Estimator,
    d: DirectOptions,
) -> gi_core::RenderOptions {
    gi_core::options!(Ispm, width: w, height: h, spp: d.spp, shadow_map_size: d.shadow_map_size, photons: photons, estimator: estimator)
}

/// `s` under the options that let GPU-traced photons stay on the GPU (`--photon-records`).
fn resident_settings(s: gi_core::RenderOptions) -> gi_core::RenderOptions {
    s.with("subsample", 1)
        .with("boundary_compensation", false)
        .with("caustic_density_bound", false)
        .with("photon_focus", 0.0)
}

fn direct_settings(w: u32, h: u32, edges: bool) -> gi_core::RenderOptions {
    gi_core::options!(Direct, width: w, height: h, spp: 16, edge_supersampling: edges)
}

/// The yard of `--lights`: a floor with boxes and spheres (5.2k triangles).
const YARD: &str = r#"{
  "camera": { "position": [0, 2.5, 7], "look_at": [0, 0.5, 0], "fov": 45 },
  "materials": {
    "ground": { "diffuse": [0.6, 0.6, 0.55] },
    "box": { "diffuse": [0.7, 0.4, 0.3] },
    "ball": { "diffuse": [0.3, 0.5, 0.7], "specular": [0.04, 0.04, 0.04], "roughness": 0.3, "fresnel": true },
    "lamp": { "diffuse": [0, 0, 0], "emission": [20, 20, 20] }
  },
  "objects": [
    { "shape": { "type": "quad", "size": [10, 10] }, "material": "ground" },
    { "shape": { "type": "box", "size": [1, 1, 1] }, "transform": { "rotate": [0, 20, 0], "translate": [-1.5, 0.5, 0] }, "material": "box" },
    { "shape": { "type": "box", "size": [0.6, 2, 0.6] }, "transform": { "translate": [1.8, 1, -1] }, "material": "box" },
    { "shape": { "type": "sphere", "radius": 0.7, "subdivisions": 4 }, "transform": { "translate": [0.4, 0.7, 0.8] }, "material": "ball" },
    { "shape": { "type": "sphere", "radius": 0.4, "subdivisions": 4 }, "transform": { "translate": [-0.6, 0.4, 2] }, "material": "ball" }
    LAMP
  ]
  LIGHTS
}"#;

/// The yard lit by `lights` (JSON after the objects: lights and environment), with the
/// lamp (an emitting 1 m² quad 4 m up) when `lamp`.
fn yard(lights: &str, lamp: bool) -> Result<Scene, Box<dyn std::error::Error>> {
    let lamp = if lamp {
        r#", { "shape": { "type": "quad", "size": [1, 1] }, "transform": { "rotate": [180, 0, 0], "translate": [1, 4, 1] }, "material": "lamp" }"#
    } else {
        ""
    };
    let json = YARD.replace("LAMP", lamp).replace("LIGHTS", lights);
    Ok(Scene::from_json(&json, "yard", &Default::default())?)
}

/// `cornell` with its point light replaced by an emitting 0.5 m² ceiling quad.
fn cornell_area() -> Result<Scene, Box<dyn std::error::Error>> {
    let mut v: serde_json::Value =
        serde_json::from_str(builtin::json("cornell").ok_or("cornell")?)?;
    v["lights"] = serde_json::json!([]);
    v["materials"]["lamp"] = serde_json::json!({ "diffuse": [0, 0, 0], "emission": [12, 12, 12] });
    v["objects"]
        .as_array_mut()
        .ok_or("objects")?
        .push(serde_json::json!({
            "shape": { "type": "quad", "size": [0.7, 0.7] },
            "transform": { "rotate": [180, 0, 0], "translate": [0, 1.98, 0] },
            "material": "lamp"
        }));
    Ok(Scene::from_json(
        &v.to_string(),
        "cornell-area",
        &Default::default(),
    )?)
}

/// `--lights`: the direct light's cost per kind of light (see the header).
fn lights_table(args: &common::Args, runs: usize) -> Result<(), Box<dyn std::error::Error>> {
    let (w, h) = match args.value("--size") {
        Some(v) => {
            let (w, h) = v.split_once('x').ok_or("--size WxH")?;
            (w.parse()?, h.parse()?)
        }
        None => (640, 480),
    };
    let point =
        r#", "lights": [ { "type": "point", "position": [1, 4, 1], "intensity": [30, 30, 30] } ]"#;
    let sun = |deg: f32| {
        format!(
            r#", "lights": [ {{ "type": "directional", "direction": [-0.4, -1, -0.3], "irradiance": [3, 3, 3], "angular_diameter": {deg} }} ]"#
        )
    };
    let sky = r#", "environment": { "radiance": [0.5, 0.6, 0.8] }"#;
    let all = format!("{}{sky}", sun(0.53));
    type Row = (String, Scene, Vec<(&'static str, u32)>);
    let rows: Vec<Row> = vec![
        ("yard, point light".into(), yard(point, false)?, vec![]),
        (
            "yard, area light".into(),
            yard("", true)?,
            vec![("area_samples", 4)],
        ),
        ("yard, area light".into(), yard("", true)?, vec![]),
        (
            "yard, area light".into(),
            yard("", true)?,
            vec![("area_samples", 64)],
        ),
        ("yard, sun 0.53°".into(), yard(&sun(0.53), false)?, vec![]),
        ("yard, sun 5°".into(), yard(&sun(5.0), false)?, vec![]),
        (
            "yard, sky".into(),
            yard(sky, false)?,
            vec![("sky_samples", 8)],
        ),
        ("yard, sky".into(), yard(sky, false)?, vec![]),
        (
            "yard, sky".into(),
            yard(sky, false)?,
            vec![("sky_samples", 64)],
        ),
        ("yard, sun + sky + area".into(), yard(&all, true)?, vec![]),
        (
            "cornell, point light".into(),
            builtin::load("cornell")?,
            vec![],
        ),
        ("cornell, area light".into(), cornell_area()?, vec![]),
    ];
    // --stages: a last column, the camera-moved frame's every stage (median per name).
    let all_stages = args.flag("--stages");
    println!(
        "| scene | samples | camera moved: frame (ms) | direct light (ms) | progressive pass (ms) | \
         light shadow maps (ms) | sampled-light shadow maps (ms) | direct light (ms) |{}",
        if all_stages { " camera moved: stages (ms) |" } else { "" }
    );
    println!(
        "|---|---|---|---|---|---|---|---|{}",
        if all_stages { "---|" } else { "" }
    );
    for (name, scene, extra) in rows {
        let mut o = gi_core::options!(Direct, width: w, height: h);
        for (k, v) in &extra {
            o = o.with(k, *v);
        }
        let d = gi_core::frame::options::DirectOptions::default().direct;
        let samples = if scene.environment.is_some() && !name.contains("area") {
            format!("{} sky", o_value(&extra, "sky_samples", d.sky_samples))
        } else if name.contains("sun + sky") {
            format!(
                "{} area, {} sky",
                o_value(&extra, "area_samples", d.area_samples),
                o_value(&extra, "sky_samples", d.sky_samples)
            )
        } else if name.contains("area") {
            format!("{} area", o_value(&extra, "area_samples", d.area_samples))
        } else {
            "–".into()
        };
        // Camera moves: the G-buffer, edges and direct light again, shadows kept.
        let mut r = Renderer::new(&scene, &o)?;
        r.render(&FrameDesc::default(), &Silent)?;
        let (mut moved, mut moved_direct, mut moved_outs) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..runs {
            let mut camera = r.scene().camera_desc();
            camera.position[0] += 0.001 * (i + 1) as f32;
            r.update(&SceneUpdate::Camera(camera))?;
            let t = Instant::now();
            let out = r.render(&FrameDesc::default(), &Silent)?;
            moved.push(t.elapsed().as_secs_f64());
            moved_direct.push(stage(&out, &["direct light", "edge shading"]));
            moved_outs.push(out);
        }
        // Progressive passes: new samples each, their shadow maps rendered again.
        let mut p = Renderer::new(&scene, &o.clone().progressive())?;
        p.render(&FrameDesc::default(), &Silent)?;
        let (mut pass, mut shadows, mut sampled, mut direct) = (vec![], vec![], vec![], vec![]);
        for _ in 0..runs {
            let t = Instant::now();
            let out = p.render(&FrameDesc::default(), &Silent)?;
            pass.push(t.elapsed().as_secs_f64());
            shadows.push(stage(&out, &["shadow maps"]));
            sampled.push(stage(&out, &["sampled light shadow maps"]));
            direct.push(stage(&out, &["direct light", "edge shading"]));
        }
        let ms = |v: Vec<f64>| format!("{:.0}", median(v) * 1e3);
        let split = if all_stages {
            format!(" {} |", stage_list(&moved_outs))
        } else {
            String::new()
        };
        println!(
            "| {name} | {samples} | {} | {} | {} | {} | {} | {} |{split}",
            ms(moved),
            ms(moved_direct),
            ms(pass),
            ms(shadows),
            ms(sampled),
            ms(direct),
        );
    }
    Ok(())
}

/// An option's value in `extra`, else `default`.
fn o_value(extra: &[(&str, u32)], name: &str, default: u32) -> u32 {
    extra
        .iter()
        .find(|(n, _)| *n == name)
        .map_or(default, |(_, v)| *v)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::get();
    let runs = args.runs(3)?;
    if std::env::args().any(|a| a == "--lights") {
        common::print_adapter()?;
        return lights_table(&args, runs);
    }
    if std::env::args().any(|a| a == "--instancing") {
        common::print_adapter()?;
        return common::instancing::table(&args, runs);
    }
    let quick = args.quick();
    let flag = |f: &str| std::env::args().any(|a| a == f);
    let (ispm_only, table_only) = (flag("--ispm-only"), flag("--table-only"));
    let (stages, one_shot) = (flag("--stages"), !flag("--no-one-shot"));
    let method = args.value("--method").unwrap_or("ispm");
    if !matches!(method, "ispm" | "bidir") {
        return Err(format!("--method {method}: ispm or bidir").into());
    }
    let estimator: Estimator = args.value("--estimator").unwrap_or("auto").parse()?;
    let traces: Vec<PhotonTrace> = match args.values("--photon-trace") {
        v if v.is_empty() => vec![PhotonTrace::Auto],
        v => v.into_iter().map(str::parse).collect::<Result<_, _>>()?,
    };
    let records: Vec<Option<bool>> = match args.values("--photon-records") {
        v if v.is_empty() => vec![None],
        v => v
            .into_iter()
            .map(|r| match r {
                "gpu" => Ok(Some(false)),
                "readback" => Ok(Some(true)),
                o => Err(format!("--photon-records {o}: gpu or readback")),
            })
            .collect::<Result<_, _>>()?,
    };
    let direct = DirectOptions::get(&args)?;
    common::print_adapter()?;
    let only = args.value("--scene");
    let scenes: Vec<(&str, Scene)> = ["cornell", "cornell-glass", "dense-cornell"]
        .into_iter()
        .filter(|n| only.is_none_or(|o| o == *n))
        .map(|n| {
            let scene = if n == "dense-cornell" {
                Ok(dense_cornell())
            } else {
                builtin::load(n)
            };
            scene.map(|s| (n, s))
        })
        .collect::<Result<_, _>>()?;
    let size = args
        .value("--size")
        .map(|v| -> Result<(u32, u32), Box<dyn std::error::Error>> {
            let (w, h) = v.split_once('x').ok_or("--size WxH")?;
            Ok((w.parse()?, h.parse()?))
        })
        .transpose()?;
    let sizes: Vec<(u32, u32)> = match size {
        Some(s) => vec![s],
        None if quick => vec![(640, 480)],
        None => vec![(640, 480), (1280, 720)],
    };
    let photons: Vec<u64> = args
        .values("--photons")
        .into_iter()
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let budgets: &[u64] = if !photons.is_empty() {
        &photons
    } else if quick {
        &[20_000]
    } else {
        &[20_000, 50_000, 200_000]
    };
    if method == "bidir" {
        return bidir_table(&scenes, &sizes, runs, direct);
    }
    if flag("--readback") {
        let scenes = if only.is_none() {
            &scenes[..1]
        } else {
            &scenes[..]
        };
        return readback_table(scenes, sizes[0], budgets[0], runs, direct);
    }
    let (stage_head, stage_rule) = if stages {
        (
            " estimator/first bounce: stages of the engine frame (ms) |",
            "---|",
        )
    } else {
        ("", "")
    };
    println!(
        "| scene | size | photons | one-shot frame (ms) | engine frame (ms) | speed-up | \
         serial frame (ms) | CPU photon trace (ms) | CPU specular paths (ms) | splat (ms) | \
         direct light (ms) | bounce maps (ms) | upsampling (ms) | rest (ms) | \
         share of all but splat and photon trace | share of all but splat and CPU traces | \
         still frame (ms) |{stage_head}"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|{stage_rule}");
    for (name, scene) in &scenes {
        for &(w, h) in &sizes {
            let rows = budgets.iter().flat_map(|p| {
                let records = &records;
                traces
                    .iter()
                    .flat_map(move |t| records.iter().map(move |r| (p, t, r)))
            });
            for (&photons, &trace, &readback) in rows {
                let mut settings =
                    ispm_settings(w, h, photons, estimator, direct).with("photon_trace", trace);
                // Several traces: each row's scene names its trace (and records path).
                let mut name = match traces.len() {
                    1 => name.to_string(),
                    _ => format!("{name} [{} trace]", trace.name()),
                };
                if let Some(readback) = readback {
                    gi_core::gpu::photon::resident::force_readback(readback);
                    settings = resident_settings(settings);
                    let path = if readback { "readback" } else { "gpu" };
                    name = format!("{name} [records {path}]");
                }
                // One-shot: a new renderer per frame, every image read back.
                let mut old = f64::NAN;
                if one_shot {
                    render(scene, &settings, &Silent)?;
                    let mut wall = Vec::new();
                    for _ in 0..runs {
                        let t = Instant::now();
                        render(scene, &settings, &Silent)?;
                        wall.push(t.elapsed().as_secs_f64());
                    }
                    old = median(wall);
                }
                // Engine: one renderer, the light moving, radiance only; the same frames
                // rendered serially in between split it into stages.
                let (frame, serial, frames, engine) = moving_light_serial(scene, &settings, runs)?;
                let stage_cell = if stages {
                    let s = &engine[0].stats;
                    let list = stage_list(&engine);
                    let t = &s.photon_trace;
                    let records = match s.photon_records.as_str() {
                        "" => String::new(),
                        r => format!(" (records {r})"),
                    };
                    let (e, b) = (&s.estimator, &s.first_bounce);
                    format!(" {e}/{b}/{t} trace{records}: {list} |")
                } else {
                    String::new()
                };
                let m = |names: &[&str]| median(frames.iter().map(|o| stage(o, names)).collect());
                let trace = m(&[
                    "bounce trace",
                    "cpu trace",
                    "gpu trace",
                    "gpu trace upload",
                    "boundary compensation",
                ]);
                let specular = m(&["specular paths"]);
                let splat = m(&["splat (wall)"]);
                let direct = m(&["direct light (wall)"]);
                let bounce = m(&["bounce maps (wall)", "bounce readback"]);
                let upsample = m(&["upsample (wall)"]);
                let rest = serial - trace - specular - splat - direct - bounce - upsample;
                // Still frames: nothing changed since the last one (median of `runs`).
                let mut r = Renderer::new(scene, &settings)?;
                r.render(&FrameDesc::default(), &Silent)?;
                let mut wall = Vec::new();
                for _ in 0..runs {
                    let t = Instant::now();
                    r.render(&FrameDesc::default(), &Silent)?;
                    wall.push(t.elapsed().as_secs_f64());
                }
                let still = median(wall);
                let ms = |x: f64| {
                    if x.is_nan() {
                        "–".to_string()
                    } else {
                        format!("{:.0}", x * 1e3)
                    }
                };
                let speed_up = if one_shot {
                    format!("{:.2}×", old / frame)
                } else {
                    "–".to_string()
                };
                println!(
                    "| {name} | {w}×{h} | {photons} | {} | {} | {speed_up} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1}% | {:.1}% | {:.1} |{stage_cell}",
                    ms(old),
                    ms(frame),
                    ms(serial),
                    ms(trace),
                    ms(specular),
                    ms(splat),
                    ms(direct),
                    ms(bounce),
                    ms(upsample),
                    ms(rest),
                    100.0 * (serial - splat - trace) / serial,
                    100.0 * (serial - splat - trace - specular) / serial,
                    still * 1e3,
                );
            }
        }
    }

    if table_only {
        return Ok(());
    }

    // The first bounce rasterized and traced, in serial frames of the same run (the cost
    // depends on the photons and the scene, not on the image size: the first size only).
    println!(
        "\n| scene | size | photons | raster: bounce maps (ms) | raster: serial frame (ms) | \
         traced: first hits (ms) | traced: serial frame (ms) | first bounce speed-up |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let (w, h) = sizes[0];
    for (name, scene) in &scenes {
        for &photons in budgets {
            let mut row = Vec::new();
            for first_bounce in [FirstBounce::Raster, FirstBounce::Traced] {
                let settings = ispm_settings(w, h, photons, estimator, direct)
                    .with("first_bounce", first_bounce);
                let (_, serial, frames, _) = moving_light_serial(scene, &settings, runs)?;
                let bounce = median(
                    frames
                        .iter()
                        .map(|o| {
                            stage(
                                o,
                                &["bounce maps (wall)", "bounce readback", "bounce trace"],
                            )
                        })
                        .collect(),
                );
                row.push((bounce, serial));
            }
            println!(
                "| {name} | {w}×{h} | {photons} | {:.0} | {:.0} | {:.1} | {:.0} | {:.1}× |",
                row[0].0 * 1e3,
                row[0].1 * 1e3,
                row[1].0 * 1e3,
                row[1].1 * 1e3,
                row[0].0 / row[1].0,
            );
        }
    }
    if ispm_only {
        return Ok(());
    }

    // The direct light alone (method `direct`, the light moving every frame): every pixel
    // supersampled against edge-adaptive supersampling, in the same run.
    println!(
        "\n| scene | size | full supersampling (ms) | edge-adaptive (ms) | speed-up | \
         camera moved, edge-adaptive (ms) | relative RMSE between them |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (name, scene) in &scenes {
        for &(w, h) in &sizes {
            let (full_time, full) = moving_light(scene, &direct_settings(w, h, false), runs)?;
            let adaptive_settings = direct_settings(w, h, true);
            let (adaptive_time, adaptive) = moving_light(scene, &adaptive_settings, runs)?;
            // A camera move re-rasterizes the centre and sub-pixel G-buffers.
            let mut r = Renderer::new(scene, &adaptive_settings)?;
            r.render(&FrameDesc::default(), &Silent)?;
            let mut moved = Vec::new();
            for i in 0..runs {
                let mut camera = r.scene().camera_desc();
                camera.position[0] += 0.001 * (i + 1) as f32;
                r.update(&SceneUpdate::Camera(camera))?;
                let t = Instant::now();
                r.render(&FrameDesc::default(), &Silent)?;
                moved.push(t.elapsed().as_secs_f64());
            }
            let times = [full_time, adaptive_time, median(moved)];
            let images = [
                full.last().expect("a frame").radiance.clone(),
                adaptive.last().expect("a frame").radiance.clone(),
            ];
            let (full, adaptive) = (&images[0], &images[1]);
            let (mut se, mut sr) = (0.0f64, 0.0f64);
            for (a, f) in adaptive.pixels.iter().zip(&full.pixels) {
                se += (*a - *f).length_squared() as f64;
                sr += f.length_squared() as f64;
            }
            println!(
                "| {name} | {w}×{h} | {:.0} | {:.0} | {:.1}× | {:.0} | {:.1e} |",
                times[0] * 1e3,
                times[1] * 1e3,
                times[0] / times[1],
                times[2] * 1e3,
                (se / sr).sqrt(),
            );
        }
    }

    // CPU BVH after an object moves: full rebuild against refitting the same tree.
    println!("\n| scene | triangles | rebuild (ms) | refit + CWBVH conversion (ms) |");
    println!("|---|---|---|---|");
    for (name, scene) in &scenes {
        let (rebuild, refit) = gi_core::trace::bvh::rebuild_vs_refit(scene, runs.max(3));
        println!(
            "| {name} | {} | {:.1} | {:.1} |",
            scene.triangle_count(),
            rebuild * 1e3,
            refit * 1e3
        );
    }
    Ok(())
}
