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
}
