//! The frame engine (`Renderer`): frames after scene updates equal one-shot renders of the
//! same pose, steady-state frames create no GPU objects and upload only what changed,
//! moving lights and objects move their shadows and indirect light, and temporal photon
//! reuse converges on a still scene.

use gi_core::estimate::Estimator;
mod common;

use common::frames::{all, max_difference, mean, settings};
use gi_core::frame::{FrameDesc, Images, Renderer};
use gi_core::gpu::alloc::counters;
use gi_core::scene::desc::{CameraDesc, LightDesc};
use gi_core::scene::{builtin, SceneUpdate};
use gi_core::Silent;
use gi_core::{render, Method, RenderOutput, Scene};
use glam::{Mat4, Vec3};

/// The light moved and dimmed, the camera turned, the last object (the tall box) moved.
fn pose(scene: &Scene, t: f32) -> Vec<SceneUpdate> {
    let cam = scene.camera_desc();
    let light = match scene.light_desc(0).expect("light") {
        LightDesc::Point {
            position,
            intensity,
        } => LightDesc::Point {
            position: [position[0] + 0.3 * t, position[1] - 0.1 * t, position[2]],
            intensity: intensity.map(|i| i * (1.0 - 0.3 * t)),
        },
        other => other,
    };
    let object = scene.objects.len() - 1;
    let transform =
        Mat4::from_translation(Vec3::new(-0.2 * t, 0.0, 0.1 * t)) * scene.objects[object].transform;
    vec![
        SceneUpdate::Camera(CameraDesc {
            position: [cam.position[0] + 0.2 * t, cam.position[1], cam.position[2]],
            ..cam
        }),
        SceneUpdate::Light { index: 0, light },
        SceneUpdate::Transform { object, transform },
    ]
}

fn posed(scene: &Scene, t: f32) -> Scene {
    let mut s = scene.clone();
    for u in pose(scene, t) {
        s.apply(&u).expect("valid update");
    }
    s
}

/// Every method: a renderer that rendered other poses first (so its BVH, GPU buffers,
/// targets and photon ring were all updated, not built) renders pose 1 exactly as a new
/// renderer of pose 1 does. Bitwise: the CPU methods sum in a fixed chunk order; the GPU
/// blends in primitive order per pixel, and the compute estimators sum in fixed point.
#[test]
fn updated_renderer_equals_one_shot() {
    let scene = builtin::load("cornell").expect("scene");
    for &method in Method::ALL {
        let s = settings(method);
        let mut r = Renderer::new(&scene, &s).expect("renderer");
        r.render(&all(), &Silent).expect("frame 0");
        for u in pose(&scene, 0.5) {
            r.update(&u).expect("update");
        }
        r.render(&all(), &Silent).expect("frame 1");
        for u in pose(&scene, 1.0) {
            r.update(&u).expect("update");
        }
        let frame = r.render(&all(), &Silent).expect("frame 2");
        let one_shot = render(&posed(&scene, 1.0), &s, &Silent).expect("one-shot");
        let d = max_difference(&frame.radiance, &one_shot.radiance);
        assert_eq!(d, 0.0, "{}: frames differ by {d}", method.name());
        assert_eq!(
            frame.albedo.pixels,
            one_shot.albedo.pixels,
            "{}",
            method.name()
        );
        assert_eq!(frame.depth, one_shot.depth, "{}", method.name());
    }
}

/// After the first frame at a size, a frame creates no buffers, textures, bind groups or
/// pipelines, and uploads only what changed: nothing for a still frame, the camera's views
/// (and the re-ordered photons) for a camera move, the lights and shadow views for a light
/// change, the moved object's instance record (128 bytes) for a transform.
#[test]
fn steady_state_creates_nothing_and_uploads_what_changed() {
    let scene = builtin::load("cornell").expect("scene");
    // Auto on lavapipe: the first bounce traced and the estimate on the CPU; then the
    // rasterized bounce maps and the tiled estimator.
    let raster = settings(Method::Ispm)
        .with("first_bounce", gi_core::frame::options::FirstBounce::Raster)
        .with("estimator", gi_core::estimate::Estimator::Tiled);
    for s in [settings(Method::Direct), settings(Method::Ispm), raster] {
        let method = s.method();
        let mut r = Renderer::new(&scene, &s).expect("renderer");
        let frame = FrameDesc::default();
        r.render(&frame, &Silent).expect("first frame");
        let labels = |uploads: Vec<(String, u64)>| {
            let mut l: Vec<String> = uploads.into_iter().map(|(l, _)| l).collect();
            l.sort();
            l.dedup();
            l
        };

        let first = r.render(&frame, &Silent).expect("second frame");
        let c0 = counters();
        let still = r.render(&frame, &Silent).expect("still frame");
        let c1 = counters();
        // Nothing moved: the direct light and the photon estimate are not redrawn, and the
        // image is the same.
        let passes: Vec<&str> = still.stats.stages.iter().map(|(n, _)| n.as_str()).collect();
        assert!(
            !passes.contains(&"direct light")
                && !passes.contains(&"photon volumes")
                && !passes.contains(&"tiled shading")
                && !passes.contains(&"cluster shading")
                && !passes.contains(&"directional shading"),
            "{passes:?}"
        );
        assert_eq!(still.radiance.pixels, first.radiance.pixels);
        assert_eq!(c1.created_since(&c0), 0, "{}: still frame", method.name());
        assert_eq!(
            c1.uploads_since(&c0),
            vec![],
            "{}: still frame",
            method.name()
        );

        let cam = scene.camera_desc();
        r.update(&SceneUpdate::Camera(CameraDesc {
            position: [cam.position[0] + 0.1, cam.position[1], cam.position[2]],
            ..cam
        }))
        .expect("camera");
        r.render(&frame, &Silent).expect("camera frame");
        let c2 = counters();
        assert_eq!(c2.created_since(&c1), 0, "{}: camera", method.name());
        // The raster volumes re-sort their photons for the new view (small ones as quads);
        // the tiled estimator keeps them; the CPU estimate is uploaded whole.
        let estimator = first.stats.estimator.as_str();
        let expected: &[&str] = match (method, estimator) {
            (Method::Direct, _) => &["eye views"],
            (_, "tiled") => &["eye views", "tiled params", "upsample params"],
            (_, "cpu") => &["cpu estimate", "eye views", "upsample params"],
            _ => &["eye views", "photons", "upsample params", "volume params"],
        };
        assert_eq!(
            labels(c2.uploads_since(&c1)),
            expected,
            "{}: camera",
            method.name()
        );

        let light = match scene.light_desc(0).expect("light") {
            LightDesc::Point { position, .. } => LightDesc::Point {
                position,
                intensity: [1.0, 2.0, 3.0],
            },
            other => other,
        };
        r.update(&SceneUpdate::Light { index: 0, light })
            .expect("light");
        r.render(&frame, &Silent).expect("light frame");
        let c3 = counters();
        assert_eq!(c3.created_since(&c2), 0, "{}: light", method.name());
        let expected: &[&str] = match (method, estimator) {
            (Method::Direct, _) => &["lights", "shadow matrices", "shadow views"],
            (_, "cpu") => &["cpu estimate", "lights", "shadow matrices", "shadow views"],
            (_, "tiled") => &[
                "lights",
                "shadow matrices",
                "shadow views",
                // The photon count is a parameter.
                "tiled params",
                "tiled photons",
            ],
            _ => &["lights", "photons", "shadow matrices", "shadow views"],
        };
        // Rasterized bounce maps upload their views; traced ones (CPU devices) nothing.
        let mut expected = expected.to_vec();
        if first.stats.first_bounce == "raster" {
            expected.insert(0, "bounce views");
        }
        assert_eq!(
            labels(c3.uploads_since(&c2)),
            expected,
            "{}: light",
            method.name()
        );

        let object = scene.objects.len() - 1;
        let o = &scene.objects[object];
        let transform = Mat4::from_translation(Vec3::new(0.05, 0.0, 0.0)) * o.transform;
        r.update(&SceneUpdate::Transform { object, transform })
            .expect("transform");
        r.render(&frame, &Silent).expect("object frame");
        let c4 = counters();
        assert_eq!(c4.created_since(&c3), 0, "{}: object", method.name());
        // The GPU draws instances: a move rewrites the object's instance record alone (its
        // mesh's vertices stay), where a flat vertex list rewrote all its placed vertices.
        let geometry: Vec<(String, u64)> = c4
            .uploads_since(&c3)
            .into_iter()
            .filter(|(l, _)| l == "instances" || l == "mesh vertices")
            .collect();
        let bytes = std::mem::size_of::<gi_core::gpu::raw::InstanceRaw>() as u64;
        assert_eq!(
            geometry,
            vec![("instances".to_string(), bytes)],
            "{}: only the object's instance record",
            method.name()
        );
    }
}

/// A short animation (light and object moving, camera panning): every frame equals a
/// one-shot render of its pose, and the moving object's shadow and indirect light move
/// with it: the frame differs from the still scene's in the pose's image, beyond noise
/// (the same seed renders the still scene twice identically).
#[test]
fn animation_frames_equal_one_shot_poses() {
    let scene = builtin::load("cornell").expect("scene");
    let s = settings(Method::Ispm);
    let mut r = Renderer::new(&scene, &s).expect("renderer");
    for step in 0..4 {
        let t = step as f32 / 3.0;
        for u in pose(&scene, t) {
            r.update(&u).expect("update");
        }
        let frame = r.render(&all(), &Silent).expect("frame");
        let one_shot = render(&posed(&scene, t), &s, &Silent).expect("one-shot");
        let d = max_difference(&frame.radiance, &one_shot.radiance);
        assert_eq!(d, 0.0, "frame {step}");
    }
    // Only the object moves: direct (shadow) and indirect light both change.
    let object = scene.objects.len() - 1;
    let moved =
        Mat4::from_translation(Vec3::new(-0.25, 0.0, 0.15)) * scene.objects[object].transform;
    let still = render(&scene, &s, &Silent).expect("still");
    let mut r = Renderer::new(&scene, &s).expect("renderer");
    r.render(&all(), &Silent).expect("frame 0");
    r.update(&SceneUpdate::Transform {
        object,
        transform: moved,
    })
    .expect("move");
    let frame = r.render(&all(), &Silent).expect("moved");
    let aov = |o: &RenderOutput, name: &str| {
        o.aovs
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, i)| i.clone())
            .expect("aov")
    };
    for name in ["direct", "indirect"] {
        let d = max_difference(&aov(&frame, name), &aov(&still, name));
        assert!(d > 0.05 * mean(&aov(&still, name)).max(1e-3), "{name}: {d}");
    }
}

/// Temporal reuse on a still scene: with 8 frames kept, the error against a converged ISPM
/// image (64× the photons) falls as frames accumulate: frame 8's RMSE is below 0.7× frame
/// 1's (noise variance falls as 1/frames; the kernels also narrow as the ring fills).
#[test]
fn temporal_reuse_converges_on_a_still_scene() {
    let scene = builtin::load("cornell").expect("scene");
    let s = settings(Method::Ispm)
        .with("temporal_frames", 8)
        .with("photons", 3_000);
    let reference = render(
        &scene,
        &settings(Method::Ispm).with("photons", 3_000 * 64),
        &Silent,
    )
    .expect("reference");
    let mut r = Renderer::new(&scene, &s).expect("renderer");
    let mut errors = Vec::new();
    for _ in 0..8 {
        let f = r.render(&FrameDesc::default(), &Silent).expect("frame");
        errors.push(f.radiance.rmse(&reference.radiance));
    }
    assert!(errors[7] < 0.7 * errors[0], "{errors:?}");
}

/// Moving objects: the renderer tries a BVH refit once, then keeps whichever of refit and
/// rebuild measured faster (the stage's name says which ran).
#[test]
fn bvh_update_is_chosen_by_measurement() {
    let scene = builtin::load("cornell-glass").expect("scene");
    let s = settings(Method::Path);
    let mut r = Renderer::new(&scene, &s).expect("renderer");
    let bvh_stage = |o: &RenderOutput| {
        o.stats
            .stages
            .iter()
            .find(|(n, _)| n.starts_with("bvh "))
            .cloned()
            .expect("a BVH stage")
    };
    let object = scene.objects.len() - 1;
    let start = scene.objects[object].transform;
    let mut frames = Vec::new();
    for i in 0..3 {
        let transform = Mat4::from_translation(Vec3::new(0.02 * i as f32, 0.0, 0.0)) * start;
        r.update(&SceneUpdate::Transform { object, transform })
            .expect("move");
        frames.push(bvh_stage(
            &r.render(&FrameDesc::default(), &Silent).expect("frame"),
        ));
    }
    assert_eq!(frames[0].0, "bvh build");
    assert_eq!(frames[1].0, "bvh refit");
    let expected = if frames[1].1 < frames[0].1 {
        "bvh refit"
    } else {
        "bvh build"
    };
    assert_eq!(frames[2].0, expected, "{frames:?}");
}

/// `direct` rasterizes everything on the GPU: it never builds (or refits) the CPU BVH, not
/// on its first frame and not after an object moved, and its frame after the move still
/// equals a one-shot render of the moved scene bitwise. The methods that trace on the CPU
/// (`ispm` here) still build it.
#[test]
fn direct_builds_no_cpu_bvh() {
    let scene = builtin::load("cornell").expect("scene");
    let bvh_stages = |o: &RenderOutput| -> Vec<String> {
        o.stats
            .stages
            .iter()
            .filter(|(n, _)| n.starts_with("bvh "))
            .map(|(n, _)| n.clone())
            .collect()
    };
    let s = settings(Method::Direct);
    let mut r = Renderer::new(&scene, &s).expect("renderer");
    let first = r.render(&all(), &Silent).expect("frame 0");
    assert_eq!(bvh_stages(&first), Vec::<String>::new());
    for u in pose(&scene, 1.0) {
        r.update(&u).expect("update");
    }
    let moved = r.render(&all(), &Silent).expect("frame 1");
    assert_eq!(bvh_stages(&moved), Vec::<String>::new());
    let one_shot = render(&posed(&scene, 1.0), &s, &Silent).expect("one-shot");
    assert_eq!(bvh_stages(&one_shot), Vec::<String>::new());
    assert_eq!(moved.radiance.pixels, one_shot.radiance.pixels);
    let ispm = render(&scene, &settings(Method::Ispm), &Silent).expect("ispm");
    assert_eq!(bvh_stages(&ispm), vec!["bvh build".to_string()]);
    // Mirrors and glass under a point light alone: a path one scattering from the camera
    // meets no light, so nothing is traced (no BVH either).
    let glass = builtin::load("cornell-glass").expect("scene");
    let point_lit = render(&glass, &s, &Silent).expect("direct");
    assert_eq!(bvh_stages(&point_lit), Vec::<String>::new());
    // Under a sky: `direct` traces the light met one scattering from the camera.
    let traced = render(&under_sky(&glass), &s, &Silent).expect("direct");
    assert_eq!(bvh_stages(&traced), vec!["bvh build".to_string()]);
    let specular = |o: &RenderOutput| o.stats.stages.iter().any(|(n, _)| n == "specular paths");
    assert!(specular(&traced) && !specular(&first) && !specular(&moved));
    assert!(!specular(&point_lit));
}

/// `scene` with a constant sky added (seen through the open front of the Cornell boxes).
fn under_sky(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    let sky = gi_core::scene::Environment::constant(Vec3::new(0.3, 0.4, 0.5));
    s.environment = Some(std::sync::Arc::new(sky));
    s
}

/// `direct` on `cornell-glass` under a sky: the light its mirror and glass show one
/// scattering from the camera is traced after a camera move, and kept (no "specular
/// paths" stage) while only the point light moves; either frame equals a new renderer's
/// frame of the same pose bitwise.
#[test]
fn direct_keeps_its_specular_image_while_only_point_lights_move() {
    let scene = under_sky(&builtin::load("cornell-glass").expect("scene"));
    let s = settings(Method::Direct);
    let mut r = Renderer::new(&scene, &s).expect("renderer");
    let specular = |o: &RenderOutput| o.stats.stages.iter().any(|(n, _)| n == "specular paths");
    assert!(specular(&r.render(&all(), &Silent).expect("frame 0")));
    let [camera, light, _] = <[SceneUpdate; 3]>::try_from(pose(&scene, 1.0)).expect("3");
    let mut posed = scene.clone();
    for (u, traces) in [(light, false), (camera, true)] {
        r.update(&u).expect("update");
        posed.apply(&u).expect("valid update");
        let frame = r.render(&all(), &Silent).expect("frame");
        assert_eq!(specular(&frame), traces, "{u:?}");
        let one_shot = render(&posed, &s, &Silent).expect("one-shot");
        let d = max_difference(&frame.radiance, &one_shot.radiance);
        assert_eq!(d, 0.0, "{u:?}");
    }
}

/// Cancels at the first update of stage `at`.
struct CancelAt(&'static str);
impl gi_core::Progress for CancelAt {
    fn update(&self, stage: &str, _: f64) -> bool {
        stage != self.0
    }
}

/// A frame cancelled half-way (after the direct light was recorded, during the photon
/// trace; `direct` on `cornell-glass` while tracing what its mirror and glass show) leaves
/// the renderer consistent: the next frame equals the one-shot render.
#[test]
fn cancelled_frame_leaves_the_renderer_consistent() {
    let cornell = builtin::load("cornell").expect("scene");
    let glass = under_sky(&builtin::load("cornell-glass").expect("scene"));
    let cases = [
        (&cornell, Method::Ispm, "cpu trace"),
        (&cornell, Method::Direct, "direct"),
        (&glass, Method::Direct, "specular paths"),
    ];
    for (scene, method, stage) in cases {
        let s = settings(method);
        let mut r = Renderer::new(scene, &s).expect("renderer");
        r.render(&all(), &Silent).expect("frame 0");
        for u in pose(scene, 1.0) {
            r.update(&u).expect("update");
        }
        let e = r.render(&all(), &CancelAt(stage)).expect_err("cancelled");
        assert!(matches!(e, gi_core::Error::Cancelled), "{e}");
        let frame = r.render(&all(), &Silent).expect("frame after");
        let one_shot = render(&posed(scene, 1.0), &s, &Silent).expect("one-shot");
        let d = max_difference(&frame.radiance, &one_shot.radiance);
        assert_eq!(d, 0.0, "{}", method.name());
    }
}

/// `ispm` on `cornell-glass` with only the light moving: the frame reuses the camera side
/// of the specular paths (their landings: no camera path is traced) and still equals a new
/// renderer's frame of the moved light bitwise (the landings depend on the camera, the
/// geometry, the materials and the seed, which did not change; the gathers find the same
/// photons in the same order). A camera move traces them again.
#[test]
fn light_only_frames_reuse_the_specular_landings() {
    let scene = builtin::load("cornell-glass").expect("scene");
    let s = settings(Method::Ispm).with("spp", 16);
    let mut r = Renderer::new(&scene, &s).expect("renderer");
    let first = r.render(&all(), &Silent).expect("frame 0");
    assert!(
        first.stats.camera_paths > 0,
        "frame 0 traced no specular paths"
    );
    let moved = pose(&scene, 1.0)[1].clone();
    r.update(&moved).expect("update");
    let frame = r.render(&all(), &Silent).expect("frame 1");
    assert_eq!(frame.stats.camera_paths, 0, "light-only frame re-traced");
    let mut posed = scene.clone();
    posed.apply(&moved).expect("valid update");
    let one_shot = render(&posed, &s, &Silent).expect("one-shot");
    let d = max_difference(&frame.radiance, &one_shot.radiance);
    assert_eq!(d, 0.0, "frames differ by {d}");
    // The specular image is not empty: the spheres show the room.
    let specular = one_shot
        .aovs
        .iter()
        .find(|(n, _)| n == "specular")
        .map(|(_, i)| mean(i))
        .expect("specular AOV");
    assert!(specular > 0.0, "{specular}");
    r.update(&pose(&scene, 1.0)[0]).expect("camera");
    let turned = r.render(&all(), &Silent).expect("frame 2");
    assert!(
        turned.stats.camera_paths > 0,
        "a camera move did not re-trace"
    );
}

/// The `cpu` estimator reads the eye G-buffer back only when it was redrawn: a frame whose
/// light alone moved reuses the view samples it read before, a camera move reads them
/// again; every frame equals a one-shot render of its pose, bitwise.
#[test]
fn light_only_frames_reuse_the_view_samples() {
    let scene = builtin::load("cornell").expect("scene");
    let s = settings(Method::Ispm)
        .with("subsample", 2)
        .with("estimator", Estimator::Cpu);
    let read_back = |o: &RenderOutput| o.stats.stages.iter().any(|(n, _)| n == "gbuffer readback");
    let same_as_one_shot = |frame: &RenderOutput, posed: &Scene| {
        let one_shot = render(posed, &s, &Silent).expect("one-shot");
        let d = max_difference(&frame.radiance, &one_shot.radiance);
        assert_eq!(d, 0.0, "frames differ by {d}");
    };
    let mut r = Renderer::new(&scene, &s).expect("renderer");
    let first = r.render(&all(), &Silent).expect("frame 0");
    assert_eq!(first.stats.estimator, "cpu");
    assert!(read_back(&first), "frame 0 did not read the G-buffer back");
    let [camera, light, _] = <[SceneUpdate; 3]>::try_from(pose(&scene, 1.0)).expect("pose");
    let mut posed = scene.clone();
    for u in [light, camera] {
        r.update(&u).expect("update");
        posed.apply(&u).expect("valid update");
        let frame = r.render(&all(), &Silent).expect("frame");
        let camera_moved = matches!(u, SceneUpdate::Camera(_));
        assert_eq!(read_back(&frame), camera_moved, "{:?}", frame.stats.stages);
        same_as_one_shot(&frame, &posed);
    }
}

/// A serial frame (`FrameDesc::serial`: the GPU waited on after each stage, for
/// benchmarks) is the same frame: bitwise equal radiance, with the wall-clock stages of the
/// splat, the upsampling, the direct light and the bounce maps in its stats.
#[test]
fn serial_frames_equal_overlapped_frames() {
    let scene = builtin::load("cornell-glass").expect("scene");
    let s = settings(Method::Ispm).with("subsample", 2);
    let frame = |serial: bool| {
        let mut r = Renderer::new(&scene, &s).expect("renderer");
        let desc = FrameDesc { serial, ..all() };
        r.render(&desc, &Silent).expect("frame 0");
        r.update(&pose(&scene, 1.0)[1]).expect("light");
        r.render(&desc, &Silent).expect("frame 1")
    };
    let (overlapped, serial) = (frame(false), frame(true));
    let d = max_difference(&overlapped.radiance, &serial.radiance);
    assert_eq!(d, 0.0, "frames differ by {d}");
    for name in [
        "bounce maps (wall)",
        "direct light (wall)",
        "splat (wall)",
        "upsample (wall)",
    ] {
        let has = |o: &RenderOutput| o.stats.stages.iter().any(|(n, _)| n == name);
        assert!(has(&serial), "no {name} in {:?}", serial.stats.stages);
        assert!(!has(&overlapped), "{name} in an overlapped frame");
    }
}

/// Method `ispm` reads the scene's extent (a pass over its meshes, for the photon volume
/// radii) once a frame, however many sources trace photons: the orchestrator makes it and
/// passes it down. Two point lights, three frames, the first light moving (every frame
/// re-traces its photons and re-sizes their volumes).
#[test]
fn ispm_reads_the_scene_extent_once_a_frame() {
    use gi_core::photon::radius::SceneExtent;
    let mut desc: serde_json::Value =
        serde_json::from_str(builtin::json("cornell").expect("cornell")).expect("json");
    let second =
        serde_json::json!({"type": "point", "position": [0.4, 1.2, 0.3], "intensity": [1, 1, 1]});
    desc["lights"].as_array_mut().expect("lights").push(second);
    let scene =
        Scene::from_json(&desc.to_string(), "two lights", &Default::default()).expect("scene");
    let options = settings(Method::Ispm).with("temporal_frames", 3);
    let mut r = Renderer::new(&scene, &options).expect("renderer");
    let desc = FrameDesc {
        seed: None,
        images: Images::default(),
        serial: false,
        readout: Default::default(),
    };
    for f in 0..3 {
        let light = LightDesc::Point {
            position: [0.1 * f as f32, 1.6, 0.0],
            intensity: [3.0; 3],
        };
        r.update(&SceneUpdate::Light { index: 0, light })
            .expect("update");
        let before = SceneExtent::passes();
        let out = r.render(&desc, &Silent).expect("frame");
        assert!(out.stats.photons_stored > 0, "frame {f} stored no photons");
        assert_eq!(SceneExtent::passes() - before, 1, "frame {f}");
    }
}

/// A still `ispm` frame does no photon work: it collects, traces, compensates and uploads
/// no photon (stages "photon collect", "cpu trace" and "boundary compensation" exactly 0,
/// against a first frame that timed its collection) and hands back the last frame's image
/// bitwise; the CPU estimator on `cornell-glass` (with its specular paths) and the tiled one
/// over rasterized bounce maps on `cornell`. A camera move keeps the ring's collection too
/// (the photons did not change) and equals a new renderer of the moved camera bitwise on
/// `cornell` (not on `cornell-glass`: the estimators keep the caustic kernels widened to
/// a pixel of the camera they were uploaded for until the photons change,
/// `indirect::at_least_a_pixel`, so a camera-only move differs there, as before).
#[test]
fn still_ispm_frames_do_no_photon_work() {
    let glass = builtin::load("cornell-glass").expect("scene");
    let cornell = builtin::load("cornell").expect("scene");
    let tiled = settings(Method::Ispm)
        .with("first_bounce", gi_core::frame::options::FirstBounce::Raster)
        .with("estimator", Estimator::Tiled);
    let stage = |o: &RenderOutput, name: &str| {
        let found = o.stats.stages.iter().find(|(n, _)| n == name);
        found.map(|(_, s)| *s)
    };
    for (scene, s) in [(&cornell, tiled), (&glass, settings(Method::Ispm))] {
        let mut r = Renderer::new(scene, &s).expect("renderer");
        let first = r.render(&all(), &Silent).expect("frame 0");
        assert!(stage(&first, "photon collect") > Some(0.0), "frame 0");
        let still = r.render(&all(), &Silent).expect("still frame");
        for name in ["photon collect", "cpu trace", "boundary compensation"] {
            assert_eq!(stage(&still, name), Some(0.0), "{name}: {:?}", still.stats);
        }
        assert_eq!(still.radiance.pixels, first.radiance.pixels);
        assert_eq!(still.stats.photons_stored, first.stats.photons_stored);
        if std::ptr::eq(scene, &glass) {
            continue;
        }
        let camera = pose(scene, 1.0)[0].clone();
        r.update(&camera).expect("camera");
        let turned = r.render(&all(), &Silent).expect("camera frame");
        assert_eq!(stage(&turned, "photon collect"), Some(0.0));
        let mut posed = scene.clone();
        posed.apply(&camera).expect("valid update");
        let one_shot = render(&posed, &s, &Silent).expect("one-shot");
        let d = max_difference(&turned.radiance, &one_shot.radiance);
        assert_eq!(d, 0.0, "{}: camera frame differs by {d}", s.method().name());
    }
}
