//! Pinhole camera.

use glam::Vec3;

/// A pinhole camera; the image plane sits at unit distance along `forward`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit vector to the right of the image.
    pub right: Vec3,
    /// Unit vector to the top of the image.
    pub up: Vec3,
    /// Vertical field of view, degrees.
    pub fov_y: f32,
    pub width: u32,
    pub height: u32,
}

impl Camera {
    pub fn new(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        fov_y: f32,
        width: u32,
        height: u32,
    ) -> Self {
        let forward = (look_at - position).normalize();
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        Camera {
            position,
            forward,
            right,
            up,
            fov_y,
            width,
            height,
        }
    }

    /// The same camera with another image size.
    pub fn with_size(mut self, width: u32, height: u32) -> Self {
        self.width = width;
        self.height = height;
        self
    }

    /// Half-height of the image plane at unit distance.
    pub fn tan_half_fov(&self) -> f32 {
        (self.fov_y.to_radians() * 0.5).tan()
    }

    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }

    /// Area of one pixel on the image plane at unit distance.
    pub fn pixel_area(&self) -> f32 {
        let h = 2.0 * self.tan_half_fov() / self.height as f32;
        h * h
    }

    /// Unit direction through image position (x, y) in pixels, (0, 0) the top-left corner.
    pub fn direction(&self, x: f32, y: f32) -> Vec3 {
        let t = self.tan_half_fov();
        let sx = (2.0 * x / self.width as f32 - 1.0) * t * self.aspect();
        let sy = (1.0 - 2.0 * y / self.height as f32) * t;
        (self.forward + self.right * sx + self.up * sy).normalize()
    }

    /// Projects a world point to continuous pixel coordinates, with the cosine between the
    /// ray and the optical axis. `None` behind the camera or outside the image.
    pub fn project(&self, p: Vec3) -> Option<(f32, f32, f32)> {
        let d = p - self.position;
        let z = d.dot(self.forward);
        if z <= 1e-6 {
            return None;
        }
        let t = self.tan_half_fov();
        let sx = d.dot(self.right) / z / (t * self.aspect());
        let sy = d.dot(self.up) / z / t;
        let x = (sx + 1.0) * 0.5 * self.width as f32;
        let y = (1.0 - sy) * 0.5 * self.height as f32;
        if x < 0.0 || y < 0.0 || x >= self.width as f32 || y >= self.height as f32 {
            return None;
        }
        Some((x, y, z / d.length()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn project_inverts_direction() {
        let c = Camera::new(Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y, 50.0, 64, 48);
        for (x, y) in [(0.5, 0.5), (10.25, 40.0), (63.0, 1.0)] {
            let p = c.position + c.direction(x, y) * 2.5;
            let (px, py, cos) = c.project(p).unwrap();
            assert!((px - x).abs() < 1e-3 && (py - y).abs() < 1e-3);
            assert!((cos - c.direction(x, y).dot(c.forward)).abs() < 1e-5);
        }
    }
}
