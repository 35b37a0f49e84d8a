//! The cone of directions each sampled sky direction stands for, whose shadow-map
//! visibility the direct light averages in ordinary frames (`shaders/common/sky_cone.wgsl`:
//! soft light through openings instead of one hard patch per direction).

/// Widest cone half-angle (45°): a direction drawn where the sky's density is low stands for
/// a large solid angle, whose disc would reach across most of the map.
const MAX_TAN: f32 = 1.0;

/// tan α of the cone of solid angle `solid_angle` (sr): 2π(1 − cos α) = Ω, capped at 45°
/// (0 for no solid angle).
pub fn tan_half_angle(solid_angle: f32) -> f32 {
    if solid_angle.is_nan() || solid_angle <= 0.0 {
        return 0.0;
    }
    let cos = (1.0 - solid_angle / std::f32::consts::TAU).max(0.0);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    (sin / cos.max(1e-6)).min(MAX_TAN)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    /// 16 uniform directions stand for π/4 sr each: a cap of half-angle acos(7/8) ≈ 28.96°.
    #[test]
    fn sixteen_uniform_directions_stand_for_29_degree_cones() {
        let t = tan_half_angle(4.0 * PI / 16.0);
        assert!(
            (t.atan().to_degrees() - 28.955).abs() < 0.01,
            "{}",
            t.atan().to_degrees()
        );
        assert_eq!(tan_half_angle(0.0), 0.0);
        assert_eq!(tan_half_angle(f32::NAN), 0.0);
        assert_eq!(tan_half_angle(4.0 * PI), MAX_TAN);
        // A small cone: Ω ≈ πα².
        let a = 0.01f32;
        assert!((tan_half_angle(PI * a * a) - a).abs() < 1e-5);
    }
}
