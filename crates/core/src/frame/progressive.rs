//! Progressive mode: probabilistic progressive photon mapping (Knaus & Zwicker 2011).
//!
//! Each frame of a progressive [`Renderer`](super::Renderer) is a pass: an independent
//! estimate of the whole image with fresh random numbers (photons, bounce-map jitter,
//! sub-pixel positions, light samples), whose photon kernels are all scaled by a global
//! radius factor rᵢ that shrinks as r²ᵢ₊₁ = r²ᵢ (i + α)/(i + 1). The image is the running
//! mean of the passes. Knaus and Zwicker show that the mean of such passes is consistent
//! (variance and bias both vanish) without per-pixel statistics, which is why this fits
//! ISPM's per-photon splat kernels: a pass needs no knowledge of the previous ones, so the
//! GPU estimators stay as they are and only the per-photon radius on the CPU changes.

use crate::image::Image;
use crate::render::{progressive_radius_scale, Settings};
use glam::{DVec3, Vec2};

/// The running sum of the passes since the last change of scene, camera or size.
pub(super) struct Accumulation {
    pub passes: u64,
    sum: Vec<DVec3>,
    width: u32,
    height: u32,
}

impl Accumulation {
    pub fn new(like: &Image) -> Self {
        Accumulation {
            passes: 0,
            sum: vec![DVec3::ZERO; like.pixels.len()],
            width: like.width,
            height: like.height,
        }
    }

    /// Adds a pass and returns the mean so far.
    pub fn add(&mut self, pass: &Image) -> Image {
        if (pass.width, pass.height) != (self.width, self.height) {
            *self = Accumulation::new(pass);
        }
        for (s, p) in self.sum.iter_mut().zip(&pass.pixels) {
            // A non-finite sample would poison the mean for good: it counts as zero (the
            // methods don't produce them; this only guards the accumulation).
            if p.is_finite() {
                *s += p.as_dvec3();
            }
        }
        self.passes += 1;
        let n = self.passes as f64;
        let mut mean = Image::new(self.width, self.height);
        for (m, s) in mean.pixels.iter_mut().zip(&self.sum) {
            *m = (*s / n).as_vec3();
        }
        mean
    }
}

/// SplitMix64 finalizer.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The settings of progressive pass `pass` (0-based): the base seed (`seed`, else the
/// settings') for the first pass, then a new one per pass, and the kernel radius scale of
/// the pass times the settings' own.
pub(super) fn pass_settings(settings: &Settings, seed: Option<u64>, pass: u64) -> Settings {
    let base = seed.unwrap_or(settings.seed);
    Settings {
        seed: if pass == 0 {
            base
        } else {
            base ^ mix(pass.wrapping_add(0x5851_F42D_4C95_7F2D))
        },
        radius_scale: settings.radius_scale
            * progressive_radius_scale(pass, settings.progressive_alpha),
        ..settings.clone()
    }
}

/// The sub-pixel offset of the GPU methods' sample positions in pass `pass` (a
/// Cranley–Patterson rotation, new per pass; zero outside progressive mode and in the first
/// pass, so that pass is the ordinary frame).
pub(super) fn sample_offset(settings: &Settings, pass: u64) -> Vec2 {
    if !settings.progressive || pass == 0 {
        return Vec2::ZERO;
    }
    let h = mix(settings.seed ^ mix(pass));
    Vec2::new(
        (h >> 40) as f32 / (1u64 << 24) as f32,
        ((h >> 16) & 0xFF_FFFF) as f32 / (1u64 << 24) as f32,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_sequence_follows_knaus_zwicker() {
        // r²₂ = r²₁ (1 + α)/2, r²₃ = r²₂ (2 + α)/3.
        let a = 0.7f32;
        let s1 = progressive_radius_scale(1, a);
        let s2 = progressive_radius_scale(2, a);
        assert!((s1 * s1 - 0.85).abs() < 1e-6);
        assert!((s2 * s2 - 0.85 * 2.7 / 3.0).abs() < 1e-6);
        assert_eq!(progressive_radius_scale(0, a), 1.0);
        // r²ᵢ ~ i^(α−1): at pass 1000 between 0.1 and 0.2 of the first for α = 0.7.
        let s = progressive_radius_scale(1000, a);
        assert!(s * s > 0.1 && s * s < 0.2, "{}", s * s);
    }

    #[test]
    fn running_mean_and_seeds() {
        let mut img = Image::new(2, 1);
        img.pixels[0] = glam::Vec3::splat(1.0);
        let mut acc = Accumulation::new(&img);
        acc.add(&img);
        img.pixels[0] = glam::Vec3::splat(3.0);
        img.pixels[1] = glam::Vec3::splat(f32::NAN);
        let m = acc.add(&img);
        assert_eq!(m.pixels[0], glam::Vec3::splat(2.0));
        assert_eq!(m.pixels[1], glam::Vec3::ZERO);
        let s = Settings {
            progressive: true,
            ..Settings::default()
        };
        let seeds: std::collections::HashSet<u64> =
            (0..100).map(|p| pass_settings(&s, None, p).seed).collect();
        assert_eq!(seeds.len(), 100);
        assert_eq!(sample_offset(&s, 0), Vec2::ZERO);
        let o = sample_offset(&s, 3);
        assert!(o.x >= 0.0 && o.x < 1.0 && o.y >= 0.0 && o.y < 1.0 && o != Vec2::ZERO);
    }
}
