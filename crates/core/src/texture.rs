//! Textures: linear RGBA images with a box-filtered mip chain, and the one lookup that every
//! method uses (repeat wrap, bilinear within a level, linear between levels).
//!
//! The GPU passes read the same texels from an atlas (`raster/textures.rs`) with the same
//! arithmetic in WGSL (`shaders/common/texture.wgsl`), so the G-buffer, the bounce maps,
//! the photon tracer and the path tracer see the same material. Texels are stored rounded to
//! `f16` here as on the GPU (`Rgba16Float`), so both hold identical values.
//!
//! Conventions: texel rows run from the top of the image down and `uv = (0, 0)` is the
//! image's top-left corner (glTF's convention; OBJ's `vt` is flipped by the loader). Level
//! `l` is `max(1, w >> l) × max(1, h >> l)`; each of its texels is the area-weighted mean
//! of the texels of level `l - 1` it covers (a box filter, exact for odd sizes too).

use glam::{Vec2, Vec4};

/// Largest width or height kept: larger images lose their finest levels (a 8192² image is
/// used at 4096²), so one atlas page of the GPU holds any texture.
pub const MAX_TEXTURE_SIZE: u32 = 4096;

/// One level of the mip chain.
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    pub width: u32,
    pub height: u32,
    /// Row-major, top row first.
    pub texels: Vec<Vec4>,
}

/// A texture: its mip chain, finest level first, down to 1×1.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub levels: Vec<Level>,
}

/// `x` rounded to the nearest `f16` (what an `Rgba16Float` texel holds).
pub fn round_f16(x: f32) -> f32 {
    half::f16::from_f32(x).to_f32()
}

/// WGSL's `mix`: `a·(1 - t) + b·t`.
#[inline]
fn mix(a: Vec4, b: Vec4, t: f32) -> Vec4 {
    a * (1.0 - t) + b * t
}

/// Repeat wrap of a texel index into `0..n`.
#[inline]
fn wrap(i: i32, n: u32) -> u32 {
    i.rem_euclid(n as i32) as u32
}

impl Level {
    #[inline]
    fn texel(&self, x: i32, y: i32) -> Vec4 {
        let (x, y) = (wrap(x, self.width), wrap(y, self.height));
        self.texels[(y * self.width + x) as usize]
    }

    /// Bilinear lookup with repeat wrap; texel centres at half-integer positions.
    pub fn bilinear(&self, uv: Vec2) -> Vec4 {
        let f = uv - uv.floor();
        let p = f * Vec2::new(self.width as f32, self.height as f32) - 0.5;
        let p0 = p.floor();
        let t = p - p0;
        let (x, y) = (p0.x as i32, p0.y as i32);
        let top = mix(self.texel(x, y), self.texel(x + 1, y), t.x);
        let bottom = mix(self.texel(x, y + 1), self.texel(x + 1, y + 1), t.x);
        mix(top, bottom, t.y)
    }

    /// The next coarser level: area-weighted box filter.
    fn downsample(&self) -> Level {
        let (w, h) = ((self.width / 2).max(1), (self.height / 2).max(1));
        let wx = weights(self.width, w);
        let wy = weights(self.height, h);
        let mut texels = Vec::with_capacity((w * h) as usize);
        for row in &wy {
            for col in &wx {
                let mut sum = Vec4::ZERO;
                for &(sy, fy) in row {
                    for &(sx, fx) in col {
                        sum += self.texels[(sy * self.width + sx) as usize] * (fx * fy);
                    }
                }
                texels.push(sum);
            }
        }
        Level {
            width: w,
            height: h,
            texels,
        }
    }
}

/// Per destination texel of a `dst`-wide row, the source texels of an `src`-wide row it
/// covers and their weights (overlap lengths over the destination texel's width).
fn weights(src: u32, dst: u32) -> Vec<Vec<(u32, f32)>> {
    let scale = src as f64 / dst as f64;
    (0..dst)
        .map(|d| {
            let (lo, hi) = (d as f64 * scale, (d + 1) as f64 * scale);
            let mut out = Vec::new();
            let mut s = lo.floor() as u32;
            while (s as f64) < hi && s < src {
                let overlap = (hi.min(s as f64 + 1.0) - lo.max(s as f64)).max(0.0);
                if overlap > 0.0 {
                    out.push((s, (overlap / scale) as f32));
                }
                s += 1;
            }
            out
        })
        .collect()
}

impl Texture {
    /// A texture from `width × height` RGBA texels (row-major, top row first), each channel
    /// clamped to [0, 1] (reflectances, roughness, coverage and encoded normals all live
    /// there). Errors name what is wrong.
    pub fn new(width: u32, height: u32, rgba: &[f32]) -> Result<Texture, String> {
        if width == 0 || height == 0 {
            return Err("texture is empty".into());
        }
        if rgba.len() != width as usize * height as usize * 4 {
            return Err(format!(
                "texture data has {} values, expected {width}×{height}×4",
                rgba.len()
            ));
        }
        if let Some(i) = rgba.iter().position(|x| !x.is_finite()) {
            return Err(format!("texel {} is not finite", i / 4));
        }
        let texels = rgba
            .chunks_exact(4)
            .map(|c| Vec4::from_slice(c).clamp(Vec4::ZERO, Vec4::ONE))
            .collect();
        let mut levels = vec![Level {
            width,
            height,
            texels,
        }];
        while levels.last().is_some_and(|l| l.width > 1 || l.height > 1) {
            let next = levels.last().map(Level::downsample).expect("non-empty");
            levels.push(next);
        }
        let keep = levels
            .iter()
            .position(|l| l.width.max(l.height) <= MAX_TEXTURE_SIZE)
            .unwrap_or(levels.len() - 1);
        levels.drain(..keep);
        for l in &mut levels {
            for t in &mut l.texels {
                *t = Vec4::from_array(t.to_array().map(round_f16));
            }
        }
        Ok(Texture { levels })
    }

    pub fn width(&self) -> u32 {
        self.levels[0].width
    }
    pub fn height(&self) -> u32 {
        self.levels[0].height
    }

    /// Trilinear lookup at an explicit level of detail (0 = finest; clamped to the chain).
    pub fn sample(&self, uv: Vec2, lod: f32) -> Vec4 {
        let top = (self.levels.len() - 1) as f32;
        let l = if lod.is_finite() {
            lod.clamp(0.0, top)
        } else {
            0.0
        };
        let l0 = l.floor();
        let f = l - l0;
        let a = self.levels[l0 as usize].bilinear(uv);
        if f > 0.0 {
            mix(a, self.levels[l0 as usize + 1].bilinear(uv), f)
        } else {
            a
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tex(w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 4]) -> Texture {
        let data: Vec<f32> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .flat_map(|(x, y)| f(x, y))
            .collect();
        Texture::new(w, h, &data).unwrap()
    }

    #[test]
    fn texel_centres_are_exact_and_wrap_repeats() {
        let t = tex(4, 2, |x, y| [x as f32 / 4.0, y as f32 / 2.0, 0.25, 1.0]);
        for y in 0..2u32 {
            for x in 0..4u32 {
                let uv = Vec2::new((x as f32 + 0.5) / 4.0, (y as f32 + 0.5) / 2.0);
                let want = Vec4::new(x as f32 / 4.0, y as f32 / 2.0, 0.25, 1.0);
                assert_eq!(t.sample(uv, 0.0), want);
                // Whole periods away, negative too: the same texel.
                for k in [-3.0, -1.0, 1.0, 7.0] {
                    let d = (t.sample(uv + Vec2::splat(k), 0.0) - want)
                        .abs()
                        .max_element();
                    assert!(d < 1e-5, "{uv} + {k}: {d}");
                }
            }
        }
        // Halfway between the last and the first column: the mean of both (repeat wrap).
        let edge = t.sample(Vec2::new(0.0, 0.25), 0.0);
        assert!((edge.x - (0.75 + 0.0) / 2.0).abs() < 1e-6, "{edge}");
    }

    #[test]
    fn bilinear_weights() {
        let t = tex(2, 2, |x, y| [x as f32, y as f32, (x * y) as f32, 1.0]);
        // A quarter texel right of the first centre and a half texel down.
        let v = t.sample(Vec2::new(0.25 + 0.125, 0.25 + 0.25), 0.0);
        assert!((v.x - 0.25).abs() < 1e-6, "{v}");
        assert!((v.y - 0.5).abs() < 1e-6, "{v}");
        assert!((v.z - 0.125).abs() < 1e-6, "{v}");
    }

    #[test]
    fn mip_chain_is_a_box_filter() {
        // 4×4 checker of 1×1 cells: level 1 is uniform 0.5, level 2 too.
        let t = tex(4, 4, |x, y| {
            let c = ((x + y) % 2) as f32;
            [c, c, c, 1.0]
        });
        assert_eq!(t.levels.len(), 3);
        assert!(t.levels[1].texels.iter().all(|v| (v.x - 0.5).abs() < 1e-3));
        // Odd sizes: 3×1 → 1×1 is the mean of all three.
        let t = tex(3, 1, |x, _| [x as f32 / 2.0, 0.0, 0.0, 1.0]);
        assert_eq!(t.levels.len(), 2);
        assert!((t.levels[1].texels[0].x - 0.5).abs() < 1e-3);
        // 5 wide → 2: texel 0 covers source 0, 1 and half of 2.
        let t = tex(5, 1, |x, _| [if x == 2 { 1.0 } else { 0.0 }, 0.0, 0.0, 1.0]);
        let l1 = &t.levels[1];
        assert_eq!(l1.width, 2);
        assert!((l1.texels[0].x - 0.2).abs() < 1e-3, "{:?}", l1.texels);
        assert!((l1.texels[1].x - 0.2).abs() < 1e-3, "{:?}", l1.texels);
        // Every level keeps the mean.
        let t = tex(7, 5, |x, y| {
            [((x * 3 + y * 5) % 7) as f32 / 6.0, 0.0, 0.0, 1.0]
        });
        let mean =
            |l: &Level| l.texels.iter().map(|v| v.x as f64).sum::<f64>() / l.texels.len() as f64;
        let m0 = mean(&t.levels[0]);
        for l in &t.levels {
            assert!((mean(l) - m0).abs() < 2e-3, "{} vs {m0}", mean(l));
        }
    }

    #[test]
    fn lod_blends_levels_and_clamps() {
        let t = tex(2, 2, |x, y| {
            let c = ((x + y) % 2) as f32;
            [c, c, c, 1.0]
        });
        let uv = Vec2::new(0.25, 0.25);
        assert_eq!(t.sample(uv, 0.0).x, 0.0);
        assert_eq!(t.sample(uv, 1.0).x, 0.5);
        assert!((t.sample(uv, 0.5).x - 0.25).abs() < 1e-6);
        assert_eq!(t.sample(uv, 9.0).x, 0.5);
        assert_eq!(t.sample(uv, -3.0).x, 0.0);
        assert_eq!(t.sample(uv, f32::NAN).x, 0.0);
    }

    #[test]
    fn values_are_clamped_rounded_and_checked() {
        let t = Texture::new(1, 1, &[2.0, -1.0, 0.1, 1.0]).unwrap();
        assert_eq!(
            t.levels[0].texels[0],
            Vec4::new(1.0, 0.0, round_f16(0.1), 1.0)
        );
        assert!(Texture::new(1, 1, &[f32::NAN, 0.0, 0.0, 1.0]).is_err());
        assert!(Texture::new(2, 1, &[0.0; 4]).is_err());
        assert!(Texture::new(0, 1, &[]).is_err());
    }
}
