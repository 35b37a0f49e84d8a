//! A float RGB image, row-major from the top-left pixel.

use glam::Vec3;

/// Linear RGB image of `f32` triples.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Mean over all pixels.
    pub fn mean(&self) -> Vec3 {
        let sum: glam::DVec3 = self.pixels.iter().map(|p| p.as_dvec3()).sum();
        (sum / self.pixels.len().max(1) as f64).as_vec3()
    }

    /// Root-mean-square difference to `other` (same size) over all pixels and channels.
    pub fn rmse(&self, other: &Image) -> f64 {
        let s: f64 = self
            .pixels
            .iter()
            .zip(&other.pixels)
            .map(|(x, y)| (*x - *y).length_squared() as f64)
            .sum();
        (s / (3 * self.pixels.len().max(1)) as f64).sqrt()
    }

    /// Pixels as a flat `[r, g, b, r, g, b, ...]` slice.
    pub fn as_flat(&self) -> &[f32] {
        bytemuck::cast_slice(&self.pixels)
    }

    /// Rec. 709 luminance of each pixel.
    pub fn luminance(&self) -> Vec<f64> {
        self.pixels
            .iter()
            .map(|p| (0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z) as f64)
            .collect()
    }

    /// PSNR (dB) of `other` against this image as the reference, on luminance, the peak
    /// being this image's largest luminance.
    pub fn psnr(&self, other: &Image) -> f64 {
        let (a, b) = (self.luminance(), other.luminance());
        let peak = a.iter().cloned().fold(0.0, f64::max);
        let mse = a.iter().zip(&b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64;
        10.0 * (peak * peak / mse).log10()
    }

    /// Mean SSIM (Wang et al. 2004) of `other` against this image on luminance, over 8×8
    /// windows with stride 4, the constants scaled by this image's largest luminance.
    pub fn ssim(&self, other: &Image) -> f64 {
        let (a, b) = (self.luminance(), other.luminance());
        let (w, h) = (self.width as usize, self.height as usize);
        let range = a.iter().cloned().fold(0.0, f64::max);
        let (c1, c2) = ((0.01 * range).powi(2), (0.03 * range).powi(2));
        let (mut total, mut windows) = (0.0, 0);
        for y0 in (0..=h.saturating_sub(8)).step_by(4) {
            for x0 in (0..=w.saturating_sub(8)).step_by(4) {
                let idx = |i: usize| (y0 + i / 8) * w + x0 + i % 8;
                let (mut mx, mut my) = (0.0, 0.0);
                for i in 0..64 {
                    mx += a[idx(i)];
                    my += b[idx(i)];
                }
                mx /= 64.0;
                my /= 64.0;
                let (mut vx, mut vy, mut cxy) = (0.0, 0.0, 0.0);
                for i in 0..64 {
                    let (dx, dy) = (a[idx(i)] - mx, b[idx(i)] - my);
                    vx += dx * dx;
                    vy += dy * dy;
                    cxy += dx * dy;
                }
                let (vx, vy, cxy) = (vx / 63.0, vy / 63.0, cxy / 63.0);
                total += ((2.0 * mx * my + c1) * (2.0 * cxy + c2))
                    / ((mx * mx + my * my + c1) * (vx + vy + c2));
                windows += 1;
            }
        }
        total / windows.max(1) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn psnr_and_ssim() {
        let mut a = Image::new(16, 16);
        for (i, p) in a.pixels.iter_mut().enumerate() {
            *p = Vec3::splat((i % 7) as f32 / 7.0 + 0.1);
        }
        assert!((a.ssim(&a) - 1.0).abs() < 1e-12);
        assert!(a.psnr(&a).is_infinite());
        let mut b = a.clone();
        for p in &mut b.pixels {
            *p *= 1.01;
        }
        // Uniform 1% gain: MSE = (0.01·L)² averaged; SSIM barely below 1.
        let p = a.psnr(&b);
        assert!(p > 35.0 && p < 50.0, "{p}");
        let s = a.ssim(&b);
        assert!(s > 0.99 && s < 1.0, "{s}");
        let flat = Image {
            pixels: vec![a.mean(); 256],
            ..a.clone()
        };
        assert!(a.ssim(&flat) < 0.2, "{}", a.ssim(&flat));
    }
}
