//! The ISPM bounce map (section 4.2) traced on the CPU instead of rasterized.
//!
//! The photons are those of the rasterized map (`bounce.wgsl`): per texel of every layer,
//! one photon leaves the light through a uniformly random point of the texel with power
//! I(ω)·A·cos³θ (A: the layer's corrected texel area), its first hit is direct light and is
//! not stored, and it scatters once as in the CPU photon tracer
//! (`photon::trace::scatter`). Only the first hit is found differently: a ray cast in the
//! scene BVH instead of a light-view G-buffer. A CPU rasterizer (lavapipe) sets up every
//! triangle in a light's view whatever the map's resolution, so on dense scenes this costs
//! a fraction of the raster passes (docs/bench/frame.md, session 9).

use super::trace::{scatter, TraceControl};
use super::PhotonRay;
use crate::error::{Error, Result};
use crate::sampling::Rng;
use crate::scene::light_views::{check_layer_memory, LightView, BOUNCE_MAPS};
use crate::scene::Scene;
use crate::trace::{Interaction, SceneBvh};
use glam::{DMat4, DVec3, DVec4};
use rayon::prelude::*;
use std::str::FromStr;

/// Random stream of the traced bounce maps' texels.
const STREAM_BOUNCE: u64 = 0x9407_0003;

/// Where method `ispm` finds the photons' first hits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FirstBounce {
    /// Picked per adapter ([`FirstBounce::resolve`]).
    #[default]
    Auto,
    /// Bounce maps rasterized on the GPU (ISPM section 4.2).
    Raster,
    /// The same photons cast from the lights in the CPU BVH ([`trace_bounce_maps`]).
    Traced,
}

impl FirstBounce {
    pub const ALL: &'static [FirstBounce] =
        &[FirstBounce::Auto, FirstBounce::Raster, FirstBounce::Traced];

    pub fn name(self) -> &'static str {
        match self {
            FirstBounce::Auto => "auto",
            FirstBounce::Raster => "raster",
            FirstBounce::Traced => "traced",
        }
    }

    /// The choice to run on `adapter` and why: an explicit choice stands; `auto` traces on
    /// CPU devices, where rasterizing the scene into every light view costs more than the
    /// casts (docs/bench/frame.md), and rasterizes on GPUs, as ISPM does.
    pub fn resolve(self, adapter: &wgpu::AdapterInfo) -> (FirstBounce, String) {
        match self {
            FirstBounce::Auto if adapter.device_type == wgpu::DeviceType::Cpu => (
                FirstBounce::Traced,
                format!(
                    "`{}` is a CPU device: casting the first hits in the CPU BVH costs less \
                     than rasterizing the scene into the light views (docs/bench/frame.md)",
                    adapter.name
                ),
            ),
            FirstBounce::Auto => (
                FirstBounce::Raster,
                format!(
                    "`{}` rasterizes on the GPU: ISPM's bounce maps",
                    adapter.name
                ),
            ),
            chosen => (chosen, "chosen in the settings".into()),
        }
    }
}

impl FromStr for FirstBounce {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        crate::error::parse_named(
            s,
            FirstBounce::ALL,
            FirstBounce::name,
            "first_bounce",
            "first bounce",
        )
    }
}

/// The bounce map's result: first-scatter rays and the bookkeeping of the power.
#[derive(Clone, Debug, Default)]
pub struct BounceMap {
    /// Photons that survived the first scatter, as rays for the CPU tracer (bounce 1).
    pub rays: Vec<PhotonRay>,
    /// Texels of all layers.
    pub texels: u64,
    /// Texels that hit the scene.
    pub covered: u64,
    /// Total power of the covered texels before the first scatter (W).
    pub incident_power: DVec3,
    /// Total power of the surviving rays (W).
    pub scattered_power: DVec3,
    /// Σ over covered texels of power × scatter probability (the expected scattered power).
    pub expected_scattered_power: DVec3,
    /// Seconds: rasterizing the bounce maps with the first scatter (until the GPU is done),
    /// reading them back, and converting the survivors to rays.
    pub raster_seconds: f64,
    pub readback_seconds: f64,
    pub scatter_seconds: f64,
    /// The light of each ray (index into `Scene::lights`).
    pub ray_lights: Vec<u32>,
    /// Whether each ray's first hit was on a material with a delta lobe (mirror, glass).
    pub first_delta: Vec<bool>,
}

/// The bounce maps of `layers` (see [`crate::scene::light_views::light_views`]) traced in `bvh`:
/// the same rays, bookkeeping and grouping by light as the rasterized maps'
/// `raster::ispm::BounceTargets::finish`. Deterministic in `seed` (one generator
/// per texel). Stops with `Cancelled` when `control` asks (between rows); a setting error
/// where the rasterized maps would not fit either.
pub fn trace_bounce_maps(
    scene: &Scene,
    bvh: &SceneBvh,
    layers: &[LightView],
    seed: u64,
    control: &dyn TraceControl,
) -> Result<BounceMap> {
    check_layer_memory(layers, &BOUNCE_MAPS)?;
    // Rows of all layers, each with its layer and its first texel's global index.
    let mut rows = Vec::new();
    let mut first = 0u64;
    for (li, l) in layers.iter().enumerate() {
        for y in 0..l.res {
            rows.push((li, y, first + y as u64 * l.res as u64));
        }
        first += l.res as u64 * l.res as u64;
    }
    let inverses: Vec<DMat4> = layers
        .iter()
        .map(|l| l.view_proj.as_dmat4().inverse())
        .collect();
    let parts: Vec<BounceMap> = rows
        .par_iter()
        .map(|&(li, y, first)| {
            let mut part = BounceMap::default();
            if control.stopped() {
                return part;
            }
            let l = &layers[li];
            for x in 0..l.res {
                let mut rng = Rng::new(seed, STREAM_BOUNCE, first + x as u64);
                texel(scene, bvh, l, &inverses[li], [x, y], &mut rng, &mut part);
            }
            part
        })
        .collect();
    if control.stopped() {
        return Err(Error::Cancelled);
    }
    let mut out = BounceMap {
        texels: first,
        ..Default::default()
    };
    for p in parts {
        out.covered += p.covered;
        out.incident_power += p.incident_power;
        out.expected_scattered_power += p.expected_scattered_power;
        out.scattered_power += p.scattered_power;
        out.rays.extend(p.rays);
        out.ray_lights.extend(p.ray_lights);
        out.first_delta.extend(p.first_delta);
    }
    Ok(out)
}

/// The photon of texel `[x, y]` of layer `l` (clip -> world `inverse`), added to `out`.
fn texel(
    scene: &Scene,
    bvh: &SceneBvh,
    l: &LightView,
    inverse: &DMat4,
    [x, y]: [u32; 2],
    rng: &mut Rng,
    out: &mut BounceMap,
) {
    // A uniformly random point of the texel, as the raster map's jittered sample.
    let j = rng.next_2d();
    let res = l.res as f64;
    let ndc_x = 2.0 * (x as f64 + j.x as f64) / res - 1.0;
    let ndc_y = 1.0 - 2.0 * (y as f64 + j.y as f64) / res;
    let far = *inverse * DVec4::new(ndc_x, ndc_y, 1.0, 1.0);
    let origin = l.position;
    let d = ((far.truncate() / far.w) - origin.as_dvec3()).normalize();
    if !d.is_finite() {
        return;
    }
    let d = d.as_vec3();
    let Some(hit) = bvh.intersect(origin, d, f32::INFINITY) else {
        return;
    };
    let light = &scene.lights[l.light];
    let c = d.dot(l.forward).max(0.0);
    let phi = light.intensity_towards(d) * (l.texel_area * c * c * c);
    out.covered += 1;
    out.incident_power += phi.as_dvec3();
    if phi.max_element() <= 0.0 || !phi.is_finite() {
        return;
    }
    let it = Interaction::new(scene, &hit, d);
    let wo = -d;
    let rho = it.material.scatter_probability(it.frame.to_local(wo));
    out.expected_scattered_power += (phi * rho).as_dvec3();
    let Some(sc) = scatter(&it, wo, phi, rng) else {
        return;
    };
    out.scattered_power += sc.power.as_dvec3();
    out.rays.push(PhotonRay::new(
        it.spawn(sc.wi),
        sc.wi,
        sc.power,
        super::path_density_factor(&it.material, sc.lobe),
        1,
    ));
    out.ray_lights.push(l.light as u32);
    out.first_delta.push(it.material.is_specular_traced());
}
