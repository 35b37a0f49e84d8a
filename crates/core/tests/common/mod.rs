//! What the integration tests share: image comparison (luminance SSIM, an edge mask,
//! differences, means, PFM output), scenes and renders; [`frames`] for the `Renderer` tests.
// Each test binary uses its own subset of these helpers.
#![allow(dead_code)]

pub mod frames;
pub mod kernel;

use gi_core::scene::builtin;
use gi_core::{render, Image, RenderOutput, Scene, Silent};
use glam::{DVec3, Vec3};
use std::path::PathBuf;

pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Pixels to leave out of per-pixel comparisons: those within `radius` pixels of
/// - a geometric edge of the reference G-buffer: a miss, a crease (4-neighbours' normals
///   differing by more than ~8°, dot < 0.99) or a depth discontinuity (the second
///   difference of view depth along x or y above 1% of the depth; planes seen at grazing
///   angles have large first but near-zero second differences);
/// - a shadow edge: the second difference of the path-traced luminance along x or y above
///   10% of the local mean. Smooth 1/d² and spot falloffs have small second differences and
///   stay in; hard shadow edges (path tracer) against PCF-softened ones (rasterizer) go.
pub fn edge_mask(reference: &RenderOutput, radius: i32) -> Vec<bool> {
    away_from(reference, &edges(reference, true), radius)
}

/// The pixels on an edge of [`edge_mask`]'s: geometric ones, and with `shadows` shadow
/// edges too.
pub fn edges(reference: &RenderOutput, shadows: bool) -> Vec<bool> {
    let (w, h) = (
        reference.radiance.width as i32,
        reference.radiance.height as i32,
    );
    let idx = |x: i32, y: i32| (y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) as usize;
    let lum: Vec<f32> = reference
        .radiance
        .pixels
        .iter()
        .map(|c| luminance(*c))
        .collect();
    let mut edge = vec![false; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let i = idx(x, y);
            let (d, n) = (reference.depth[i], reference.normal.pixels[i]);
            let mut e = d <= 0.0;
            for (dx, dy) in [(1, 0), (0, 1)] {
                let (a, b) = (idx(x - dx, y - dy), idx(x + dx, y + dy));
                let (da, db) = (reference.depth[a], reference.depth[b]);
                e |= da <= 0.0 || db <= 0.0 || (da + db - 2.0 * d).abs() > 0.01 * d;
                e |= reference.normal.pixels[a].dot(n) < 0.99
                    || reference.normal.pixels[b].dot(n) < 0.99;
                if shadows {
                    let mean = (lum[a] + lum[b] + lum[i]) / 3.0;
                    e |= (lum[a] + lum[b] - 2.0 * lum[i]).abs() > 0.1 * mean;
                }
            }
            edge[i] = e;
        }
    }
    edge
}

/// The pixels of `reference`'s image farther than `radius` pixels (per axis) from every
/// `edge` pixel.
pub fn away_from(reference: &RenderOutput, edge: &[bool], radius: i32) -> Vec<bool> {
    let (w, h) = (
        reference.radiance.width as i32,
        reference.radiance.height as i32,
    );
    let idx = |x: i32, y: i32| (y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) as usize;
    let mut keep = vec![true; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            if edge[idx(x, y)] {
                for dy in -radius..=radius {
                    for dx in -radius..=radius {
                        keep[idx(x + dx, y + dy)] = false;
                    }
                }
            }
        }
    }
    keep
}

/// Mean SSIM of luminance over the pixels in `mask`, with 7×7 uniform windows and the
/// usual constants C1 = (0.01·L)², C2 = (0.03·L)² for L the reference's 99th-percentile
/// luminance (the images are linear HDR).
pub fn ssim(a: &Image, b: &Image, mask: &[bool]) -> f64 {
    let (w, h) = (a.width as i32, a.height as i32);
    let la: Vec<f64> = a.pixels.iter().map(|c| luminance(*c) as f64).collect();
    let lb: Vec<f64> = b.pixels.iter().map(|c| luminance(*c) as f64).collect();
    let mut sorted = lb.clone();
    sorted.sort_by(f64::total_cmp);
    let l = sorted[(sorted.len() - 1) * 99 / 100].max(1e-12);
    let (c1, c2) = ((0.01 * l).powi(2), (0.03 * l).powi(2));
    let (mut total, mut count) = (0.0, 0);
    for y in 0..h {
        for x in 0..w {
            if !mask[(y * w + x) as usize] {
                continue;
            }
            let (mut sa, mut sb, mut saa, mut sbb, mut sab, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
            for yy in (y - 3).max(0)..=(y + 3).min(h - 1) {
                for xx in (x - 3).max(0)..=(x + 3).min(w - 1) {
                    let j = (yy * w + xx) as usize;
                    sa += la[j];
                    sb += lb[j];
                    saa += la[j] * la[j];
                    sbb += lb[j] * lb[j];
                    sab += la[j] * lb[j];
                    n += 1.0;
                }
            }
            let (ma, mb) = (sa / n, sb / n);
            let va = (saa / n - ma * ma).max(0.0);
            let vb = (sbb / n - mb * mb).max(0.0);
            let cov = sab / n - ma * mb;
            total += ((2.0 * ma * mb + c1) * (2.0 * cov + c2))
                / ((ma * ma + mb * mb + c1) * (va + vb + c2));
            count += 1;
        }
    }
    total / count.max(1) as f64
}

/// `target/test-output/`, created on demand.
pub fn output_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/test-output");
    let _ = std::fs::create_dir_all(&dir);
    dir
}

/// Writes a little-endian colour PFM (bottom row first).
pub fn write_pfm(path: &std::path::Path, img: &Image) -> std::io::Result<()> {
    let mut bytes = format!("PF\n{} {}\n-1.0\n", img.width, img.height).into_bytes();
    for y in (0..img.height).rev() {
        for x in 0..img.width {
            for v in img.get(x, y).to_array() {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    std::fs::write(path, bytes)
}

/// A texture map holding "checker": 64×64 texels in 4×4-texel squares of albedo 0.1 and 0.8
/// (texture edges for the direct light's edge test and the upsampling's albedo ratio).
pub fn checker_textures() -> gi_core::scene::TextureMap {
    const SIZE: u32 = 64;
    let texels: Vec<f32> = (0..SIZE * SIZE)
        .flat_map(|i| {
            let (x, y) = (i % SIZE / 4, i / SIZE / 4);
            let a = if (x + y) % 2 == 0 { 0.1 } else { 0.8 };
            [a, a, a, 1.0]
        })
        .collect();
    let texture = gi_core::texture::Texture::new(SIZE, SIZE, &texels).expect("checker texture");
    [("checker".to_string(), std::sync::Arc::new(texture))]
        .into_iter()
        .collect()
}

/// A built-in scene.
pub fn load(name: &str) -> Scene {
    builtin::load(name).expect("built-in scene")
}

/// The mean pixel of `img`, per channel.
pub fn mean(img: &Image) -> DVec3 {
    img.pixels.iter().map(|p| p.as_dvec3()).sum::<DVec3>() / img.pixels.len() as f64
}

/// Means of the `block`×`block` pixel blocks.
pub fn block_means(img: &Image, block: u32) -> Vec<DVec3> {
    let (bw, bh) = (img.width / block, img.height / block);
    let mut out = vec![DVec3::ZERO; (bw * bh) as usize];
    for y in 0..bh * block {
        for x in 0..bw * block {
            out[((y / block) * bw + x / block) as usize] +=
                img.get(x, y).as_dvec3() / (block * block) as f64;
        }
    }
    out
}

/// `scene` rendered with `s`.
pub fn run(scene: &Scene, s: &gi_core::RenderOptions) -> RenderOutput {
    render(scene, s, &Silent).expect("render")
}

/// Largest per-pixel difference of `a` and `b` relative to `scale`.
pub fn max_difference(a: &Image, b: &Image, scale: f32) -> f32 {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (*p - *q).abs().max_element() / scale)
        .fold(0.0, f32::max)
}

/// Pixels with any light.
pub fn lit_pixels(img: &Image) -> usize {
    img.pixels.iter().filter(|p| p.max_element() > 0.0).count()
}

/// A spot light over a glossy floor, a wall, a metal box of roughness `metal_roughness` and
/// a glossy ball of `subdivisions` (the BSDF's specular lobes lit by a spot).
pub fn spot_scene(name: &str, metal_roughness: f32, subdivisions: u32) -> Scene {
    let json = format!(
        r#"{{
  "camera": {{ "position": [0, 1.6, 3.6], "look_at": [0, 0.35, 0], "fov": 45, "width": 64, "height": 64 }},
  "lights": [
    {{ "type": "spot", "position": [0.3, 2.6, 1.2], "direction": [-0.15, -1, -0.45],
      "intensity": [20, 18, 15], "inner_angle": 20, "outer_angle": 38 }}
  ],
  "materials": {{
    "floor": {{ "diffuse": [0.7, 0.7, 0.7], "specular": [0.04, 0.04, 0.04], "roughness": 0.5, "fresnel": true }},
    "wall": {{ "diffuse": [0.6, 0.55, 0.5] }},
    "ball": {{ "diffuse": [0.2, 0.35, 0.6], "specular": [0.05, 0.05, 0.05], "roughness": 0.3, "fresnel": true }},
    "metal": {{ "specular": [0.9, 0.7, 0.4], "roughness": {metal_roughness} }}
  }},
  "objects": [
    {{ "shape": {{ "type": "quad", "size": [4, 4] }}, "material": "floor" }},
    {{ "shape": {{ "type": "quad", "size": [4, 3] }}, "transform": {{ "rotate": [90, 0, 0], "translate": [0, 1.5, -1.5] }},
      "material": "wall" }},
    {{ "shape": {{ "type": "box", "size": [0.5, 0.7, 0.5] }}, "transform": {{ "rotate": [0, 30, 0], "translate": [-0.6, 0.35, -0.2] }},
      "material": "metal" }},
    {{ "shape": {{ "type": "sphere", "radius": 0.4, "subdivisions": {subdivisions} }}, "transform": {{ "translate": [0.5, 0.4, 0.2] }},
      "material": "ball" }}
  ]
}}"#
    );
    Scene::from_json(&json, name, &std::collections::HashMap::new()).expect("valid scene")
}

/// The area-lit Cornell box (2 m, a 0.5 m lamp of radiance 12 under the ceiling) seen from
/// the front at `size`², as scene JSON, with `lights` (a JSON list's items), and `materials`
/// and `objects` added to its own (JSON object members and list items, or empty).
pub fn area_lit_box(size: u32, lights: &str, materials: &str, objects: &str) -> String {
    let (comma_m, comma_o) = (
        if materials.is_empty() { "" } else { "," },
        if objects.is_empty() { "" } else { "," },
    );
    format!(
        r#"{{
        "camera": {{"position": [0, 1, 3.4], "look_at": [0, 1, 0], "fov": 40,
                    "width": {size}, "height": {size}}},
        "lights": [{lights}],
        "materials": {{
            "white": {{"diffuse": [0.73, 0.73, 0.73]}},
            "red": {{"diffuse": [0.63, 0.065, 0.05]}},
            "green": {{"diffuse": [0.14, 0.45, 0.091]}},
            "lamp": {{"diffuse": [0.5, 0.5, 0.5], "emission": [12, 12, 12]}}{comma_m}
            {materials}
        }},
        "objects": [
            {{"shape": {{"type": "quad", "size": [2, 2]}}, "material": "white"}},
            {{"shape": {{"type": "quad", "size": [2, 2]}}, "material": "white",
              "transform": {{"rotate": [180, 0, 0], "translate": [0, 2, 0]}}}},
            {{"shape": {{"type": "quad", "size": [2, 2]}}, "material": "white",
              "transform": {{"rotate": [90, 0, 0], "translate": [0, 1, -1]}}}},
            {{"shape": {{"type": "quad", "size": [2, 2]}}, "material": "red",
              "transform": {{"rotate": [0, 0, -90], "translate": [-1, 1, 0]}}}},
            {{"shape": {{"type": "quad", "size": [2, 2]}}, "material": "green",
              "transform": {{"rotate": [0, 0, 90], "translate": [1, 1, 0]}}}},
            {{"shape": {{"type": "quad", "size": [0.5, 0.5]}}, "material": "lamp",
              "transform": {{"rotate": [180, 0, 0], "translate": [0, 1.98, 0]}}}}{comma_o}
            {objects}
        ]
    }}"#
    )
}
