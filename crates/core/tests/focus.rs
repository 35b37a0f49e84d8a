//! Photon focusing (issue 11): projection maps aim part of each light's photons at the
//! mirrors and glass; caustic photons become more frequent and the power they carry is
//! unchanged in expectation.

use gi_core::frame::gather::gather_trace_settings;
use gi_core::photon::focus::Focus;
use gi_core::photon::trace::{emit_and_trace_focused, Checked};
use gi_core::photon::PathKind;
use gi_core::scene::builtin;
use gi_core::trace::SceneBvh;
use gi_core::Method;
use gi_core::Silent;
use glam::DVec3;

/// Per run of `n` photons: caustic photons stored, and the caustic power per chunk of
/// 10,000 photons (for the Monte Carlo error of the total).
fn caustics(focus: f32, n: u64, seed: u64) -> (u64, Vec<DVec3>) {
    let scene = builtin::load("cornell-glass").unwrap();
    let bvh = SceneBvh::build(&scene);
    let settings = gi_core::options!(Gather, photons: n);
    let pts = gather_trace_settings(&scene, &settings);
    let f = Focus::of_scene(&scene, focus);
    let mut count = 0;
    let mut chunks = Vec::new();
    let per = 10_000;
    for c in 0..n / per {
        let set = emit_and_trace_focused(
            &scene,
            &bvh,
            per,
            &pts,
            seed ^ (c * 0x9E37_79B9),
            &Checked::new(&Silent, "t"),
            &f,
        )
        .unwrap();
        let mut power = DVec3::ZERO;
        for (p, fp) in set.photons.iter().zip(&set.footprints) {
            if fp.kind == PathKind::Caustic {
                count += 1;
                power += p.power().as_dvec3();
            }
        }
        chunks.push(power);
    }
    (count, chunks)
}

fn mean_and_error(chunks: &[DVec3]) -> (f64, f64) {
    let v: Vec<f64> = chunks.iter().map(|c| c.element_sum()).collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

#[test]
fn focusing_multiplies_caustic_photons_and_keeps_their_power() {
    let n = 300_000;
    let (plain_count, plain) = caustics(0.0, n, 1);
    let (focused_count, focused) = caustics(0.5, n, 2);
    let ratio = focused_count as f64 / plain_count as f64;
    println!("caustic photons per emitted: {plain_count} -> {focused_count} of {n} ({ratio:.1}x)");
    // The issue asks for at least 5x on cornell-glass (measured: 11.1x, z = 0.75; the two spheres
    // subtend about 2.5% of the point light's sphere of directions, half the photons are
    // aimed into their cones).
    assert!(ratio >= 5.0, "{ratio}");
    // Same caustic power in expectation: the difference within 3.5 combined standard errors
    // of the two totals (chunk-to-chunk variance over 30 chunks each).
    let (m0, e0) = mean_and_error(&plain);
    let (m1, e1) = mean_and_error(&focused);
    let z = (m1 - m0) / (e0 * e0 + e1 * e1).sqrt();
    println!("caustic power per chunk: {m0:.5} ± {e0:.5} -> {m1:.5} ± {e1:.5} (z = {z:.2})");
    assert!(z.abs() < 3.5, "z = {z}");
    // And focusing makes that estimate far less noisy.
    assert!(e1 < 0.5 * e0, "{e0} {e1}");
}

#[test]
fn no_specular_objects_no_focusing() {
    let scene = builtin::load("cornell").unwrap();
    let f = Focus::of_scene(&scene, 0.5);
    assert!((0..scene.lights.len()).all(|l| !f.active(l)));
    let glass = builtin::load("cornell-glass").unwrap();
    assert!(Focus::of_scene(&glass, 0.5).active(0));
    assert!(!Focus::of_scene(&glass, 0.0).active(0));
}

/// ISPM (per frame, `render` with a new seed): the aimed CPU photons carry every first hit
/// on the spheres, the bounce map the rest.
fn ispm_frames(focus: f32, seeds: std::ops::Range<u64>) -> (u64, u64, Vec<f64>) {
    let scene = builtin::load("cornell-glass").unwrap();
    let (mut caustic, mut emitted, mut means) = (0, 0, Vec::new());
    for seed in seeds {
        let settings = gi_core::RenderOptions::defaults(Method::Ispm)
            .with_method(gi_core::Method::Ispm)
            .with("width", 48)
            .with("height", 48)
            .with("photons", 50_000)
            .with("photon_focus", focus)
            .with("seed", seed);
        let out = gi_core::render(&scene, &settings, &Silent).unwrap();
        caustic += out.stats.caustic_photons;
        emitted += out.stats.photons_emitted;
        means.push(out.radiance.mean().as_dvec3().element_sum());
    }
    (caustic, emitted, means)
}

#[test]
fn ispm_focusing_multiplies_caustic_photons_and_keeps_the_image_mean() {
    let (c0, e0, plain) = ispm_frames(0.0, 0..8);
    let (c1, e1, focused) = ispm_frames(0.5, 100..108);
    let before = c0 as f64 / e0 as f64;
    let after = c1 as f64 / e1 as f64;
    println!(
        "ispm caustic photons per emitted photon: {before:.4} -> {after:.4} ({:.1}x)",
        after / before
    );
    // At least 5x, as the issue asks (measured 8.6x: the spheres subtend ~2.5% of the
    // light's directions; half as many photons again are aimed into their cones).
    assert!(after >= 5.0 * before, "{before} {after}");
    // The image mean against a path-traced reference (with light tracing for the caustics).
    let scene = builtin::load("cornell-glass").unwrap();
    let reference: f64 = (0..2)
        .map(|seed| {
            let s = gi_core::RenderOptions::defaults(Method::Path)
                .with_method(gi_core::Method::Path)
                .with("width", 48)
                .with("height", 48)
                .with("spp", 64)
                .with("seed", seed);
            let out = gi_core::render(&scene, &s, &Silent).unwrap();
            out.radiance.mean().as_dvec3().element_sum() / 2.0
        })
        .sum();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (m0, m1) = (mean(&plain), mean(&focused));
    println!(
        "image mean: path {reference:.4}; ispm {m0:.4} ({:+.1}%) -> focused {m1:.4} ({:+.1}%)",
        100.0 * (m0 / reference - 1.0),
        100.0 * (m1 / reference - 1.0)
    );
    // Focused: within 1.5% of the reference (measured +0.8%, the photon-volume splat's own
    // bias; the Monte Carlo error of this comparison is about 0.3%). Unfocused, the few
    // bounce-map caustic photons got wide density-bounded kernels and the mean was ~19%
    // high at this size; since caustic kernels are at least a pixel wide and splatted at
    // full resolution (issue 29) it is +0.7% (focused +0.9%). Focusing must not be worse
    // beyond the noise of the two means' difference (~0.45%, two independent 0.3% errors):
    // 1% of the reference.
    assert!((m1 / reference - 1.0).abs() < 0.015, "{m1} vs {reference}");
    assert!(
        (m1 - reference).abs() <= (m0 - reference).abs() + 0.01 * reference,
        "focused {m1}, plain {m0}, path {reference}"
    );
}
