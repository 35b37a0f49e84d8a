//! Alpha-masked cut-outs in the passes that the Python tests cannot see one by one: the
//! bounce maps (ISPM's first photon hits) treat a fully cut-out quad as absent, and a
//! half-cut quad as half there.

use gi_core::scene::TextureMap;
use gi_core::texture::Texture;
use gi_core::Scene;
use std::collections::HashMap;
use std::sync::Arc;

/// A floor and, between it and a spot light pointing down, a 1×1 quad whose coverage is
/// `alpha` (left half) and 1 (right half).
fn scene(with_quad: bool, alpha: f32) -> Scene {
    let texels: Vec<f32> = (0..2)
        .flat_map(|x| [0.5, 0.5, 0.5, if x == 0 { alpha } else { 1.0 }])
        .collect();
    let mask = Texture::new(2, 1, &texels).unwrap();
    let mut objects = vec![serde_json::json!(
        {"shape": {"type": "quad", "size": [4, 4]}, "material": "white"})];
    if with_quad {
        objects.push(
            serde_json::json!({"shape": {"type": "quad", "size": [1, 1]},
            "material": "masked", "transform": {"translate": [0, 1, 0]}}),
        );
    }
    let json = serde_json::json!({
        "camera": {"position": [0, 3, 0.1], "look_at": [0, 0, 0], "width": 16, "height": 16},
        "lights": [{"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0],
                    "intensity": [1, 1, 1], "inner_angle": 10, "outer_angle": 12}],
        "materials": {"white": {"diffuse": [0.8, 0.8, 0.8]},
                      "masked": {"diffuse": [0.2, 0.9, 0.2], "alpha_texture": "mask"}},
        "objects": objects,
    });
    let textures: TextureMap = [("mask".to_string(), Arc::new(mask))].into_iter().collect();
    Scene::from_json_textured(&json.to_string(), "t", &HashMap::new(), &textures).unwrap()
}

fn settings() -> gi_core::RenderOptions {
    gi_core::options!(Ispm, photons: 20_000)
}

#[test]
fn bounce_maps_skip_cut_out_texels() {
    let s = settings();
    let floor = gi_core::frame::bounce_map(&scene(false, 1.0), &s).unwrap();
    let cut = gi_core::frame::bounce_map(&scene(true, 0.0), &s).unwrap();
    let opaque = gi_core::frame::bounce_map(&scene(true, 1.0), &s).unwrap();
    // The spot's 12° cone lights a disc of radius 0.21 on the quad (half-width 0.5): all of
    // its power reaches the quad when it is opaque, half of it passes the cut half. The
    // expected scattered power is Σ Φ·albedo over covered texels: floor 0.8, quad green 0.9
    // and red 0.2 (bounce-map texels carry equal powers, whatever they hit: exact ratios
    // up to the texels on the quad's centre line).
    let ratio = |a: &gi_core::photon::bounce::BounceMap, b: &gi_core::photon::bounce::BounceMap| {
        a.expected_scattered_power.y / b.expected_scattered_power.y
    };
    assert_eq!(cut.covered, floor.covered);
    // Half on the floor (0.8), half on the quad's opaque half (albedo 0.9 in green).
    let half = ratio(&cut, &floor);
    assert!((half - (0.5 + 0.5 * 0.9 / 0.8)).abs() < 0.02, "{half}");
    // The red channel sees the quad's 0.2 where it is opaque.
    let red = opaque.expected_scattered_power.x / floor.expected_scattered_power.x;
    assert!((red - 0.2 / 0.8).abs() < 0.01, "{red}");
}
