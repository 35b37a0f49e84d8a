//! The closed-sphere furnace: radius R, diffuse albedo ρ, isotropic point light of intensity I
//! at the centre. Every wall point receives E0 = I/R² directly and, by symmetry, the same
//! indirect irradiance, so the outgoing radiance with all bounces is
//! L = ρ·I / (π·R²·(1 − ρ)).

use gi_core::{render, scene::builtin, Scene};
use std::collections::HashMap;

fn furnace(albedo: f32, intensity: f32, radius: f32) -> Scene {
    let text = builtin::json("furnace").unwrap();
    let mut v: serde_json::Value = serde_json::from_str(text).unwrap();
    v["materials"]["wall"]["diffuse"] = serde_json::json!([albedo, albedo, albedo]);
    v["lights"][0]["intensity"] = serde_json::json!([intensity, intensity, intensity]);
    v["objects"][0]["shape"]["radius"] = serde_json::json!(radius);
    Scene::from_json(&v.to_string(), "furnace-test", &HashMap::new()).unwrap()
}

fn check(albedo: f32) {
    let (i, r) = (2.0f32, 1.0f32);
    let scene = furnace(albedo, i, r);
    let settings = gi_core::options!(Path, spp: 32, width: 48, height: 48, seed: 7);
    let out = render(&scene, &settings, &gi_core::Silent).unwrap();
    let expected = albedo * i / (std::f32::consts::PI * r * r * (1.0 - albedo));
    let mean = out.radiance.mean();
    // 1% is the bound. Error budget: the geodesic sphere (20480 flat faces) is
    // within 0.05% of the analytic one, and the Monte Carlo error of the image mean at
    // 73k paths is below 0.3% (ρ = 0.8, where paths are longest).
    for c in 0..3 {
        let rel = (mean[c] - expected) / expected;
        assert!(
            rel.abs() < 0.01,
            "albedo {albedo}: channel {c} mean {} vs analytic {expected} ({:+.3}%)",
            mean[c],
            rel * 100.0
        );
    }
}

#[test]
fn furnace_albedo_half() {
    check(0.5);
}

#[test]
fn furnace_albedo_0_8() {
    check(0.8);
}
