//! Footprint ellipsoids of photon hits (Fabianowski & Dingliana 2009, fig. 1): two skewed
//! semi-axes in the surface plane and a thin extent along the normal, so that query points
//! on nearby surfaces cut an ellipse through it.

use super::lbvh::Aabb;
use super::Kernel;
use glam::{Mat3, Vec3};

/// A photon's footprint ellipsoid.
#[derive(Clone, Copy, Debug)]
pub struct Footprint {
    pub centre: Vec3,
    /// Maps world offsets to ellipsoid coordinates (α, β, γ): inside iff α² + β² + γ² ≤ 1.
    to_local: Mat3,
    /// Area of the footprint ellipse, π·|a₁ × a₂| (m²).
    pub area: f32,
    pub bounds: Aabb,
}

impl Footprint {
    /// From semi-axes `a` (in the surface plane, possibly skewed), the unit `normal` and
    /// the half-thickness along it (a fraction of the smaller axis is a good choice).
    /// `None` for a degenerate footprint.
    pub fn new(centre: Vec3, a: [Vec3; 2], normal: Vec3, half_thickness: f32) -> Option<Self> {
        let h = normal * half_thickness;
        let m = Mat3::from_cols(a[0], a[1], h);
        let det = m.determinant();
        if !det.is_finite() || det.abs() < 1e-30 {
            return None;
        }
        let to_local = m.inverse();
        let area = std::f32::consts::PI * a[0].cross(a[1]).length();
        // The ellipsoid's extent along each world axis: the length of the matrix row.
        let ext = Vec3::new(m.row(0).length(), m.row(1).length(), m.row(2).length());
        Some(Footprint {
            centre,
            to_local,
            area,
            bounds: Aabb {
                min: centre - ext,
                max: centre + ext,
            },
        })
    }

    /// Kernel weight (1/m²) of this footprint at `p`, or `None` outside it: the disc
    /// kernel stretched over the ellipse, so it still integrates to 1 over the footprint.
    #[inline]
    pub fn weight(&self, p: Vec3, kernel: Kernel) -> Option<f32> {
        let l = self.to_local * (p - self.centre);
        let planar = l.x * l.x + l.y * l.y;
        if planar + l.z * l.z > 1.0 {
            return None;
        }
        Some(kernel.weight(planar, 1.0) * std::f32::consts::PI / self.area)
    }
}

/// The automatic leaf-size threshold (§5.3): proportional to the number of footprints
/// expected to overlap a query point, Σ footprint areas / total scene surface area.
pub fn t_auto(footprint_area_sum: f64, scene_area: f64, scale: f64) -> usize {
    if scene_area <= 0.0 {
        return 1;
    }
    ((scale * footprint_area_sum / scene_area).round() as usize).clamp(1, 256)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// Both kernels integrate to 1 over the (skewed) footprint ellipse, and the box bounds it.
    #[test]
    fn kernels_are_normalised_and_bounded() {
        let a = [Vec3::new(0.3, 0.0, 0.1), Vec3::new(0.1, 0.0, 0.2)];
        let f = Footprint::new(Vec3::new(1.0, 2.0, 3.0), a, Vec3::Y, 0.01).unwrap();
        let mut rng = Rng::new(4, 0, 0);
        let n = 400_000;
        let (x0, x1, z0, z1) = (
            f.bounds.min.x,
            f.bounds.max.x,
            f.bounds.min.z,
            f.bounds.max.z,
        );
        let area = (x1 - x0) * (z1 - z0);
        for &kernel in Kernel::ALL {
            let mut sum = 0.0f64;
            for _ in 0..n {
                let p = Vec3::new(
                    x0 + rng.next_f32() * (x1 - x0),
                    2.0,
                    z0 + rng.next_f32() * (z1 - z0),
                );
                if let Some(w) = f.weight(p, kernel) {
                    assert!(f.bounds.contains(p));
                    sum += w as f64;
                }
            }
            let integral = sum * area as f64 / n as f64;
            // Uniform sampling of the bounding rectangle: standard error ≈ 0.2%.
            assert!((integral - 1.0).abs() < 0.01, "{kernel:?}: {integral}");
        }
        assert!(
            f.weight(Vec3::new(1.0, 2.05, 3.0), Kernel::Box).is_none(),
            "too far off the surface"
        );
    }
}
