//! The indirect estimators (`Settings::estimator`) splat the same photons with the same
//! kernels, BSDF and normal test, so they must give the same image: raster photon volumes
//! against tiled compute splatting, on lavapipe at small sizes.

mod common;

use common::{lit_pixels, max_difference};
use gi_core::estimate::Estimator;
use gi_core::Silent;
use gi_core::{render, scene::builtin, RenderOutput, Scene};

fn scene(name: &str) -> Scene {
    match name {
        "spot-glossy" => common::spot_scene(name, 0.2, 3),
        _ => builtin::load(name).expect("built-in scene"),
    }
}

fn settings(size: u32, subsample: u32, kernel_scale: f32) -> gi_core::RenderOptions {
    gi_core::options!(Ispm, spp: 1, width: size, height: size, seed: 7, photons: 50_000, subsample: subsample, kernel_scale: kernel_scale)
}

fn run(scene: &Scene, s: &gi_core::RenderOptions, estimator: Estimator) -> RenderOutput {
    render(scene, &s.clone().with("estimator", estimator), &Silent).expect("render")
}

fn indirect(out: &RenderOutput) -> &gi_core::Image {
    out.aovs
        .iter()
        .find(|(n, _)| n == "indirect")
        .map(|(_, img)| img)
        .expect("indirect AOV")
}

/// `tiled`, `cluster` and `cpu` (the same estimate computed on the CPU) equal `volumes` on: the Cornell box at subsample 1 and 2 (the half-texel shift
/// of the low-resolution view); the furnace, whose camera sits inside the sphere among the
/// photons (volumes reaching behind the eye plane: full-screen tile ranges); a spot light on
/// glossy and metallic surfaces; the Cornell box with glass and a mirror (caustic photons
/// with small kernels); and 4× larger kernels at 128² (long lists).
/// Tolerance: 1e-4 of the image's largest pixel. Both sum the same terms (the same WGSL
/// function, ported to Rust for `cpu`) in another order: raster blending in draw order,
/// tiled in list order (atomics), cpu in photon order;
/// an f32 sum of a few hundred terms of like sign is off by ~1e-5 relative. Equal lit-pixel
/// counts check that no photon is dropped or added at a tile edge. The tolerance is checked
/// to be tight: 3% smaller kernels differ by more than 100× it.
#[test]
fn binned_estimators_give_the_same_image_as_volumes() {
    let cases = [
        ("cornell", 64, 1, 1.0),
        ("cornell", 64, 2, 1.0),
        ("furnace", 32, 1, 4.0),
        ("spot-glossy", 64, 2, 1.0),
        ("cornell-glass", 64, 1, 1.0),
        ("cornell", 128, 1, 4.0),
    ];
    for (name, size, subsample, kernel_scale) in cases {
        let sc = scene(name);
        let s = settings(size, subsample, kernel_scale);
        let volumes = run(&sc, &s, Estimator::Volumes);
        assert_eq!(volumes.stats.estimator, "volumes");
        let v = indirect(&volumes);
        let scale = v.pixels.iter().map(|p| p.max_element()).fold(0.0, f32::max);
        let lit = lit_pixels(v);
        assert!(scale > 0.0, "{name}: no indirect light");
        assert!(lit > size as usize * size as usize / 4, "{lit} lit pixels");
        let rad_scale = volumes
            .radiance
            .pixels
            .iter()
            .map(|p| p.max_element())
            .fold(0.0, f32::max);
        for estimator in [Estimator::Tiled, Estimator::Cluster, Estimator::Cpu] {
            let out = run(&sc, &s, estimator);
            let e = estimator.name();
            assert_eq!(out.stats.estimator, e);
            let t = indirect(&out);
            let d = max_difference(t, v, scale);
            let regrown = out
                .stats
                .stages
                .iter()
                .any(|(n, _)| n == "photon lists regrown");
            eprintln!(
                "{name} {size}² k={subsample} ks={kernel_scale} {e}: max pixel {scale:.4}, \
                 lit {lit}/{}, |{e} − volumes| {d:.2e} of the max pixel; photons {}; \
                 list entries {} (trivial accepts {}); lists regrown: {regrown}",
                size * size,
                out.stats.photons_stored,
                out.stats.list_entries,
                out.stats.trivial_accepts,
            );
            assert_eq!(lit_pixels(t), lit, "{name}: {e} lights other pixels");
            // The GPU estimators run the same WGSL kernel: 1e-4 of the max pixel (summation
            // order). The CPU estimator evaluates it in Rust: on a GPU whose pow/exp are the
            // hardware's approximations (NVIDIA: ~2⁻²² relative, amplified by a glossy
            // exponent) it differs more (H100: 1.9e-4 on spot-glossy; lavapipe, whose
            // math is LLVM's as the CPU's, < 1e-4): 1e-3, far below any real difference.
            let tol = if estimator == Estimator::Cpu {
                1e-3
            } else {
                1e-4
            };
            assert!(d < tol, "{name}: {e} differs from volumes by {d}");
            // The composite adds the same indirect light: the radiance agrees as closely.
            let dr = max_difference(&out.radiance, &volumes.radiance, rad_scale);
            assert!(dr < tol, "{name}: {e} radiance differs by {dr}");
            // Wide kernels over the box's diffuse walls: the hierarchy must accept whole
            // nodes, or it is only a finer tiling.
            if estimator == Estimator::Cluster && name != "spot-glossy" && kernel_scale >= 1.0 {
                assert!(out.stats.trivial_accepts > 0, "{name}: no trivial accepts");
            }
        }
        if name == "cornell" && size == 64 && subsample == 1 {
            let smaller = run(
                &sc,
                &s.clone().with("kernel_scale", 0.97),
                Estimator::Cluster,
            );
            let d = max_difference(indirect(&smaller), v, scale);
            eprintln!("cornell with 3% smaller kernels: {d:.2e}");
            assert!(d > 1e-2, "{d}");
        }
    }
}

/// Lists are sized from a CPU estimate when photons are uploaded; when the GPU needs more,
/// the frame grows them and redoes the estimate. Forced here by scaling the estimate down
/// (`GI_LIST_ESTIMATE`; the other tests in this binary may see it too, which only sends them
/// through the same, exact, path): the image must equal the volumes' and the list entries
/// must be those of a normally sized run.
#[test]
fn lists_regrow_when_the_estimate_is_short() {
    let sc = scene("cornell");
    let s = settings(96, 2, 1.0);
    let volumes = run(&sc, &s, Estimator::Volumes);
    let scale = volumes
        .radiance
        .pixels
        .iter()
        .map(|p| p.max_element())
        .fold(0.0, f32::max);
    for estimator in [Estimator::Tiled, Estimator::Cluster] {
        let normal = run(&sc, &s, estimator);
        std::env::set_var(gi_core::estimate::binned::LIST_ESTIMATE_ENV, "0.01");
        let short = run(&sc, &s, estimator);
        std::env::remove_var(gi_core::estimate::binned::LIST_ESTIMATE_ENV);
        let regrown = |o: &RenderOutput| {
            o.stats
                .stages
                .iter()
                .any(|(n, _)| n == "photon lists regrown")
        };
        let e = estimator.name();
        assert!(regrown(&short), "{e}: a 1% estimate did not overflow");
        assert_eq!(short.stats.list_entries, normal.stats.list_entries, "{e}");
        assert_eq!(short.radiance.pixels, normal.radiance.pixels, "{e}");
        let d = max_difference(&short.radiance, &volumes.radiance, scale);
        assert!(d < 1e-4, "{e}: {d}");
    }
    // The cluster walk's job lists alone too short: jobs beyond them are lost to the walk,
    // so the frame must notice, grow them and walk again.
    let normal = run(&sc, &s, Estimator::Cluster);
    std::env::set_var(gi_core::estimate::binned::JOB_ESTIMATE_ENV, "0.001");
    let short = run(&sc, &s, Estimator::Cluster);
    std::env::remove_var(gi_core::estimate::binned::JOB_ESTIMATE_ENV);
    assert!(
        short
            .stats
            .stages
            .iter()
            .any(|(n, _)| n == "photon lists regrown"),
        "short job lists did not overflow"
    );
    assert_eq!(short.stats.list_entries, normal.stats.list_entries);
    assert_eq!(short.radiance.pixels, normal.radiance.pixels);
}

/// The compute estimators build their lists with atomics, in an order that varies between
/// runs, but sum in fixed point: the same settings give the same bits.
#[test]
fn binned_estimators_are_reproducible() {
    let sc = scene("cornell");
    let s = settings(96, 2, 2.0);
    for estimator in [
        Estimator::Tiled,
        Estimator::Cluster,
        Estimator::Directional,
        Estimator::Cpu,
    ] {
        let a = run(&sc, &s, estimator);
        let b = run(&sc, &s, estimator);
        assert!(a.stats.list_entries > 0);
        assert_eq!(a.radiance.pixels, b.radiance.pixels, "{}", estimator.name());
    }
}

#[test]
fn estimator_setting_parses_and_auto_reports_its_choice() {
    assert_eq!(
        gi_core::frame::options::IspmOptions::default().estimator,
        Estimator::Auto
    );
    assert_eq!("tiled".parse::<Estimator>().ok(), Some(Estimator::Tiled));
    let e = "splat".parse::<Estimator>().err();
    assert!(
        matches!(e, Some(gi_core::Error::Setting { name, .. }) if name == "estimator"),
        "{e:?}"
    );
    let sc = scene("cornell");
    let out = run(&sc, &settings(32, 2, 1.0), Estimator::Auto);
    assert!(
        ["volumes", "tiled", "cluster", "cpu"].contains(&out.stats.estimator.as_str()),
        "{}",
        out.stats.estimator
    );
    assert!(!out.stats.estimator_reason.is_empty());
    assert!(out.stats.estimator_memory.iter().all(|(_, b)| *b > 0));
}

/// The directional approximation against the exact cluster estimate (the same photons and
/// hierarchy). Its irradiance is constant per node and it sees 8 mean directions, so it is
/// close, not equal. Measured at 256² (subsample 2, 100k photons): the Cornell box PSNR
/// 28.7 dB, SSIM 0.807, mean +1.8% (diffuse walls: the approximation everywhere, blocky at
/// 16-pixel leaves; 25.7 dB / 0.767 before the leaves were split by normal); the spot-lit
/// glossy scene 49.9 dB, 0.993, mean +0.1% (its glossy clusters are summed exactly).
/// Bounds: 26 dB / 0.77 and 45 dB / 0.98, means within 5% (about 3 dB and a third of the
/// SSIM gap to 1 below the measurements, which are deterministic for the seed: the margin
/// leaves room for changes to the photon kernels, not for a broken approximation).
/// A lost octant, a wrong weight or double-counted ancestors fail them (the first version,
/// weighting by octant centres, lost 19%).
#[test]
fn directional_is_close_to_cluster() {
    for (name, min_psnr, min_ssim) in [("cornell", 26.0, 0.77), ("spot-glossy", 45.0, 0.98)] {
        let sc = scene(name);
        let s = settings(256, 2, 1.0).with("photons", 100_000);
        let cluster = run(&sc, &s, Estimator::Cluster);
        let directional = run(&sc, &s, Estimator::Directional);
        assert_eq!(directional.stats.estimator, "directional");
        let (c, d) = (indirect(&cluster), indirect(&directional));
        let mean =
            |img: &gi_core::Image| img.luminance().iter().sum::<f64>() / img.pixels.len() as f64;
        let (p, q) = (c.psnr(d), c.ssim(d));
        let ratio = mean(d) / mean(c);
        eprintln!(
            "{name}: directional vs cluster: PSNR {p:.2} dB, SSIM {q:.4}, mean ratio {ratio:.4}"
        );
        assert!(p > min_psnr, "{name}: PSNR {p}");
        assert!(q > min_ssim, "{name}: SSIM {q}");
        assert!((ratio - 1.0).abs() < 0.05, "{name}: mean ratio {ratio}");
    }
}
