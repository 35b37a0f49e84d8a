//! Image comparison helpers for the GPU golden tests: luminance SSIM, an edge mask, PFM output.
// Each test binary uses its own subset of these helpers.
#![allow(dead_code)]

use gi_core::{Image, RenderOutput};
use glam::Vec3;
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
                let mean = (lum[a] + lum[b] + lum[i]) / 3.0;
                e |= (lum[a] + lum[b] - 2.0 * lum[i]).abs() > 0.1 * mean;
            }
            edge[i] = e;
        }
    }
    // Dilate.
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
