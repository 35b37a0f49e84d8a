//! The GPU direct light of area lights (emitting surfaces), the sun (a directional light
//! with an angular diameter) and the sky (the environment), for methods `direct`, `ispm` and
//! `bidir` (raster/shaders/common/direct_shade.wgsl), against references:
//!
//! - an area-lit quad over a floor with a black box: against `path` with `max_depth` 2 (the
//!   only light paths there are camera → floor → emitter, every other surface is black, so
//!   that is the direct light whether `path` finds the emitter by BSDF sampling or by
//!   next-event estimation); the emitter seen by the camera; `bidir`'s direct light the same;
//! - the sun through the straight edge of a plate: the penumbra against the visible fraction
//!   of the sun's disc (a circular segment), and the lit floor against E·ρ/π;
//! - a convex object under a constant sky: a Lambertian sphere of albedo ρ under radiance L
//!   has radiance ρ·L everywhere on it (every point sees a whole hemisphere of sky), and the
//!   sky seen behind it is L; a sphere on a floor under the same sky against `path`;
//! - progressive `direct` on the area light: the error against `path` falls with the passes;
//! - two emitting objects, one taken in closed form and one sampled only: one frame of
//!   `direct` against `path`'s direct light over eight seeds;
//! - still frames of a scene with all three create nothing, upload nothing and redraw
//!   nothing.
//!
//! Tolerances are stated at each check with what they allow for. On failure the images go to
//! `target/test-output/lights-<name>-*.pfm`.

mod common;

use gi_core::frame::{FrameDesc, Images, Renderer};
use gi_core::gpu::alloc::counters;
use gi_core::image::Image;
use gi_core::scene::Scene;
use gi_core::Silent;
use gi_core::{render, Method, RenderOptions, RenderOutput};
use glam::{DVec3, Vec3};
use std::collections::HashMap;

const SIZE: u32 = 48;

const AREA_SCENE: &str = r#"{
  "camera": { "position": [0, 1.0, 3.2], "look_at": [0, 0.45, 0], "fov": 50, "width": 48, "height": 48 },
  "materials": {
    "floor": { "diffuse": [0.7, 0.7, 0.7] },
    "black": { "diffuse": [0, 0, 0] },
    "light": { "diffuse": [0, 0, 0], "emission": [3, 2.5, 2] }
  },
  "objects": [
    { "shape": { "type": "quad", "size": [4, 4] }, "material": "floor" },
    { "shape": { "type": "box", "size": [0.5, 0.5, 0.5] }, "transform": { "rotate": [0, 25, 0], "translate": [0.1, 0.25, 0] },
      "material": "black" },
    { "shape": { "type": "quad", "size": [1.2, 0.8] }, "transform": { "rotate": [150, 0, 0], "translate": [-0.2, 1.4, -0.3] },
      "material": "light" }
  ]
}"#;

/// Sun straight down through the edge x = 0 of a black plate 1 m above the floor, whose
/// angular diameter (10°) makes a penumbra 2·tan 5° = 0.175 m wide on the floor.
const SUN_SCENE: &str = r#"{
  "camera": { "position": [0, 0.55, 2.4], "look_at": [0, 0, 0], "fov": 30, "width": 48, "height": 48 },
  "lights": [ { "type": "directional", "direction": [0, -1, 0], "irradiance": [3, 3, 3], "angular_diameter": 10 } ],
  "materials": {
    "floor": { "diffuse": [0.6, 0.6, 0.6] },
    "black": { "diffuse": [0, 0, 0] }
  },
  "objects": [
    { "shape": { "type": "quad", "size": [4, 4] }, "material": "floor" },
    { "shape": { "type": "quad", "size": [2, 3] }, "transform": { "translate": [-1, 1, 0] }, "material": "black" }
  ]
}"#;

const SKY: [f32; 3] = [1.0, 0.8, 0.6];
const ALBEDO: f32 = 0.6;

fn sky_scene(floor: bool) -> Scene {
    let floor = if floor {
        r#", { "shape": { "type": "quad", "size": [6, 6] }, "transform": { "translate": [0, -0.5, 0] }, "material": "m" }"#
    } else {
        ""
    };
    let json = format!(
        r#"{{
  "camera": {{ "position": [0, 0.8, 3], "look_at": [0, -0.1, 0], "fov": 40, "width": 48, "height": 48 }},
  "materials": {{ "m": {{ "diffuse": [{ALBEDO}, {ALBEDO}, {ALBEDO}] }} }},
  "objects": [ {{ "shape": {{ "type": "sphere", "radius": 0.5, "subdivisions": 4 }}, "material": "m" }}{floor} ],
  "environment": {{ "radiance": [{}, {}, {}] }}
}}"#,
        SKY[0], SKY[1], SKY[2]
    );
    scene(&json, "sky")
}

fn scene(json: &str, name: &str) -> Scene {
    Scene::from_json(json, name, &HashMap::new()).expect("scene")
}

fn options(method: Method) -> RenderOptions {
    RenderOptions::defaults(method)
        .with("width", SIZE)
        .with("height", SIZE)
        .with("seed", 7)
}

fn write_images(name: &str, images: &[(&str, &Image)]) {
    let dir = common::output_dir();
    for (suffix, img) in images {
        let _ = common::write_pfm(&dir.join(format!("lights-{name}-{suffix}.pfm")), img);
    }
}

/// Pixels away (by more than a pixel) from the reference's geometric edges: misses, creases
/// and depth steps (`common::edge_mask` without its shadow-edge test, which a noisy
/// reference would trip everywhere; these comparisons average blocks of pixels instead).
fn geometric_keep(reference: &RenderOutput) -> Vec<bool> {
    common::away_from(reference, &common::edges(reference, false), 1)
}

/// Means over `b`×`b` blocks of pixels (kept where `keep`), per block with enough kept
/// pixels: (block mean of `a`, block mean of `reference`).
fn block_means(a: &Image, reference: &Image, keep: &[bool], b: u32) -> Vec<(DVec3, DVec3)> {
    let w = a.width;
    let mut out = Vec::new();
    for by in 0..a.height / b {
        for bx in 0..w / b {
            let (mut sa, mut sr, mut n) = (DVec3::ZERO, DVec3::ZERO, 0);
            for y in by * b..(by + 1) * b {
                for x in bx * b..(bx + 1) * b {
                    let i = (y * w + x) as usize;
                    if keep[i] {
                        sa += a.pixels[i].as_dvec3();
                        sr += reference.pixels[i].as_dvec3();
                        n += 1;
                    }
                }
            }
            if n * 2 >= (b * b) as usize {
                out.push((sa / n as f64, sr / n as f64));
            }
        }
    }
    out
}

/// |Σ a / Σ r − 1| over the kept pixels (sum of channels).
fn mean_bias(a: &Image, reference: &Image, keep: &[bool]) -> f64 {
    let (mut sa, mut sr) = (0.0, 0.0);
    for (i, k) in keep.iter().enumerate() {
        if *k {
            sa += a.pixels[i].as_dvec3().element_sum();
            sr += reference.pixels[i].as_dvec3().element_sum();
        }
    }
    (sa / sr.max(1e-12) - 1.0).abs()
}

/// Σ|a − r| / Σ r over block means (sum of channels).
fn block_error(blocks: &[(DVec3, DVec3)]) -> f64 {
    let (mut e, mut r) = (0.0, 0.0);
    for (a, b) in blocks {
        e += (*a - *b).abs().element_sum();
        r += b.element_sum();
    }
    e / r.max(1e-12)
}

/// The area-light reference: `path` with `max_depth` 2 (see the header), 2048 samples.
fn area_reference(scene: &Scene) -> RenderOutput {
    let o = options(Method::Path).with("spp", 2048).with("max_depth", 2);
    render(scene, &o, &Silent).expect("path")
}

/// `direct` on the area-lit quad against `path`: 4×4-pixel block means off the geometric
/// edges within 4% summed over the image (measured: 16 points per frame, 1.6%; the error is
/// the sampling error of the 16 points shared by every pixel, the near-field discs'
/// darkening, ≈ r²/d² ≈ 0.4% at the floor, and 1-tap shadow lookups at 256² of soft
/// shadows), the image mean within 3%; pixels that see the emitter's face directly equal its
/// radiance (1e-4: the G-buffer carries it in f32); `bidir`'s direct light is the same image.
#[test]
fn area_light_matches_path() {
    let scene = scene(AREA_SCENE, "area");
    let path = area_reference(&scene);
    let direct = render(&scene, &options(Method::Direct), &Silent).expect("direct");
    let keep = geometric_keep(&path);
    let blocks = block_means(&direct.radiance, &path.radiance, &keep, 4);
    let err = block_error(&blocks);
    let bias = mean_bias(&direct.radiance, &path.radiance, &keep);
    eprintln!(
        "area light: block error {err:.4}, mean bias {bias:.4} ({} blocks)",
        blocks.len()
    );
    if err > 0.04 || bias > 0.03 {
        write_images(
            "area",
            &[("path", &path.radiance), ("direct", &direct.radiance)],
        );
    }
    assert!(err < 0.04 && bias < 0.03, "block error {err}, bias {bias}");

    // The emitter seen by the camera: its radiance exactly, where the pixel is all emitter
    // (on its plane, through (−0.2, 1.4, −0.3) with normal (0, −cos 30°, sin 30°)).
    let emission = Vec3::new(3.0, 2.5, 2.0);
    let normal = Vec3::new(0.0, -0.866_025_4, 0.5);
    let mut seen = 0;
    for (i, keep) in keep.iter().enumerate() {
        let p = direct.position.pixels[i];
        if *keep && (p - Vec3::new(-0.2, 1.4, -0.3)).dot(normal).abs() < 1e-3 {
            seen += 1;
            let d = direct.radiance.pixels[i];
            assert!((d - emission).abs().max_element() < 1e-4, "pixel {i}: {d}");
        }
    }
    assert!(
        seen > 10,
        "the camera sees the emitter's face ({seen} pixels)"
    );

    // `bidir`'s direct light is the same pass.
    let bidir = render(
        &scene,
        &options(Method::Bidir).with("max_depth", 1),
        &Silent,
    )
    .expect("bidir");
    let aov = |o: &RenderOutput| {
        o.aovs
            .iter()
            .find(|(n, _)| n == "direct")
            .map(|(_, i)| i.clone())
    };
    let (a, b) = (
        aov(&direct).expect("direct aov"),
        aov(&bidir).expect("bidir aov"),
    );
    let diff = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(x, y)| (*x - *y).abs().max_element())
        .fold(0.0f32, f32::max);
    assert!(diff < 1e-5, "bidir's direct light differs by {diff}");
}

/// Irradiance at `p` (normal `n`) from a uniformly emitting polygon of radiance 1 with
/// `corners`, all above `p`'s horizon: Lambert's formula, ½ Σ θᵢ·(n·ûᵢ) over its edges.
fn polygon_irradiance(p: DVec3, n: DVec3, corners: &[DVec3]) -> f64 {
    let mut sum = 0.0;
    for i in 0..corners.len() {
        let a = (corners[i] - p).normalize();
        let b = (corners[(i + 1) % corners.len()] - p).normalize();
        let theta = a.dot(b).clamp(-1.0, 1.0).acos();
        sum += theta * n.dot(a.cross(b).normalize());
    }
    0.5 * sum.abs()
}

/// The area-lit quad without the box.
fn open_area_scene() -> Scene {
    let json = AREA_SCENE.replace(
        r#"{ "shape": { "type": "box", "size": [0.5, 0.5, 0.5] }, "transform": { "rotate": [0, 25, 0], "translate": [0.1, 0.25, 0] },
      "material": "black" },"#,
        "",
    );
    scene(&json, "area-open")
}

/// The exact radiance of the open scene's floor pixels of `out` away from edges (its
/// position AOV): ρ/π·L·E with E the quad's irradiance by Lambert's polygon formula (0
/// elsewhere), and which pixels those are.
fn open_exact(out: &RenderOutput) -> (Image, Vec<bool>) {
    // The quad's corners (±0.6, 0, ±0.4) turned 150° about x and moved.
    let corner = |x: f64, z: f64| {
        let a = 150f64.to_radians();
        DVec3::new(x - 0.2, -z * a.sin() + 1.4, z * a.cos() - 0.3)
    };
    let corners = [
        corner(-0.6, -0.4),
        corner(0.6, -0.4),
        corner(0.6, 0.4),
        corner(-0.6, 0.4),
    ];
    let emission = DVec3::new(3.0, 2.5, 2.0);
    let keep = geometric_keep(out);
    let mut exact = Image::new(SIZE, SIZE);
    let mut floor = vec![false; keep.len()];
    for (i, p) in out.position.pixels.iter().enumerate() {
        if keep[i] && p.y.abs() < 1e-4 && out.depth[i] > 0.0 {
            let e = polygon_irradiance(p.as_dvec3(), DVec3::Y, &corners);
            exact.pixels[i] = (emission * (0.7 / std::f64::consts::PI * e)).as_vec3();
            floor[i] = true;
        }
    }
    (exact, floor)
}

/// The open scene's floor against the exact irradiance of the quad: `direct` (16 points,
/// the diffuse light in closed form, the points only weighing the visibility) per pixel
/// within 0.5% (float round-off and the G-buffer's f16 albedo), and `path` (2048 samples) in
/// 4×4 blocks within 4% (its noise).
#[test]
fn area_light_matches_polygon_irradiance() {
    let scene = open_area_scene();
    let path = area_reference(&scene);
    let direct = render(&scene, &options(Method::Direct), &Silent).expect("direct");
    let (exact, floor) = open_exact(&direct);
    let mut worst = 0.0f32;
    for (i, f) in floor.iter().enumerate() {
        if *f {
            let rel = ((direct.radiance.pixels[i] - exact.pixels[i]) / exact.pixels[i]).abs();
            worst = worst.max(rel.max_element());
        }
    }
    let p = block_error(&block_means(&path.radiance, &exact, &floor, 4));
    eprintln!("open area light against the polygon formula: direct worst {worst:.4}, path {p:.4}");
    if worst > 0.005 || p > 0.04 {
        write_images(
            "open",
            &[
                ("path", &path.radiance),
                ("direct", &direct.radiance),
                ("exact", &exact),
            ],
        );
    }
    assert!(worst < 0.005 && p < 0.04, "direct {worst}, path {p}");
}

/// Progressive `direct` with 4 points per pass converges: on the open scene against the
/// exact irradiance, the 4×4-block error after 16 passes is under a third of the first
/// pass's and under 2% (each pass sums the points plainly, unbiased: new points, sub-pixel
/// positions and near-field discs shrinking as the photon kernels per pass); with the box,
/// against `path` in 8×8 blocks within 4% after 16 passes (`path`'s own noise there ≈ 1.5%;
/// what stays is the 256² shadow maps' bias).
#[test]
fn progressive_area_light_converges_to_path() {
    let passes = |scene: &Scene, n: u32| -> Vec<RenderOutput> {
        let o = options(Method::Direct)
            .with("area_samples", 4)
            .progressive();
        let mut r = Renderer::new(scene, &o).expect("renderer");
        (1..=n)
            .map(|_| r.render(&FrameDesc::default(), &Silent).expect("pass"))
            .collect()
    };
    let open = open_area_scene();
    let frames = passes(&open, 16);
    let (exact, floor) =
        open_exact(&render(&open, &options(Method::Direct), &Silent).expect("direct"));
    let errors: Vec<f64> = [0, 3, 15]
        .iter()
        .map(|&i| block_error(&block_means(&frames[i].radiance, &exact, &floor, 4)))
        .collect();
    eprintln!("progressive open area light: block error after 1, 4, 16 passes {errors:?}");
    assert!(
        errors[2] < errors[0] / 3.0 && errors[2] < 0.02,
        "errors {errors:?}"
    );

    let scene = scene(AREA_SCENE, "area");
    let path = area_reference(&scene);
    let keep = geometric_keep(&path);
    let last = passes(&scene, 16).pop().expect("a pass");
    let err = block_error(&block_means(&last.radiance, &path.radiance, &keep, 8));
    eprintln!("progressive area light against path after 16 passes: {err:.4}");
    assert!(err < 0.04, "{err}");
}

/// A room corner lit by two emitting objects and no other light: an emitting box (12
/// triangles) near the wall and an emitting geodesic sphere of 320 triangles (more than the
/// direct pass sums in closed form), a black box between them.
const GROUPS_SCENE: &str = r#"{
  "camera": { "position": [0.3, 1.1, 2.6], "look_at": [0, 0.45, -0.4], "fov": 55, "width": 48, "height": 48 },
  "materials": {
    "grey": { "diffuse": [0.7, 0.7, 0.7] },
    "black": { "diffuse": [0, 0, 0] },
    "lantern": { "diffuse": [0, 0, 0], "emission": [6, 3, 1] },
    "globe": { "diffuse": [0, 0, 0], "emission": [1.5, 2.5, 6] }
  },
  "objects": [
    { "shape": { "type": "quad", "size": [4, 4] }, "material": "grey" },
    { "shape": { "type": "quad", "size": [4, 2.5] }, "transform": { "rotate": [90, 0, 0], "translate": [0, 1.25, -1.2] },
      "material": "grey" },
    { "shape": { "type": "box", "size": [0.3, 0.3, 0.3] }, "transform": { "rotate": [0, 30, 0], "translate": [0.6, 0.7, -0.8] },
      "material": "lantern" },
    { "shape": { "type": "sphere", "radius": 0.15, "subdivisions": 2 }, "transform": { "translate": [-0.7, 0.15, -0.3] },
      "material": "globe" },
    { "shape": { "type": "box", "size": [0.3, 0.3, 0.3] }, "transform": { "translate": [0.05, 0.15, -0.3] },
      "material": "black" }
  ]
}"#;

/// One frame of `direct` with emitting objects of which only some fit the closed-form
/// polygons (`Emitters::polygon_groups`): the box's diffuse light by the ratio estimator
/// against its own points, the sphere's points summed as they are, the points stratified
/// over the two. Against `path` with `max_depth` 1 (the direct light), 2048 samples, over
/// the frames of seeds 1–8 (each draws its own 16 points): the 4×4-block error off the
/// geometric edges, mean over the frames, within 0.15, and the mean frame's image mean
/// within 4%. Measured: block errors 0.05–0.16 (mean 0.095), the mean frame's image mean
/// 1.8% off; with every emitter's light summed from points drawn by power alone, as before
/// the groups, block errors 0.26–0.44 (mean 0.33; the sphere got no point at seed 7).
#[test]
fn emitting_objects_in_groups_match_path() {
    let scene = scene(GROUPS_SCENE, "groups");
    let o = options(Method::Path).with("spp", 2048).with("max_depth", 1);
    let path = render(&scene, &o, &Silent).expect("path");
    let keep = geometric_keep(&path);
    let seeds = 1..=8u64;
    let mut errors = Vec::new();
    let mut mean = Image::new(SIZE, SIZE);
    for seed in seeds.clone() {
        let o = options(Method::Direct).with("seed", seed);
        let direct = render(&scene, &o, &Silent).expect("direct");
        errors.push(block_error(&block_means(
            &direct.radiance,
            &path.radiance,
            &keep,
            4,
        )));
        for (m, d) in mean.pixels.iter_mut().zip(&direct.radiance.pixels) {
            *m += *d / seeds.clone().count() as f32;
        }
    }
    let err = errors.iter().sum::<f64>() / errors.len() as f64;
    let bias = mean_bias(&mean, &path.radiance, &keep);
    eprintln!("emitting objects in groups: block errors {errors:.3?} (mean {err:.4}), mean bias {bias:.4}");
    if err > 0.15 || bias > 0.04 {
        write_images("groups", &[("path", &path.radiance), ("direct", &mean)]);
    }
    assert!(err < 0.15 && bias < 0.04, "block error {err}, bias {bias}");
}

/// Merging the closed-form emitters' coplanar triangle pairs into convex quads
/// (`scene::emitters::quads`: four edge terms instead of six, the shared edge's two
/// cancelling) changes one frame of `direct` by float rounding alone: on the room of
/// emitting objects (the box's six faces as quads), on the same room with the box sunk
/// halfway into the floor (whose points see its side faces cut by their horizon: the clipped
/// quads) and on the open area-lit quad, per pixel
/// within 1e-4 of the image's brightest pixel (the edge terms are sums of f32 arc terms of
/// relative error ~1e-6: 2e-6 for the rational θ/sin θ, a few ulps for the normalizations).
#[test]
fn emitter_quads_change_the_light_by_rounding_alone() {
    use gi_core::scene::emitters::{quads, Emitters};
    for (name, scene) in [
        ("groups", scene(GROUPS_SCENE, "groups")),
        (
            "sunk",
            scene(
                &GROUPS_SCENE.replace("[0.6, 0.7, -0.8]", "[0.6, 0.0, -0.8]"),
                "sunk",
            ),
        ),
        ("open", open_area_scene()),
    ] {
        let groups = Emitters::of(&scene).polygon_groups(&scene, (64, 8), 16);
        assert!(
            groups.polygons.len() < groups.triangles.len(),
            "{name}: nothing merged"
        );
        let o = options(Method::Direct).with("seed", 3u64);
        let merged = render(&scene, &o, &Silent).expect("direct");
        std::env::set_var(quads::QUADS_ENV, "0");
        let triangles = render(&scene, &o, &Silent);
        std::env::remove_var(quads::QUADS_ENV);
        let triangles = triangles.expect("direct");
        let peak = triangles
            .radiance
            .pixels
            .iter()
            .map(|p| p.max_element())
            .fold(0.0f32, f32::max);
        let diff = merged
            .radiance
            .pixels
            .iter()
            .zip(&triangles.radiance.pixels)
            .map(|(a, b)| (*a - *b).abs().max_element())
            .fold(0.0f32, f32::max);
        eprintln!("{name}: quads against triangles, largest difference {diff:e} (peak {peak})");
        assert!(
            peak > 0.0 && diff <= 1e-4 * peak,
            "{name}: {diff} of {peak}"
        );
    }
}

/// A white emitting cube (emitting from its outer sides), alone in the dark and turned so
/// that three faces show: no face of a convex emitter lights another
/// (each lies behind the others' planes) nor itself (every direction to it from its own
/// surface is grazing), so every pixel it covers has its emission, L, exactly, and no pixel
/// more. Per pixel within 1e-4·L (f32 rounding), with the closed-form polygons as quads and
/// as triangles. Before the plane's thickness was taken from the polygon's size, a sample at
/// the silhouette on a back face's inner side (the G-buffer draws both sides) could come out
/// at L + ρ·L: its own face seemed to fill its hemisphere.
#[test]
fn an_emitter_lights_neither_itself_nor_its_other_faces() {
    let json = r#"{
      "camera": { "position": [1.6, 1.3, 2.1], "look_at": [0, 0, 0], "fov": 25, "width": 64, "height": 64 },
      "materials": { "lamp": { "diffuse": [0.75, 0.75, 0.75], "emission": [8, 4, 1.2] } },
      "objects": [ { "shape": { "type": "box", "size": [0.6, 0.6, 0.6] }, "transform": { "rotate": [10, 30, 0] }, "material": "lamp" } ]
    }"#;
    let scene = scene(json, "lone-lamp");
    let emission = Vec3::new(8.0, 4.0, 1.2);
    for quads in ["1", "0"] {
        std::env::set_var(gi_core::scene::emitters::quads::QUADS_ENV, quads);
        let out = render(&scene, &options(Method::Direct), &Silent);
        std::env::remove_var(gi_core::scene::emitters::quads::QUADS_ENV);
        let out = out.expect("direct");
        let keep = geometric_keep(&out);
        let (mut interior, mut over) = (0.0f32, 0.0f32);
        let mut covered = 0;
        for (i, px) in out.radiance.pixels.iter().enumerate() {
            over = over.max((*px - emission).max_element());
            if keep[i] && out.depth[i] > 0.0 {
                interior = interior.max((*px - emission).abs().max_element());
                covered += 1;
            }
        }
        eprintln!("lone lamp (quads {quads}): {covered} interior pixels, off by {interior:e}, over by {over:e}");
        assert!(covered > 300, "{covered}");
        assert!(
            interior <= 1e-4 * 8.0 && over <= 1e-4 * 8.0,
            "quads {quads}: {interior} {over}"
        );
    }
}

/// Fraction of a disc light of unit radius visible past a straight edge at signed distance
/// `s` (in radii) from the disc's centre: the circular segment beyond it.
fn segment(s: f64) -> f64 {
    let s = s.clamp(-1.0, 1.0);
    1.0 - (s.acos() - s * (1.0 - s * s).sqrt()) / std::f64::consts::PI
}

/// The sun's penumbra behind the plate's edge: on the floor (z within the plate, away from
/// the image border) the radiance is ρ/π·E·V with V the visible fraction of the sun's disc
/// past the edge, V = segment(x / tan 5°) (1 m below the edge). Per pixel within 0.1·ρE/π
/// (percentage-closer soft shadows filter with a disc of the penumbra's radius, a smoothed
/// version of the segment; shadow texels 5.6 mm), mean absolute error within 0.03·ρE/π, and
/// the penumbra is there: pixels between 10% and 90% lit.
#[test]
fn sun_penumbra_follows_the_disc() {
    let scene = scene(SUN_SCENE, "sun");
    let out = render(&scene, &options(Method::Direct), &Silent).expect("direct");
    let lit = 0.6 * 3.0 / std::f64::consts::PI;
    let tan_a = 5f64.to_radians().tan();
    let (mut worst, mut sum, mut n, mut partial) = (0.0f64, 0.0, 0, 0);
    let mut expected = Image::new(SIZE, SIZE);
    for (i, p) in out.position.pixels.iter().enumerate() {
        if out.depth[i] <= 0.0 || p.y.abs() > 1e-3 || p.z.abs() > 1.3 || p.x.abs() > 0.8 {
            continue;
        }
        let v = segment(p.x as f64 / tan_a);
        expected.pixels[i] = Vec3::splat((lit * v) as f32);
        let got = out.radiance.pixels[i].x as f64 / lit;
        let e = (got - v).abs();
        worst = worst.max(e);
        sum += e;
        n += 1;
        if got > 0.1 && got < 0.9 {
            partial += 1;
        }
    }
    let mean = sum / n as f64;
    eprintln!(
        "sun penumbra: {n} floor pixels, worst {worst:.3}, mean {mean:.4}, {partial} partly lit"
    );
    if worst > 0.1 || mean > 0.03 {
        write_images("sun", &[("direct", &out.radiance), ("expected", &expected)]);
    }
    assert!(
        n > 500 && partial >= 20,
        "{n} pixels, {partial} in the penumbra"
    );
    assert!(worst < 0.1 && mean < 0.03, "worst {worst}, mean {mean}");
}

/// `n` progressive passes with `o`, each pass's output (every image; the radiance the
/// mean so far, the AOVs the pass's own).
fn progressive_passes(scene: &Scene, o: RenderOptions, n: u32) -> Vec<RenderOutput> {
    let mut r = Renderer::new(scene, &o.progressive()).expect("renderer");
    let desc = FrameDesc {
        images: Images::ALL,
        ..FrameDesc::default()
    };
    (0..n)
        .map(|_| r.render(&desc, &Silent).expect("pass"))
        .collect()
}

/// The mean of the `name` AOV over `frames` (per-pass images, not accumulated).
fn mean_aov(frames: &[RenderOutput], name: &str) -> Image {
    let first = &frames[0].radiance;
    let mut sum = vec![DVec3::ZERO; first.pixels.len()];
    for f in frames {
        let (_, img) = f.aovs.iter().find(|(n, _)| n == name).expect("aov");
        for (s, p) in sum.iter_mut().zip(&img.pixels) {
            *s += p.as_dvec3();
        }
    }
    let mut out = Image::new(first.width, first.height);
    for (o, s) in out.pixels.iter_mut().zip(&sum) {
        *o = (*s / frames.len() as f64).as_vec3();
    }
    out
}

/// Mean |radiance/(ρE/π) − V| over the sun scene's floor pixels (as in
/// [`sun_penumbra_follows_the_disc`]), V the visible fraction of the sun's disc.
fn sun_error(out: &RenderOutput, radiance: &Image) -> (f64, usize) {
    let lit = 0.6 * 3.0 / std::f64::consts::PI;
    let tan_a = 5f64.to_radians().tan();
    let (mut sum, mut n) = (0.0, 0);
    for (i, p) in out.position.pixels.iter().enumerate() {
        if out.depth[i] <= 0.0 || p.y.abs() > 1e-3 || p.z.abs() > 1.3 || p.x.abs() > 0.8 {
            continue;
        }
        let v = segment(p.x as f64 / tan_a);
        sum += (radiance.pixels[i].x as f64 / lit - v).abs();
        n += 1;
    }
    (sum / n.max(1) as f64, n)
}

/// Progressive passes under the 10° sun converge to the penumbra of its disc: each pass
/// casts hard shadows along one direction drawn uniformly from the disc (`direct`: an
/// orthographic shadow map along it; `ispm`: rays traced on the CPU, as `path` would with
/// next-event estimation of the disc), so the mean over passes is the disc's visible
/// fraction. Mean absolute error over the floor (in units of ρE/π) after 32 passes within
/// 0.02 (measured 0.008 (direct) and 0.003 (ispm): the noise of 32 directions in the
/// 0.175 m penumbra, ~10% of the floor pixels, at most √(V(1−V)/32) ≈ 0.09 each, and the
/// shadow maps' texel), and under half the first pass's (measured: `direct` one hard
/// shadow, 0.05; `ispm` its k² rays per pixel each along a direction of its own, 0.014).
/// The floor's plate has no indirect light (black), so `ispm`'s image is the direct light.
#[test]
fn progressive_sun_converges_to_the_disc() {
    let scene = scene(SUN_SCENE, "sun");
    for method in [Method::Direct, Method::Ispm] {
        let o = options(method).with("photons", 2000);
        let frames = progressive_passes(&scene, o, 32);
        let (first, n) = sun_error(&frames[0], &frames[0].radiance);
        let last = frames.last().expect("a pass");
        let (err, _) = sun_error(last, &last.radiance);
        eprintln!(
            "progressive sun, {}: {n} floor pixels, error after 1 pass {first:.4}, after 32 {err:.4}",
            method.name()
        );
        assert!(n > 500, "{n} floor pixels");
        assert!(
            err < 0.02 && err < first / 2.0,
            "{}: {first} -> {err}",
            method.name()
        );
    }
}

/// `path`'s direct light of the sky scene (512 spp) and the pixels off its geometric edges.
fn sky_path_reference(scene: &Scene) -> (RenderOutput, Vec<bool>) {
    let o = options(Method::Path).with("spp", 512).with("max_depth", 1);
    let path = render(scene, &o, &Silent).expect("path");
    let keep = geometric_keep(&path);
    (path, keep)
}

/// Progressive passes under the sky converge to `path`'s direct light (`max_depth` 1, 512
/// samples) on the sphere-on-a-floor scene: `direct` (16 new directions per pass, summed
/// plainly: unbiased but for the shadow maps' texels) and `ispm`'s ray-traced direct light
/// (its `direct` AOV averaged over the passes: one environment sample per camera sample;
/// its indirect light is another matter). 4×4 block means off the geometric edges after 16
/// passes within 3% summed over the image (`path`'s own noise ≈ 1%; measured 1.7% and
/// 1.8%, from 7.1% and 8.2% after one pass), the mean within 1% (measured 0.6%, 0.4%), and below the first pass's block error.
#[test]
fn progressive_sky_converges_to_path() {
    let scene = sky_scene(true);
    let (path, keep) = sky_path_reference(&scene);
    for method in [Method::Direct, Method::Ispm] {
        let o = options(method).with("photons", 2000);
        let frames = progressive_passes(&scene, o, 16);
        let (first, last) = if method == Method::Ispm {
            (
                mean_aov(&frames[..1], "direct"),
                mean_aov(&frames, "direct"),
            )
        } else {
            let last = frames.last().expect("a pass");
            (frames[0].radiance.clone(), last.radiance.clone())
        };
        let e0 = block_error(&block_means(&first, &path.radiance, &keep, 4));
        let err = block_error(&block_means(&last, &path.radiance, &keep, 4));
        let bias = mean_bias(&last, &path.radiance, &keep);
        eprintln!(
            "progressive sky, {}: block error after 1 pass {e0:.4}, after 16 {err:.4}, mean bias {bias:.4}",
            method.name()
        );
        if err > 0.03 || bias > 0.01 {
            write_images(
                &format!("sky-progressive-{}", method.name()),
                &[("path", &path.radiance), ("last", &last)],
            );
        }
        assert!(
            err < 0.03 && bias < 0.01 && err < e0,
            "{}: {e0} -> {err}, bias {bias}",
            method.name()
        );
    }
}

/// A Lambertian sphere under a constant sky: radiance ρ·L on every pixel that sees it
/// (away from its silhouette), the sky L behind it; for `direct` and `ispm` (whose indirect
/// light is nothing here: a convex object alone). Per pixel within 2% (the ratio estimator
/// is exact where all 16 directions' shadow taps see the sky; a tap at grazing angles may
/// find the sphere itself), the sky exact.
#[test]
fn convex_object_under_constant_sky() {
    let scene = sky_scene(false);
    let sky = Vec3::from(SKY);
    for method in [Method::Direct, Method::Ispm] {
        let out = render(&scene, &options(method), &Silent).expect("render");
        let cam = scene.camera.position;
        let (mut worst, mut n, mut background) = (0.0f32, 0, 0);
        let w = SIZE as usize;
        for (i, px) in out.radiance.pixels.iter().enumerate() {
            let p = out.position.pixels[i];
            let nrm = out.normal.pixels[i];
            if out.depth[i] <= 0.0 {
                // No surface: the sky, where no neighbour sees the sphere either (edge pixels
                // are the mean of their sub-pixel samples).
                let (x, y) = (i % w, i / w);
                let clear = (x.saturating_sub(1)..=(x + 1).min(w - 1)).all(|x| {
                    (y.saturating_sub(1)..=(y + 1).min(w - 1)).all(|y| out.depth[y * w + x] <= 0.0)
                });
                if clear {
                    background += 1;
                    assert!(
                        (*px - sky).abs().max_element() < 1e-4,
                        "{}: sky {px}",
                        method.name()
                    );
                }
                continue;
            }
            if nrm.dot((cam - p).normalize()) < 0.3 {
                continue;
            }
            let rel = ((*px - sky * ALBEDO) / (sky * ALBEDO)).abs().max_element();
            worst = worst.max(rel);
            n += 1;
        }
        eprintln!("{}: {n} sphere pixels, worst {worst:.4}", method.name());
        if worst > 0.02 {
            write_images(&format!("sky-{}", method.name()), &[("out", &out.radiance)]);
        }
        assert!(
            n > 200 && background > 200,
            "{n} sphere, {background} sky pixels"
        );
        assert!(worst < 0.02, "{}: worst {worst}", method.name());
    }
}

/// A sphere on a floor under the same sky against `path` (`max_depth` 1: the sky's direct
/// light, 512 samples): 4×4 block means summed over the image within 7% with the default 16
/// directions and within 3.5% with 64, the mean within 3% and 1.5% (the sphere's occlusion of
/// the floor and the floor's of the sphere sampled by that many shadow-mapped directions:
/// shadows of 16 distinct directions, and the ratio estimator's O(1/n) bias where they
/// overlap).
#[test]
fn sky_occlusion_matches_path() {
    let scene = sky_scene(true);
    let (path, keep) = sky_path_reference(&scene);
    for (n, max_err, max_bias) in [(16, 0.07, 0.03), (64, 0.035, 0.015)] {
        let o = options(Method::Direct).with("sky_samples", n);
        let direct = render(&scene, &o, &Silent).expect("direct");
        let err = block_error(&block_means(&direct.radiance, &path.radiance, &keep, 4));
        let bias = mean_bias(&direct.radiance, &path.radiance, &keep);
        eprintln!("sky occlusion, {n} directions: block error {err:.4}, mean bias {bias:.4}");
        if err > max_err || bias > max_bias {
            write_images(
                "sky-floor",
                &[("path", &path.radiance), ("direct", &direct.radiance)],
            );
        }
        assert!(
            err < max_err && bias < max_bias,
            "{n}: block error {err}, bias {bias}"
        );
    }
}

/// With an emitter, the sun and the sky, a still frame of `direct`, `ispm` and `bidir`
/// creates no GPU object, uploads nothing, redraws no direct light and gives the same image:
/// the sampled lights are drawn once from the options' seed.
#[test]
fn still_frames_with_sampled_lights_redo_nothing() {
    let json = AREA_SCENE.replace(
        r#""materials""#,
        r#""lights": [ { "type": "directional", "direction": [0.3, -1, 0.2], "irradiance": [1, 1, 1], "angular_diameter": 2 } ],
  "environment": { "radiance": [0.2, 0.25, 0.3] },
  "materials""#,
    );
    let scene = scene(&json, "all");
    for method in [Method::Direct, Method::Ispm, Method::Bidir] {
        let mut r =
            Renderer::new(&scene, &options(method).with("photons", 5000)).expect("renderer");
        let frame = FrameDesc::default();
        r.render(&frame, &Silent).expect("first");
        let first = r.render(&frame, &Silent).expect("second");
        let c0 = counters();
        let still = r.render(&frame, &Silent).expect("still");
        let c1 = counters();
        let passes: Vec<&str> = still.stats.stages.iter().map(|(n, _)| n.as_str()).collect();
        assert!(
            !passes.contains(&"direct light") && !passes.contains(&"sampled light shadow maps"),
            "{}: {passes:?}",
            method.name()
        );
        assert_eq!(c1.created_since(&c0), 0, "{}", method.name());
        let uploads = c1.uploads_since(&c0);
        if method == Method::Bidir {
            // `bidir` re-draws its VPLs and bundles every frame; the direct light nothing.
            let ours = [
                "sampled lights",
                "sampled light matrices",
                "sampled light views",
            ];
            assert!(
                uploads
                    .iter()
                    .all(|(l, _)| !ours.contains(&l.as_str()) && l != "direct params"),
                "{uploads:?}"
            );
        } else {
            assert_eq!(uploads, vec![], "{}", method.name());
        }
        assert_eq!(
            still.radiance.pixels,
            first.radiance.pixels,
            "{}",
            method.name()
        );
    }
}
