//! The bounce maps (ISPM's first photon hits, rasterized from the light) and the CPU photon
//! tracer see the same textured material: a photon is a point sample, so both read the
//! finest level at the photon's point, whatever the bounce map's texel covers.
//!
//! The scene: a spot light over a floor with a fine grey checker (cells of 2 texels of a
//! 1024² texture over 4 m). The bounce map covers the floor with texels about 4 texture
//! texels wide, so a lookup at the rasterizer's mip level would see a near-uniform grey and
//! every photon would survive its diffuse scatter with probability ≈ 0.5 wherever it lands.
//! With the point lookup, survival follows the albedo a(uv) where the photon lands, and the
//! CPU's level-0 albedo averaged over the surviving photons' points is E[a²]/E[a] (≈ 0.70
//! for this checker), not E[a] (0.5).

use gi_core::scene::TextureMap;
use gi_core::texture::Texture;
use gi_core::trace::SceneBvh;
use gi_core::Scene;
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::sync::Arc;

const SIZE: u32 = 1024;
const DARK: f32 = 0.02;
const BRIGHT: f32 = 0.98;

fn checker() -> Texture {
    let texels: Vec<f32> = (0..SIZE * SIZE)
        .flat_map(|i| {
            let (x, y) = (i % SIZE / 2, i / SIZE / 2);
            let a = if (x + y) % 2 == 0 { DARK } else { BRIGHT };
            [a, a, a, 1.0]
        })
        .collect();
    Texture::new(SIZE, SIZE, &texels).unwrap()
}

fn scene() -> Scene {
    let json = serde_json::json!({
        "camera": {"position": [0, 3, 0.1], "look_at": [0, 0, 0], "width": 16, "height": 16},
        "lights": [{"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0],
                    "intensity": [1, 1, 1], "inner_angle": 25, "outer_angle": 30}],
        "materials": {"checker": {"diffuse": [1, 1, 1], "diffuse_texture": "checker"}},
        "objects": [{"shape": {"type": "quad", "size": [4, 4]}, "material": "checker"}],
    });
    let textures: TextureMap = [("checker".to_string(), Arc::new(checker()))]
        .into_iter()
        .collect();
    Scene::from_json_textured(&json.to_string(), "t", &HashMap::new(), &textures).unwrap()
}

#[test]
fn bounce_map_photons_see_the_cpu_material() {
    let scene = scene();
    let settings = gi_core::options!(Ispm, photons: 20_000);
    let bm = gi_core::frame::bounce_map(&scene, &settings).unwrap();
    let bvh = SceneBvh::build(&scene);
    let light = Vec3::new(0.0, 2.0, 0.0);
    // The CPU's level-0 albedo where each surviving photon left the floor (found by casting
    // from the light through the ray's origin, which sits 1e-4 above the floor).
    let albedos: Vec<f32> = bm
        .rays
        .iter()
        .filter_map(|r| {
            let to = Vec3::from(r.origin) - light;
            let hit = bvh.intersect(light, to.normalize(), 10.0)?;
            let t = hit.triangle as usize;
            let uv = scene.uv_at(t, hit.u, hit.v);
            Some(scene.material_at(t, uv, 0.0).diffuse.x)
        })
        .collect();
    assert!(albedos.len() > 5_000, "{} survivors", albedos.len());
    let mean = albedos.iter().sum::<f32>() / albedos.len() as f32;
    // E[a²]/E[a] of the checker's level-0 bilinear lookup over uniform uv (the lit disc
    // spans hundreds of cells, so its points are uniform over a cell): midpoint rule over
    // one period (4 texels) with 64 samples per texel, exact to ~1e-4 for the piecewise
    // quadratic a² (analytically 0.25 + 0.48²·(2/3)² = 0.3524 over 0.5: 0.7048).
    let n = 256;
    let period = 4.0 / SIZE as f32;
    let (mut s1, mut s2) = (0.0f64, 0.0f64);
    let tex = scene.texture(0);
    for i in 0..n {
        for j in 0..n {
            let uv = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32) * period;
            let a = tex.sample(uv, 0.0).x as f64;
            s1 += a;
            s2 += a * a;
        }
    }
    let expected = (s2 / s1) as f32;
    assert!(expected > 0.65, "{expected}");
    // Tolerance 0.02: the standard error of a mean of ≥ 5000 albedos in [0.02, 0.98] is
    // under 0.007, and the disc's texels are not exactly uniform over a cell (the spot's
    // falloff weights them only by survival, not in this mean). A mip-level lookup gives
    // ≈ 0.5, ten tolerances away.
    assert!(
        (mean - expected).abs() < 0.02,
        "mean albedo at survivors {mean}, expected {expected}"
    );
}
