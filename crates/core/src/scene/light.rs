//! The analytic lights: point, spot and directional (the sun). Area lights are emissive
//! surfaces (`scene::emitters`), the sky is the environment (`scene::environment`).

use crate::sampling::{uniform_cone, uniform_sphere, Frame, Rng};
use glam::Vec3;
use std::f32::consts::PI;

/// A light source; point and spot intensity in W/sr per channel, directional irradiance in
/// W/m² per channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Isotropic point light; emitted power 4π·I.
    Point { position: Vec3, intensity: Vec3 },
    /// Spot light: full intensity inside `cos_inner`, smooth falloff to zero at `cos_outer`.
    Spot {
        position: Vec3,
        direction: Vec3,
        intensity: Vec3,
        cos_inner: f32,
        cos_outer: f32,
    },
    /// A distant light (the sun): light travelling along the unit `direction` with
    /// `irradiance` on a surface facing it, from a disc of directions of half-angle
    /// acos(`cos_half_angle`) around it (1: parallel light).
    Directional {
        direction: Vec3,
        irradiance: Vec3,
        cos_half_angle: f32,
    },
}

/// The bounding sphere of a scene: where a distant light's photons enter it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub centre: Vec3,
    pub radius: f32,
}

/// An emitted photon: origin, direction and power (W).
#[derive(Clone, Copy, Debug)]
pub struct Emission {
    pub origin: Vec3,
    pub direction: Vec3,
    pub power: Vec3,
}

impl Light {
    /// Where a point or spot light is; a directional light has no position (the origin).
    pub fn position(&self) -> Vec3 {
        match *self {
            Light::Point { position, .. } | Light::Spot { position, .. } => position,
            Light::Directional { .. } => Vec3::ZERO,
        }
    }

    /// Whether the light is at a finite position (point, spot).
    pub fn is_local(&self) -> bool {
        !matches!(self, Light::Directional { .. })
    }

    /// Intensity on the axis (W/sr per channel).
    pub fn intensity(&self) -> Vec3 {
        match *self {
            Light::Point { intensity, .. } | Light::Spot { intensity, .. } => intensity,
            Light::Directional { irradiance, .. } => irradiance,
        }
    }

    /// The share of the on-axis intensity emitted at cosine `cos` from the axis: 1 for a
    /// point light, the spot falloff for a spot light.
    pub fn falloff(&self, cos: f32) -> f32 {
        match *self {
            Light::Point { .. } => 1.0,
            Light::Spot {
                cos_inner,
                cos_outer,
                ..
            } => spot_falloff(cos, cos_inner, cos_outer),
            Light::Directional { .. } => 1.0,
        }
    }

    /// Radiant intensity (W/sr) emitted in unit direction `dir`.
    pub fn intensity_towards(&self, dir: Vec3) -> Vec3 {
        match *self {
            Light::Point { intensity, .. } => intensity,
            Light::Spot {
                direction,
                intensity,
                cos_inner,
                cos_outer,
                ..
            } => intensity * spot_falloff(dir.dot(direction), cos_inner, cos_outer),
            Light::Directional { .. } => Vec3::ZERO,
        }
    }

    /// Total emitted power (W): ∫ I(ω) dω; for a directional light, the power that crosses
    /// the scene's bounding sphere `bounds` (E·πr²).
    pub fn power(&self, bounds: Bounds) -> Vec3 {
        match *self {
            Light::Point { intensity, .. } => 4.0 * PI * intensity,
            Light::Spot {
                intensity,
                cos_inner,
                cos_outer,
                ..
            } => {
                // ∫ falloff dω = 2π ∫ s(c) dc; smoothstep integrates to half its span.
                intensity * 2.0 * PI * ((1.0 - cos_inner) + 0.5 * (cos_inner - cos_outer))
            }
            Light::Directional { irradiance, .. } => {
                irradiance * (PI * bounds.radius * bounds.radius * self.disc_flux_factor())
            }
        }
    }

    /// A directional light's flux through a disc facing it over E·area: Ω/(π sin²α) =
    /// 2/(1 + cos α) for a disc of directions of half-angle α of uniform radiance (1 for
    /// parallel light); 1 for the other lights.
    fn disc_flux_factor(&self) -> f32 {
        match *self {
            Light::Directional { cos_half_angle, .. } if cos_half_angle < 1.0 => {
                2.0 / (1.0 + cos_half_angle.max(-1.0))
            }
            _ => 1.0,
        }
    }

    /// The radiance (W·sr⁻¹·m⁻² per channel) of a directional light's disc of directions:
    /// L = E/(π sin²α), so that a surface facing it receives the irradiance E. `None` for
    /// parallel light (a delta in direction, reached by next-event estimation alone) and
    /// the other lights.
    pub fn disc_radiance(&self) -> Option<Vec3> {
        match *self {
            Light::Directional {
                irradiance,
                cos_half_angle,
                ..
            } if cos_half_angle < 1.0 => {
                let c = cos_half_angle.max(-1.0);
                Some(irradiance / (PI * (1.0 - c * c)))
            }
            _ => None,
        }
    }

    /// The radiance a ray leaving the scene in unit direction `wi` finds on a directional
    /// light's disc (zero outside it, and for the other lights).
    pub fn disc_radiance_from(&self, wi: Vec3) -> Vec3 {
        match (*self, self.disc_radiance()) {
            (
                Light::Directional {
                    direction,
                    cos_half_angle,
                    ..
                },
                Some(l),
            ) if wi.dot(-direction) >= cos_half_angle => l,
            _ => Vec3::ZERO,
        }
    }

    /// The density over solid angle of [`Light::sample_towards`] for a directional light's
    /// disc of directions (0 for parallel light and the other lights).
    pub fn disc_pdf(&self) -> f32 {
        match *self {
            Light::Directional { cos_half_angle, .. } if cos_half_angle < 1.0 => {
                1.0 / (2.0 * PI * (1.0 - cos_half_angle))
            }
            _ => 0.0,
        }
    }

    /// Solid angle (sr) that photons are emitted into (a directional light's: its disc of
    /// directions).
    pub fn solid_angle(&self) -> f32 {
        match *self {
            Light::Point { .. } => 4.0 * PI,
            Light::Spot { cos_outer, .. } => 2.0 * PI * (1.0 - cos_outer),
            Light::Directional { cos_half_angle, .. } => 2.0 * PI * (1.0 - cos_half_angle),
        }
    }

    /// A direction towards the light from anywhere (a directional light: within its disc,
    /// uniformly in solid angle) with its density (sr⁻¹; infinite for parallel light).
    pub fn sample_towards(&self, u: glam::Vec2) -> Option<(Vec3, f32)> {
        let Light::Directional {
            direction,
            cos_half_angle,
            ..
        } = *self
        else {
            return None;
        };
        if cos_half_angle >= 1.0 {
            return Some((-direction, f32::INFINITY));
        }
        let local = uniform_cone(u, cos_half_angle);
        Some((
            Frame::new(-direction).to_world(local),
            1.0 / (2.0 * PI * (1.0 - cos_half_angle)),
        ))
    }

    /// The density over solid angle with which [`Light::emit`] sends a point or spot light's
    /// photon along the unit direction `dir` (uniform over the sphere or the spot's outer
    /// cone); 0 for a directional light, whose photons start on a disc.
    pub fn emit_pdf(&self, dir: Vec3) -> f32 {
        match *self {
            Light::Point { .. } => 1.0 / (4.0 * PI),
            Light::Spot {
                direction,
                cos_outer,
                ..
            } if dir.dot(direction) >= cos_outer => 1.0 / (2.0 * PI * (1.0 - cos_outer)),
            _ => 0.0,
        }
    }

    /// Emits one photon carrying power `power / n` on average when called `n` times; a
    /// directional light's enter the scene through the disc of `bounds` facing it.
    pub fn emit(&self, rng: &mut Rng, bounds: Bounds) -> Emission {
        match *self {
            Light::Point {
                position,
                intensity,
            } => Emission {
                origin: position,
                direction: uniform_sphere(rng.next_2d()),
                power: 4.0 * PI * intensity,
            },
            Light::Spot {
                position,
                direction,
                cos_outer,
                ..
            } => {
                let local = uniform_cone(rng.next_2d(), cos_outer);
                let dir = Frame::new(direction).to_world(local);
                let pdf = 1.0 / (2.0 * PI * (1.0 - cos_outer));
                Emission {
                    origin: position,
                    direction: dir,
                    power: self.intensity_towards(dir) / pdf,
                }
            }
            Light::Directional { .. } => {
                let u_towards = rng.next_2d();
                self.emit_directional(u_towards, rng.next_2d(), bounds)
            }
        }
    }

    /// [`Light::emit`] of a directional light from its two uniform samples: `u_towards`
    /// for the direction within its disc of directions, `u_disc` for the point on the disc
    /// of `bounds` (so that a caller may stratify the points). Other lights: as from the
    /// centre of the disc of directions, power zero.
    pub fn emit_directional(
        &self,
        u_towards: glam::Vec2,
        u_disc: glam::Vec2,
        bounds: Bounds,
    ) -> Emission {
        let Light::Directional {
            irradiance,
            direction,
            ..
        } = *self
        else {
            return Emission {
                origin: bounds.centre,
                direction: Vec3::NEG_Y,
                power: Vec3::ZERO,
            };
        };
        let towards = match self.sample_towards(u_towards) {
            Some((d, _)) => d,
            None => -direction,
        };
        let (origin, area) = bounds.disc_point(towards, u_disc);
        Emission {
            origin,
            direction: -towards,
            power: irradiance * (area * self.disc_flux_factor()),
        }
    }
}

impl Bounds {
    /// A uniformly random point on the disc of the sphere facing direction `towards` (the
    /// disc through the centre, moved out to the sphere's surface on that side), and the
    /// disc's area: where light arriving from `towards` enters the sphere.
    pub fn disc_point(&self, towards: Vec3, u: glam::Vec2) -> (Vec3, f32) {
        let frame = Frame::new(towards);
        let r = self.radius * u.x.sqrt();
        let phi = 2.0 * PI * u.y;
        let local = Vec3::new(r * phi.cos(), r * phi.sin(), self.radius);
        (
            self.centre + frame.to_world(local),
            PI * self.radius * self.radius,
        )
    }
}

/// Spot falloff: smoothstep in cos θ from the outer to the inner cone.
pub fn spot_falloff(cos: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if cos >= cos_inner {
        return 1.0;
    }
    if cos <= cos_outer {
        return 0.0;
    }
    let t = (cos - cos_outer) / (cos_inner - cos_outer);
    t * t * (3.0 - 2.0 * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    const BOUNDS: Bounds = Bounds {
        centre: Vec3::ZERO,
        radius: 2.0,
    };

    /// A directional light's photons carry E·πr² in total, enter the bounding sphere on the
    /// side it faces, and travel along its direction.
    #[test]
    fn directional_photons_cross_the_bounding_disc() {
        let direction = Vec3::new(0.3, -1.0, 0.2).normalize();
        let l = Light::Directional {
            direction,
            irradiance: Vec3::new(1.0, 2.0, 3.0),
            cos_half_angle: 1.0,
        };
        let mut rng = Rng::new(1, 0, 0);
        let n = 10_000;
        let mut sum = Vec3::ZERO;
        for _ in 0..n {
            let e = l.emit(&mut rng, BOUNDS);
            sum += e.power / n as f32;
            assert!((e.direction - direction).length() < 1e-6);
            assert!((e.origin - BOUNDS.centre).dot(-direction) > 1.99);
            // On the disc: within the radius of the axis through the centre. (Each photon
            // carries exactly E·πr²/n: the sum differs by float round-off alone.)
            let off = (e.origin - BOUNDS.centre).reject_from(direction);
            assert!(off.length() <= 2.0 + 1e-4);
        }
        let power = l.power(BOUNDS);
        assert!(
            ((sum - power) / power).abs().max_element() < 1e-3,
            "{sum} vs {power}"
        );
    }

    #[test]
    fn spot_power_matches_emission() {
        let l = Light::Spot {
            position: Vec3::ZERO,
            direction: Vec3::new(0.0, -1.0, 0.0),
            intensity: Vec3::new(1.0, 2.0, 3.0),
            cos_inner: 20f32.to_radians().cos(),
            cos_outer: 35f32.to_radians().cos(),
        };
        let mut rng = Rng::new(0, 0, 0);
        let n = 200_000;
        let mut sum = Vec3::ZERO;
        for _ in 0..n {
            sum += l.emit(&mut rng, BOUNDS).power / n as f32;
        }
        // Mean of bounded samples; the falloff band's variance gives a standard error < 0.3%.
        let power = l.power(BOUNDS);
        assert!(
            ((sum - power) / power).abs().max_element() < 0.01,
            "{sum} vs {power}"
        );
    }
}
