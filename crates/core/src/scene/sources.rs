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

impl Sources {
    pub fn of(scene: &Scene) -> Sources {
        let bounds = scene.bounds();
        let emitters = Emitters::of(scene);
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
        list.retain(|(_, p)| p.element_sum() > 0.0 && p.is_finite());
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

    /// Emits one photon from `source`, with the source's power over one photon.
    pub fn emit_from(&self, scene: &Scene, source: Source, rng: &mut Rng) -> Option<Emission> {
        match source {
            Source::Light(i) => Some(scene.lights[i].emit(rng, self.bounds)),
            Source::Emitters => self.emitters.emit(scene, rng),
            Source::Environment => scene.environment.as_deref()?.emit(rng, self.bounds),
        }
    }
}
