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
    // 1% is the issue's bound. Error budget: the geodesic sphere (20480 flat faces) is
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

/// The emitting furnace: the sphere's inside emits L = 1 and reflects with albedo ρ, no
/// other light. Every point sees the same radiance L/(1 − ρ) (the series L + ρL + ρ²L …),
/// which method `path` finds by its own rays hitting the emitting walls. Bound 1%: the
/// Monte Carlo error of the image mean at 48×48×32 paths is below 0.3% at ρ = 0.5.
#[test]
fn emitting_furnace_radiance_is_l_over_one_minus_rho() {
    let text = builtin::json("furnace").unwrap();
    let mut v: serde_json::Value = serde_json::from_str(text).unwrap();
    v["lights"] = serde_json::json!([]);
    v["materials"]["wall"]["emission"] = serde_json::json!([1.0, 1.0, 1.0]);
    v["materials"]["wall"]["two_sided"] = serde_json::json!(true);
    let scene = Scene::from_json(&v.to_string(), "emitting-furnace", &HashMap::new()).unwrap();
    assert_eq!(
        gi_core::scene::Emitters::of(&scene).len(),
        scene.triangle_count()
    );
    let settings = gi_core::options!(Path, spp: 32, width: 48, height: 48, seed: 3);
    let out = render(&scene, &settings, &gi_core::Silent).unwrap();
    let expected = 1.0 / (1.0 - 0.5);
    let mean = out.radiance.mean();
    for c in 0..3 {
        let rel = (mean[c] - expected) / expected;
        assert!(rel.abs() < 0.01, "channel {c}: {} vs {expected}", mean[c]);
    }
}

/// A sun of irradiance E at normal incidence on a Lambertian floor of albedo ρ: the floor's
/// radiance is ρE/π, in `path` (next-event estimation of the parallel light) and in the
/// photon methods (photons entering through the bounding disc). Bounds: 0.5% for `path`
/// (direct light only, noise-free on a plane), 3% for the density estimates (photon
/// noise over the image at 200k photons; the floor's edges are cropped).
#[test]
fn sun_on_a_floor_gives_rho_e_over_pi() {
    let json = r#"{
        "camera": {"position": [0, 3, 0.001], "look_at": [0, 0, 0], "fov": 30,
                   "width": 32, "height": 32},
        "lights": [{"type": "directional", "direction": [0, -1, 0], "irradiance": [2, 2, 2]}],
        "materials": {"floor": {"diffuse": [0.5, 0.5, 0.5]}},
        "objects": [{"shape": {"type": "quad", "size": [4, 4]}, "material": "floor"}]
    }"#;
    let scene = Scene::from_json(json, "sun", &HashMap::new()).unwrap();
    let expected = 0.5 * 2.0 / std::f32::consts::PI;
    for (options, bound) in [
        (gi_core::options!(Path, spp: 4, max_depth: 1), 0.005),
        (
            gi_core::options!(Photon, spp: 1, photons: 200_000, max_depth: 1),
            0.03,
        ),
        (
            gi_core::options!(Gather, spp: 1, photons: 50_000, max_depth: 2),
            0.005,
        ),
    ] {
        let out = render(&scene, &options, &gi_core::Silent).unwrap();
        let mean = out.radiance.mean();
        let rel = (mean.x - expected) / expected;
        assert!(
            rel.abs() < bound,
            "{:?}: {} vs {expected}",
            options.method(),
            mean.x
        );
    }
}
