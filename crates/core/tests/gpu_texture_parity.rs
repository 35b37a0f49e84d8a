//! CPU/GPU parity of texture lookups: a compute shader samples the atlas with
//! `texture.wgsl`'s `tex_sample` at explicit (uv, level of detail) queries and must match
//! `Texture::sample`.
//!
//! Tolerance: 2e-5 per channel (texels are in [0, 1]). Both sides read identical texels (the
//! CPU rounds its levels to f16 as the `Rgba16Float` atlas stores them) and do the same f32
//! arithmetic: wrap, bilinear weights and the level blend are a dozen roundings of about
//! 6e-8 each. Where `uv·size - 0.5` lies within an ULP of an integer the two may pick
//! neighbouring texel pairs, but bilinear filtering is continuous there, so the results
//! still agree to rounding. 8-bit sources are not involved: images arrive as floats.

mod common;

use gi_core::gpu;
use gi_core::gpu::Pipelines;
use gi_core::raster::textures::{GpuTextures, TexturesLayout};
use gi_core::sampling::Rng;
use gi_core::scene::TextureMap;
use gi_core::texture::Texture;
use gi_core::Scene;
use glam::{Vec2, Vec4};
use std::collections::HashMap;
use std::sync::Arc;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct QueryRaw {
    uv: [f32; 2],
    lod: f32,
    texture: u32,
}

fn random_texture(rng: &mut Rng, w: u32, h: u32) -> Texture {
    let data: Vec<f32> = (0..w * h * 4).map(|_| rng.next_f32()).collect();
    Texture::new(w, h, &data).unwrap()
}

/// A scene whose materials use every texture (the atlas packs the scene's textures).
fn scene_with(textures: &[(String, Arc<Texture>)]) -> Scene {
    let mats: serde_json::Map<String, serde_json::Value> = textures
        .iter()
        .map(|(n, _)| (n.clone(), serde_json::json!({"diffuse_texture": n})))
        .collect();
    let json = serde_json::json!({
        "camera": {"position": [0, 1, 3], "look_at": [0, 0, 0], "width": 8, "height": 8},
        "materials": mats,
        "objects": [{"shape": {"type": "quad", "size": [1, 1]}, "material": textures[0].0}],
    });
    let map: TextureMap = textures.iter().cloned().collect();
    Scene::from_json_textured(&json.to_string(), "parity", &HashMap::new(), &map).unwrap()
}

#[test]
fn wgsl_texture_lookup_matches_cpu() {
    let mut rng = Rng::new(13, 0, 0);
    // Odd and non-square sizes, a single texel, and a chain of nine levels.
    let sizes = [(7, 5), (16, 16), (1, 1), (33, 9), (300, 200), (2, 64)];
    let textures: Vec<(String, Arc<Texture>)> = sizes
        .iter()
        .enumerate()
        .map(|(i, &(w, h))| (format!("t{i}"), Arc::new(random_texture(&mut rng, w, h))))
        .collect();
    let scene = scene_with(&textures);
    let mut queries = Vec::new();
    for t in 0..textures.len() as u32 {
        let tex = scene.texture(t);
        let (w, h) = (tex.width() as f32, tex.height() as f32);
        for i in 0..400 {
            let uv = Vec2::new(rng.next_f32() * 6.0 - 3.0, rng.next_f32() * 6.0 - 3.0);
            let lod = match i % 4 {
                0 => 0.0,
                1 => (rng.next_f32() * 10.0 - 1.0).floor(),
                _ => rng.next_f32() * 11.0 - 1.0,
            };
            queries.push((t, uv, lod));
        }
        // Texel centres and texel edges of the finest level, and the texture's border.
        for (x, y) in [
            (0.5, 0.5),
            (1.0, 1.0),
            (w - 0.5, h - 0.5),
            (w, h),
            (0.0, 0.0),
        ] {
            queries.push((t, Vec2::new(x / w, y / h), 0.0));
        }
    }
    let cpu: Vec<Vec4> = queries
        .iter()
        .map(|&(t, uv, lod)| scene.texture(t).sample(uv, lod))
        .collect();
    let gpu = gpu_sample(&scene, &queries);
    let mut worst = 0.0f32;
    let mut failures = Vec::new();
    for (i, ((c, g), q)) in cpu.iter().zip(&gpu).zip(&queries).enumerate() {
        let d = (*c - *g).abs().max_element();
        worst = worst.max(d);
        if d > 2e-5 || d.is_nan() {
            failures.push(format!("query {i} {q:?}: cpu {c} gpu {g}"));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} differ (worst {worst}): {:?}",
        failures.len(),
        queries.len(),
        &failures[..failures.len().min(5)]
    );
    // The queries are not trivially equal: the lookups vary.
    let spread = cpu.iter().map(|v| v.x).fold(0.0f32, f32::max)
        - cpu.iter().map(|v| v.x).fold(1.0f32, f32::min);
    assert!(spread > 0.5, "{spread}");
    eprintln!("{} queries, worst difference {worst:e}", queries.len());
}

fn gpu_sample(scene: &Scene, queries: &[(u32, Vec2, f32)]) -> Vec<Vec4> {
    let ctx = gpu::context(None).expect("a GPU adapter (lavapipe in CI)");
    let textures_layout = &TexturesLayout::get(&ctx).layout;
    let textures = GpuTextures::new(&ctx, scene, textures_layout).unwrap();
    let raw: Vec<QueryRaw> = queries
        .iter()
        .map(|&(t, uv, lod)| QueryRaw {
            uv: uv.into(),
            lod,
            texture: t,
        })
        .collect();
    let parts = [
        gpu::shaders::COMMON,
        gpu::shaders::TEXTURE,
        include_str!("gpu_texture_parity.wgsl"),
    ];
    let input = bytemuck::cast_slice(&raw);
    let textures = Some((textures_layout, &textures.group));
    common::kernel::run(&ctx, &parts, input, queries.len(), textures)
        .iter()
        .map(|v| Vec4::from_array(*v))
        .collect()
}
