//! Scenes for benchmarks: the Cornell box with dense geodesic spheres (≥ 100k triangles),
//! with many copies of one sphere (coincident or on a grid), and incoherent rays inside it. Shared by `cargo bench` and the Embree comparison.

use super::{builtin, Scene};
use crate::sampling::{uniform_sphere, Rng};
use glam::Vec3;
use std::collections::HashMap;

/// The Cornell box plus three geodesic spheres of 20·4⁶ = 81,920 triangles each (~246k).
pub fn dense_cornell() -> Scene {
    let mut v: serde_json::Value =
        serde_json::from_str(builtin::json("cornell").unwrap_or_default()).unwrap_or_default();
    if let Some(objects) = v["objects"].as_array_mut() {
        for (x, z) in [(-0.5f32, 0.3f32), (0.5, -0.3), (0.0, 0.5)] {
            objects.push(serde_json::json!({
                "shape": {"type": "sphere", "radius": 0.3, "subdivisions": 6},
                "transform": {"translate": [x, 1.2, z]},
                "material": "white"
            }));
        }
    }
    Scene::from_json(&v.to_string(), "dense-cornell", &HashMap::new())
        .expect("the benchmark scene is valid")
}

/// The Cornell box plus `copies` geodesic spheres of 20·4⁵ = 20,480 triangles each (radius
/// 0.1): all at one place (`coincident`: the degenerate input of many coincident triangles)
/// or on a square grid filling the box at y = 1.
pub fn sphere_copies(copies: usize, coincident: bool) -> Scene {
    let mut v: serde_json::Value =
        serde_json::from_str(builtin::json("cornell").unwrap_or_default()).unwrap_or_default();
    let side = (copies as f32).sqrt().ceil().max(1.0) as usize;
    if let Some(objects) = v["objects"].as_array_mut() {
        for i in 0..copies {
            let (x, z) = if coincident {
                (0.0, 0.0)
            } else {
                let cell = 1.8 / side as f32;
                (
                    -0.9 + cell * ((i % side) as f32 + 0.5),
                    -0.9 + cell * ((i / side) as f32 + 0.5),
                )
            };
            objects.push(serde_json::json!({
                "shape": {"type": "sphere", "radius": 0.1, "subdivisions": 5},
                "transform": {"translate": [x, 1.0, z]},
                "material": "white"
            }));
        }
    }
    let name = if coincident { "coincident" } else { "grid" };
    Scene::from_json(&v.to_string(), name, &HashMap::new()).expect("the benchmark scene is valid")
}

/// `n` incoherent rays: origins uniform in the box, directions uniform on the sphere.
pub fn incoherent_rays(n: usize, seed: u64) -> Vec<(Vec3, Vec3)> {
    let mut rng = Rng::new(seed, 0, 0);
    (0..n)
        .map(|_| {
            let o = Vec3::new(
                rng.next_f32() * 1.9 - 0.95,
                rng.next_f32() * 1.9 + 0.05,
                rng.next_f32() * 1.9 - 0.95,
            );
            (o, uniform_sphere(rng.next_2d()))
        })
        .collect()
}
