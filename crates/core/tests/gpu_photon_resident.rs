//! GPU-traced photons taken by the binned estimators on the GPU (`gpu::photon::resident`,
//! issue 45 item 1): the sizing pass gives the CPU's volume radii; a frame that keeps the
//! photons on the GPU reads no photon record back and renders the image of the readback
//! path; scenes whose photons a CPU step needs fall back to the readback and say why.

use gi_core::frame::options::PhotonTrace;
use gi_core::frame::{FrameDesc, Images, Renderer};
use gi_core::gpu::photon::{resident, trace};
use gi_core::photon::radius::VolumeRadius;
use gi_core::photon::Photon;
use gi_core::scene::builtin;
use gi_core::{Method, RenderOptions, RenderOutput, Scene, Silent};

/// Options under which `cornell`'s photons can stay on the GPU: the GPU trace, a binned
/// estimator at full resolution, and none of the CPU steps (boundary compensation, the
/// caustic density bound, aimed caustics).
fn options() -> RenderOptions {
    RenderOptions::defaults(Method::Ispm)
        .with("width", 48)
        .with("height", 36)
        .with("spp", 1)
        .with("photons", 8_000)
        .with("max_depth", 4)
        .with("photon_trace", PhotonTrace::Gpu)
        .with("estimator", gi_core::estimate::Estimator::Tiled)
        .with("subsample", 1)
        .with("boundary_compensation", false)
        .with("caustic_density_bound", false)
        .with("photon_focus", 0.0)
        // Narrow kernels, so that the radii are `VolumeRadius::of`'s, not all `r_max`
        // (cornell's diffuse path densities widen the default kernels past it): a sizing
        // pass 1% off fails the image comparison.
        .with("kernel_scale", 0.2)
}

/// Two frames (the second a still frame) of a new renderer, with the photon records read
/// back during them; the readback path forced when `readback`.
fn frames(scene: &Scene, o: &RenderOptions, readback: bool) -> (RenderOutput, u64) {
    resident::force_readback(readback);
    let desc = FrameDesc {
        seed: None,
        images: Images::default(),
        serial: false,
        readout: Default::default(),
    };
    let before = trace::records_read_back();
    let mut r = Renderer::new(scene, o).expect("renderer");
    let first = r.render(&desc, &Silent).expect("frame");
    let still = r.render(&desc, &Silent).expect("still frame");
    resident::force_readback(false);
    assert_eq!(
        still.radiance.pixels, first.radiance.pixels,
        "a still frame"
    );
    (first, trace::records_read_back() - before)
}

#[test]
fn cornell_keeps_its_photons_on_the_gpu_with_the_readback_image() {
    let scene = builtin::load("cornell").expect("scene");
    let (kept, read) = frames(&scene, &options(), false);
    assert_eq!(kept.stats.photon_records, "gpu", "{:?}", kept.stats);
    assert_eq!(read, 0, "records read back on the GPU path");
    let (back, read_back) = frames(&scene, &options(), true);
    assert!(back.stats.photon_records.starts_with("readback"));
    assert!(kept.stats.photons_stored > 1000);
    assert_eq!(kept.stats.photons_stored, back.stats.photons_stored);
    assert_eq!(
        read_back, back.stats.photons_stored,
        "the readback path's records"
    );
    // The same photons (the GPU's stream of one seed); their order and the radii's `pow`
    // (WGSL against Rust) differ, so the sums differ by float rounding only.
    let (a, b) = (&kept.radiance.pixels, &back.radiance.pixels);
    let mut worst = 0.0f32;
    for (x, y) in a.iter().zip(b) {
        for c in 0..3 {
            worst = worst.max((x[c] - y[c]).abs() / y[c].abs().max(1e-2));
        }
    }
    assert!(worst <= 1e-4, "largest relative difference {worst}");
    eprintln!("cornell: largest relative difference {worst:e}");
}

#[test]
fn cornell_glass_falls_back_to_the_readback_and_says_why() {
    let scene = builtin::load("cornell-glass").expect("scene");
    let (out, read) = frames(&scene, &options(), false);
    let why = &out.stats.photon_records;
    assert!(why.starts_with("readback: mirrors and glass"), "{why}");
    assert_eq!(read, out.stats.photons_stored);
    let (forced, _) = frames(&scene, &options(), true);
    assert_eq!(forced.radiance.pixels, out.radiance.pixels);
}

#[test]
fn the_default_options_read_back_and_name_the_cpu_step() {
    let mut scene = builtin::load("cornell").expect("scene");
    scene.camera = scene.camera.with_size(32, 24);
    let o = RenderOptions::defaults(Method::Ispm)
        .with("photons", 2_000)
        .with("spp", 1)
        .with("photon_trace", PhotonTrace::Gpu)
        .with("estimator", gi_core::estimate::Estimator::Tiled);
    let (out, read) = frames(&scene, &o, false);
    assert_eq!(
        out.stats.photon_records,
        "readback: subsample > 1 splats the caustic photons apart, split on the CPU"
    );
    assert_eq!(read, out.stats.photons_stored);
    let (cpu, read) = frames(
        &scene,
        &o.clone().with("photon_trace", PhotonTrace::Cpu),
        false,
    );
    assert_eq!(cpu.stats.photon_records, "");
    assert_eq!(read, 0);
}

/// The sizing pass against the CPU: `VolumeRadius::of`, caustic photons widened to a
/// pixel as `ispm`'s upload does, the pad word cleared, the caustic count.
#[test]
fn the_sizing_pass_gives_the_cpus_radii() {
    let ctx = gi_core::gpu::context(None).expect("a GPU adapter (lavapipe in CI)");
    let radius = VolumeRadius {
        r_base: 0.01,
        r_max: 0.2,
    };
    let sizing = resident::Sizing {
        radius,
        eye: [0.5, 1.0, 3.0],
        pixel_per_metre: 0.004,
    };
    let mut photons = Vec::new();
    for i in 0..1000u32 {
        let t = i as f32 / 1000.0;
        // Path densities from 1e-9 (widened to the largest) to 10 (caustic).
        let p = Photon {
            position: [t * 4.0 - 2.0, (t * 37.0).sin(), -(t * 11.0).cos() * 5.0],
            bounce: i % 4,
            path_density: 10f32.powf(-9.0 + 10.0 * t),
            power: [t, 1.0, 2.0],
            _pad0: i,
            footprint_radius: if i % 7 == 0 { 0.05 + t } else { 0.0 },
            ..Default::default()
        };
        photons.push(p);
    }
    let (sized, caustic) = resident::sized_on_gpu(&ctx, &photons, sizing).expect("sized");
    let mut caustics = 0;
    for (p, s) in photons.iter().zip(&sized) {
        let mut r = radius.of(p);
        if gi_core::photon::density::is_caustic(p) {
            caustics += 1;
            let d = (p.position() - glam::Vec3::from(sizing.eye)).length();
            r = r.max(d * sizing.pixel_per_metre);
        }
        let err = (s.footprint_radius - r).abs() / r;
        assert!(
            err <= 1e-5,
            "{p:?}: radius {} against {r}",
            s.footprint_radius
        );
        assert_eq!(s._pad0, 0);
        assert_eq!(
            (s.position, s.bounce, s.power),
            (p.position, p.bounce, p.power)
        );
    }
    assert!(caustics > 100 && caustics < 900, "{caustics}");
    assert_eq!(caustic, caustics);
}
