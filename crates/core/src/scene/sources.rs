//! Every source of light of a scene, drawn by power: the analytic lights (point, spot,
//! directional), the emitting triangles together, and the environment. Photons and light
//! paths start here, so that a light's share of them is its share of the power.

use super::emitters::Emitters;
use super::light::{Bounds, Emission};
use super::Scene;
use crate::sampling::{AliasTable, Rng};
use glam::Vec3;

/// One source of light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// `scene.lights[i]`.
    Light(usize),
    /// The emitting triangles (area lights), together.
    Emitters,
    /// The environment (sky).
    Environment,
}

/// The sources of a scene and their powers.
#[derive(Clone, Debug)]
pub struct Sources {
    pub emitters: Emitters,
    pub bounds: Bounds,
    /// The sources that emit, with their power (W per channel).
    pub list: Vec<(Source, Vec3)>,
    alias: Option<AliasTable>,
}

/// How the photons of a source spread, where photon differentials start from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spread {
    /// From a point into `solid_angle` steradians (point and spot lights): n photons are
    /// √(Ω/n) radians apart.
    Angular { solid_angle: f32 },
    /// From a surface, `area` m² per photon drawn from the source (n photons: √(area/n)
    /// metres apart) across the plane of `normal`: an area light's surface (directions
    /// cosine-distributed from each point: `diffuse`), or the bounding disc that the sun's
    /// and the sky's photons enter through (directions that do not spread out).
    Area {
        area: f32,
        normal: Vec3,
        diffuse: bool,
    },
}

impl Sources {
    pub fn of(scene: &Scene) -> Sources {
        Sources::filtered(scene, |_| true)
    }

    /// The sources of `scene` that `keep` accepts (e.g. all but the environment, whose
    /// light the path tracer finds by itself).
    pub fn filtered(scene: &Scene, keep: impl Fn(Source) -> bool) -> Sources {
        let bounds = scene.bounds();
        let emitters = if keep(Source::Emitters) {
            Emitters::of(scene)
        } else {
            Emitters::default()
        };
        let mut list = Vec::new();
        for (i, l) in scene.lights.iter().enumerate() {
            list.push((Source::Light(i), l.power(bounds)));
        }
        if !emitters.is_empty() {
            list.push((Source::Emitters, emitters.power()));
        }
        if let Some(env) = scene.environment.as_deref() {
            list.push((Source::Environment, env.power(bounds)));
        }
        list.retain(|(s, p)| p.element_sum() > 0.0 && p.is_finite() && keep(*s));
        let weights: Vec<f32> = list.iter().map(|(_, p)| p.element_sum()).collect();
        Sources {
            alias: AliasTable::new(&weights),
            emitters,
            bounds,
            list,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.alias.is_none()
    }

    /// Total power (W per channel).
    pub fn power(&self) -> Vec3 {
        self.list.iter().map(|(_, p)| *p).sum()
    }

    /// Whether any source has no position (area, distant or environment light): the
    /// rasterized bounce maps and reflective shadow maps see only point and spot lights.
    pub fn has_non_local(&self, scene: &Scene) -> bool {
        self.list.iter().any(|(s, _)| match s {
            Source::Light(i) => !scene.lights[*i].is_local(),
            _ => true,
        })
    }

    /// Emits one photon from a source drawn by power: the source, its probability and the
    /// photon, whose power is the source's over one photon divided by that probability
    /// (divide by the photon count).
    pub fn emit(&self, scene: &Scene, rng: &mut Rng) -> Option<(Source, f32, Emission)> {
        let (i, p) = self.alias.as_ref()?.sample(rng.next_f32());
        let source = self.list[i].0;
        let mut e = self.emit_from(scene, source, rng)?;
        e.power /= p;
        Some((source, p, e))
    }

    /// The probability that [`Sources::emit`] draws `source` (0 if it is not among them).
    pub fn prob(&self, source: Source) -> f32 {
        let (Some(alias), Some(i)) = (
            &self.alias,
            self.list.iter().position(|(s, _)| *s == source),
        ) else {
            return 0.0;
        };
        alias.prob(i)
    }

    /// A source drawn by power from `u` in [0, 1), and its probability.
    pub fn choose(&self, u: f32) -> Option<(Source, f32)> {
        let (i, p) = self.alias.as_ref()?.sample(u);
        Some((self.list[i].0, p))
    }

    /// [`Sources::emit`] with how the source's photons spread (for photon differentials).
    pub fn emit_spread(
        &self,
        scene: &Scene,
        rng: &mut Rng,
    ) -> Option<(Source, f32, Emission, Spread)> {
        let (source, p) = self.choose(rng.next_f32())?;
        let (mut e, spread) = self.emit_spread_from(scene, source, rng)?;
        e.power /= p;
        Some((source, p, e, spread))
    }

    /// One photon of `source` with the source's power over one photon, and how the
    /// source's photons spread.
    pub fn emit_spread_from(
        &self,
        scene: &Scene,
        source: Source,
        rng: &mut Rng,
    ) -> Option<(Emission, Spread)> {
        Some(match source {
            Source::Emitters => {
                let (e, s) = self.emitters.emit_sample(scene, rng)?;
                let spread = Spread::Area {
                    area: 1.0 / s.pdf_area,
                    normal: s.normal,
                    diffuse: true,
                };
                (e, spread)
            }
            Source::Light(l) if scene.lights[l].is_local() => {
                let e = self.emit_from(scene, source, rng)?;
                let solid_angle = scene.lights[l].solid_angle();
                (e, Spread::Angular { solid_angle })
            }
            _ => {
                let e = self.emit_from(scene, source, rng)?;
                let spread = Spread::Area {
                    area: std::f32::consts::PI * self.bounds.radius * self.bounds.radius,
                    normal: e.direction,
                    diffuse: false,
                };
                (e, spread)
            }
        })
    }

    /// Emits one photon from `source`, with the source's power over one photon.
    pub fn emit_from(&self, scene: &Scene, source: Source, rng: &mut Rng) -> Option<Emission> {
        match source {
            Source::Light(i) => Some(scene.lights[i].emit(rng, self.bounds)),
            Source::Emitters => self.emitters.emit(scene, rng),
            Source::Environment => scene.environment.as_deref()?.emit(rng, self.bounds),
        }
    }
}
