//! CPU photon tracing (ISPM Appendix A, with the path density of section 4.3).
//!
//! A photon is stored at every hit on a surface with a non-delta lobe, then scattered by
//! sampling the BSDF and kept alive by Russian roulette with survival probability
//! `q = min(1, max(Φ·w) / max(Φ))` (`w` = the sample's f·cos/pdf), so that a survivor's
//! power `Φ·w/q` keeps its largest channel: stored photons have roughly equal power.
//!
//! Work is split into fixed chunks of paths, each traced with its own per-path generator
//! `Rng::new(seed, stream, path)` into its own [`PhotonSet`]; the chunks are concatenated
//! in order, so the result depends on the seed only, not on the thread schedule.

use super::differential::{self, Differentials};
use super::focus::Focus;
use super::{path_density_factor, FootprintAxes, PathKind, Photon, PhotonRay, PhotonSet};
use crate::bsdf::Lobe;
use crate::cancel::Progress;
use crate::error::{Error, Result};
use crate::memory;
use crate::sampling::Rng;
use crate::scene::light::Emission;
use crate::scene::sources::Spread;
use crate::scene::{Scene, Source, Sources};
use crate::trace::{Interaction, SceneBvh};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// Paths per parallel work item.
const CHUNK: u64 = 4096;
/// Random stream of emitted photon paths.
const STREAM_EMIT: u64 = 0x9407_0000;
/// Random stream of continued photon paths.
const STREAM_CONTINUE: u64 = 0x9407_0001;
/// Random stream of photon paths aimed at the specular objects for ISPM.
const STREAM_AIMED: u64 = 0x9407_0002;
/// Random stream of the sky's pilot photons (`super::sky_guide`).
const STREAM_SKY_PILOT: u64 = 0x9407_0003;
/// Random stream of the sky's aimed photons (`super::sky_guide`).
const STREAM_SKY_AIMED: u64 = 0x9407_0004;

/// Photon tracer settings.
#[derive(Clone, Copy, Debug)]
pub struct PhotonTraceSettings {
    /// Maximum number of scatterings of a path; stored bounce indices are `0..=max_bounces`.
    pub max_bounces: u32,
    /// Whether hits of bounce 0 (direct light) are stored.
    pub store_direct: bool,
    /// Trace photon differentials and record each stored photon's footprint.
    pub differentials: Option<DifferentialSettings>,
}

/// Footprint parameters of photon differentials (Fabianowski & Dingliana 2009, §4).
#[derive(Clone, Copy, Debug)]
pub struct DifferentialSettings {
    /// Global spacing Δ = √(Ω/n); see [`super::differential::global_spacing`].
    pub spacing: f32,
    /// User smoothing factor s (bias against variance).
    pub smoothing: f32,
    /// Largest footprint semi-axis (m).
    pub r_max: f32,
}

impl Default for PhotonTraceSettings {
    fn default() -> Self {
        PhotonTraceSettings {
            max_bounces: 16,
            store_direct: true,
            differentials: None,
        }
    }
}

/// Emits `n_photons` photons from the scene's sources (lights, emitters, environment; each
/// chosen with probability proportional to its power, so each photon carries about total
/// power / n) and traces them.
pub fn emit_and_trace(
    scene: &Scene,
    bvh: &SceneBvh,
    n_photons: u64,
    s: &PhotonTraceSettings,
    seed: u64,
) -> PhotonSet {
    emit_and_trace_checked(scene, bvh, n_photons, s, seed, &Unchecked)
        .unwrap_or_else(|e| panic!("photon trace: {e}"))
}

/// [`emit_and_trace`] under `control`: progress reported per chunk of paths, cancellation
/// asked between paths, and the stored photons kept within the memory budget.
pub fn emit_and_trace_checked(
    scene: &Scene,
    bvh: &SceneBvh,
    n_photons: u64,
    s: &PhotonTraceSettings,
    seed: u64,
    control: &dyn TraceControl,
) -> Result<PhotonSet> {
    emit_and_trace_focused(scene, bvh, n_photons, s, seed, control, &Focus::default())
}

/// [`emit_and_trace_checked`] with part of each light's photons aimed at the specular
/// objects by its projection map (`focus`, see [`super::focus`]), weighted by the mixture
/// density so that the estimate is unchanged.
pub fn emit_and_trace_focused(
    scene: &Scene,
    bvh: &SceneBvh,
    n_photons: u64,
    s: &PhotonTraceSettings,
    seed: u64,
    control: &dyn TraceControl,
    focus: &Focus,
) -> Result<PhotonSet> {
    let sources = Sources::of(scene);
    emit_and_trace_sources(scene, bvh, &sources, n_photons, s, seed, control, focus)
}

/// Emits `n_photons` photons from `sources` (each chosen with probability proportional to
/// its power, so each photon carries about their total power / n) and traces them; point
/// and spot lights aim part of theirs by `focus`.
#[allow(clippy::too_many_arguments)]
pub fn emit_and_trace_sources(
    scene: &Scene,
    bvh: &SceneBvh,
    sources: &Sources,
    n_photons: u64,
    s: &PhotonTraceSettings,
    seed: u64,
    control: &dyn TraceControl,
    focus: &Focus,
) -> Result<PhotonSet> {
    let mut set = trace_chunks(n_photons, control, |i, out| {
        let mut rng = Rng::new(seed, STREAM_EMIT, i);
        let Some((e, spread)) = emit_photon(scene, sources, n_photons, focus, &mut rng) else {
            out.absorbed += 1;
            return;
        };
        follow_emitted(scene, bvh, &e, spread, s, &mut rng, out);
    })?;
    set.emitted = n_photons;
    finish_footprints(&mut set, s);
    Ok(set)
}

/// `n` of the sky's photons of `scene` emitted as [`Sources::emit`] would and traced: the
/// rays (towards the sky, crossing of the centre's plane) of those whose paths stored a
/// photon, in index order (the pilot of [`super::sky_guide::SkyGuide`]; its photons are
/// not kept).
pub fn sky_pilot(
    scene: &Scene,
    bvh: &SceneBvh,
    n: u64,
    s: &PhotonTraceSettings,
    seed: u64,
    control: &dyn TraceControl,
) -> Result<Vec<super::sky_guide::SkyRay>> {
    let bounds = scene.bounds();
    let Some(env) = scene.environment.as_deref() else {
        return Ok(Vec::new());
    };
    let marked = std::sync::Mutex::new(Vec::new());
    trace_chunks(n, control, |i, out| {
        let mut rng = Rng::new(seed, STREAM_SKY_PILOT, i);
        let Some(e) = env.emit(&mut rng, bounds) else {
            return;
        };
        let before = out.photons.len();
        let ray = PhotonRay::new(e.origin, e.direction, e.power, 1.0, 0);
        follow(
            scene,
            bvh,
            &ray,
            Differentials::emitted(e.direction),
            None,
            s,
            &mut rng,
            out,
        );
        if out.photons.len() > before {
            out.photons.truncate(before);
            let towards = -e.direction;
            let c = bounds.centre;
            let point = e.origin - towards * (e.origin - c).dot(towards);
            let ray = super::sky_guide::SkyRay { towards, point };
            marked
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .push((i, ray));
        }
    })?;
    let mut marked = marked.into_inner().unwrap_or_else(|p| p.into_inner());
    marked.sort_by_key(|(i, _)| *i);
    Ok(marked.into_iter().map(|(_, r)| r).collect())
}

/// The aimed photons of the sky's `guide` ([`super::sky_guide`]) traced, stored from
/// their second hit as the plain ones; their footprints (`s.differentials`) are the plain
/// photons' (the bounding disc's area over the plain count), so that a surface's light is
/// smoothed as with the plain photons alone, over more of them.
pub fn emit_aimed_sky(
    scene: &Scene,
    bvh: &SceneBvh,
    guide: &super::sky_guide::SkyGuide,
    plain: u64,
    s: &PhotonTraceSettings,
    seed: u64,
    control: &dyn TraceControl,
) -> Result<PhotonSet> {
    let Some(env) = scene.environment.as_deref() else {
        return Ok(PhotonSet::default());
    };
    let b = scene.bounds();
    let area = std::f32::consts::PI * b.radius * b.radius / plain.max(1) as f32;
    let mut set = trace_chunks(guide.aimed(), control, |i, out| {
        let mut rng = Rng::new(seed, STREAM_SKY_AIMED, i);
        let Some(e) = guide
            .emit_aimed(env, &mut rng)
            .filter(|e| e.power.max_element() > 0.0)
        else {
            out.absorbed += 1;
            return;
        };
        let spread = Neighbours::Area(area, e.direction, false);
        follow_emitted(scene, bvh, &e, spread, s, &mut rng, out);
    })?;
    set.emitted = guide.aimed();
    finish_footprints(&mut set, s);
    Ok(set)
}

/// Traces the emitted photon `e` whose neighbours lie as `spread` (its differentials when
/// `s` asks for them) into `out`.
fn follow_emitted(
    scene: &Scene,
    bvh: &SceneBvh,
    e: &Emission,
    spread: Neighbours,
    s: &PhotonTraceSettings,
    rng: &mut Rng,
    out: &mut PhotonSet,
) {
    let ray = PhotonRay::new(e.origin, e.direction, e.power, 1.0, 0);
    let diff = s
        .differentials
        .map_or(Differentials::emitted(e.direction), |ds| {
            emitted_differentials(e, spread, ds.spacing)
        });
    follow(scene, bvh, &ray, diff, None, s, rng, out);
}

/// The rays of [`emit_and_trace_sources`]'s `n` paths as it emits them (the same
/// generator and draws, so the same first segments), for a tracer elsewhere that draws its
/// own numbers after emission (the GPU continuation, `gpu::photon::emitted`): photon `i` at
/// index `i`, bounce 0; a zero-power ray where the emission absorbs the path (a tracer
/// counts it absorbed, as this one does). No differentials.
pub fn emitted_rays(
    scene: &Scene,
    sources: &Sources,
    n: u64,
    seed: u64,
    focus: &Focus,
) -> Vec<PhotonRay> {
    (0..n)
        .into_par_iter()
        .map(|i| {
            let mut rng = Rng::new(seed, STREAM_EMIT, i);
            ray_of(emit_photon(scene, sources, n, focus, &mut rng).map(|(e, _)| e))
        })
        .collect()
}

/// The rays of [`emit_aimed_sky`]'s paths as it emits them (see [`emitted_rays`]).
pub fn aimed_sky_rays(
    scene: &Scene,
    guide: &super::sky_guide::SkyGuide,
    seed: u64,
) -> Vec<PhotonRay> {
    let Some(env) = scene.environment.as_deref() else {
        return Vec::new();
    };
    (0..guide.aimed())
        .into_par_iter()
        .map(|i| {
            let mut rng = Rng::new(seed, STREAM_SKY_AIMED, i);
            ray_of(guide.emit_aimed(env, &mut rng))
        })
        .collect()
}

/// An emitted photon's ray at bounce 0, or a zero-power one for none.
fn ray_of(e: Option<Emission>) -> PhotonRay {
    match e.filter(|e| e.power.max_element() > 0.0) {
        Some(e) => PhotonRay::new(e.origin, e.direction, e.power, 1.0, 0),
        None => PhotonRay::new(Vec3::ZERO, Vec3::Z, Vec3::ZERO, 1.0, 0),
    }
}

/// How one photon's neighbours lie at its emission: a point light's photons `spacing`
/// radians apart (√(1/(n q(ω))) for a density q per steradian), or the area a photon
/// stands for on an emitting surface or the bounding disc (see [`Spread`]).
#[derive(Clone, Copy, Debug)]
enum Neighbours {
    Angular(f32),
    /// Area per photon, the surface's normal, and whether directions spread diffusely.
    Area(f32, Vec3, bool),
}

/// One of `n` photons from `sources`: a source drawn by power, a photon of it (aimed by
/// `focus` for some of a point or spot light's), its power over one photon of `n`; and how
/// the source's photons lie around it.
fn emit_photon(
    scene: &Scene,
    sources: &Sources,
    n: u64,
    focus: &Focus,
    rng: &mut Rng,
) -> Option<(Emission, Neighbours)> {
    let (source, p) = sources.choose(rng.next_f32())?;
    // The source's share of the photons.
    let n_s = (n as f32 * p).max(1.0);
    let (mut e, neighbours) = match source {
        Source::Light(li) if focus.active(li) => {
            let light = &scene.lights[li];
            let (direction, q) = focus.sample(light, li, rng);
            let power = if q > 0.0 {
                light.intensity_towards(direction) / q
            } else {
                Vec3::ZERO
            };
            let e = Emission {
                origin: light.position(),
                direction,
                power,
            };
            (e, Neighbours::Angular((1.0 / (n_s * q.max(1e-12))).sqrt()))
        }
        _ => {
            let (e, spread) = sources.emit_spread_from(scene, source, rng)?;
            let neighbours = match spread {
                Spread::Angular { solid_angle } => Neighbours::Angular((solid_angle / n_s).sqrt()),
                Spread::Area {
                    area,
                    normal,
                    diffuse,
                } => Neighbours::Area(area / n_s, normal, diffuse),
            };
            (e, neighbours)
        }
    };
    if let (Source::Environment, Some(guide)) = (source, &focus.sky) {
        // The plain technique's balance-heuristic weight (1 off the guide's kernels).
        e.power *= guide.plain_weight(scene.environment.as_deref()?, &e);
    }
    e.power /= p * n as f32;
    Some((e, neighbours))
}

/// The differentials of an emitted photon whose neighbours lie as `neighbours`, scaled for
/// the global spacing Δ = `spacing`: a point light's photons spread by their angular
/// spacing (√(Ω_l/n_l) rather than Δ: aimed photons are denser, their footprints smaller);
/// a surface's start with the area per photon across the surface, then spread as after a
/// diffuse re-emission (area lights) or stay parallel (the sun's and the sky's, which cross
/// the bounding disc together).
fn emitted_differentials(e: &Emission, neighbours: Neighbours, spacing: f32) -> Differentials {
    match neighbours {
        Neighbours::Angular(a) => Differentials::emitted(e.direction).scaled(a / spacing),
        Neighbours::Area(area, normal, diffuse) => {
            let side = area.max(0.0).sqrt() / spacing;
            let f = crate::sampling::Frame::new(normal);
            let mut diff = Differentials {
                dp: [f.t * side, f.b * side],
                dd: [Vec3::ZERO; 2],
            };
            if diffuse {
                diff.reemit(e.direction);
            }
            diff
        }
    }
}

/// Photon focusing for ISPM: `n` photons of light `li` aimed into its projection map
/// (`focus` with an aimed share of 1, its cones around every specular object), each with
/// power I(ω)/(n·q(ω)) for the cones' mixture density q; only the paths whose first hit
/// has a delta lobe are traced on (from bounce 0, not stored there), since the bounce map
/// keeps every other first hit and drops these (`BounceMap::first_delta`). The two parts
/// partition the light's first hits, so the estimate is unchanged while the caustic paths
/// get many more photons.
#[allow(clippy::too_many_arguments)]
pub fn emit_aimed_caustics(
    scene: &Scene,
    bvh: &SceneBvh,
    li: usize,
    n: u64,
    s: &PhotonTraceSettings,
    seed: u64,
    control: &dyn TraceControl,
    focus: &Focus,
) -> Result<PhotonSet> {
    let light = &scene.lights[li];
    let origin = light.position();
    let mut set = trace_chunks(n, control, |i, out| {
        let mut rng = Rng::new(seed, STREAM_AIMED, i);
        let (direction, q) = focus.sample(light, li, &mut rng);
        let power = light.intensity_towards(direction) / (q * n as f32);
        if q.is_nan() || q <= 0.0 || power.max_element() <= 0.0 {
            out.absorbed += 1;
            return;
        }
        let Some(hit) = bvh.intersect(origin, direction, f32::INFINITY) else {
            out.escaped += 1;
            return;
        };
        if !Interaction::new(scene, &hit, direction)
            .material
            .is_specular_traced()
        {
            out.absorbed += 1;
            return;
        }
        let ray = PhotonRay::new(origin, direction, power, 1.0, 0);
        let diff = s
            .differentials
            .map_or(Differentials::emitted(direction), |ds| {
                let spacing = (1.0 / (n as f32 * q)).sqrt();
                Differentials::emitted(direction).scaled(spacing / ds.spacing)
            });
        follow(scene, bvh, &ray, diff, None, s, &mut rng, out);
    })?;
    set.emitted = n;
    finish_footprints(&mut set, s);
    Ok(set)
}

/// The rays of [`emit_aimed_caustics`]'s paths as it emits them (see [`emitted_rays`]): a
/// zero-power ray where it absorbs the path (no power, or a first hit without a delta
/// lobe), the ray itself where it escapes (a tracer finds it escaping too).
pub fn aimed_caustic_rays(
    scene: &Scene,
    bvh: &SceneBvh,
    li: usize,
    n: u64,
    seed: u64,
    focus: &Focus,
) -> Vec<PhotonRay> {
    let light = &scene.lights[li];
    let origin = light.position();
    (0..n)
        .into_par_iter()
        .map(|i| {
            let mut rng = Rng::new(seed, STREAM_AIMED, i);
            let (direction, q) = focus.sample(light, li, &mut rng);
            let power = light.intensity_towards(direction) / (q * n as f32);
            if q.is_nan() || q <= 0.0 || power.max_element() <= 0.0 {
                return ray_of(None);
            }
            let specular = bvh
                .intersect(origin, direction, f32::INFINITY)
                .is_none_or(|hit| {
                    Interaction::new(scene, &hit, direction)
                        .material
                        .is_specular_traced()
                });
            let e = Emission {
                origin,
                direction,
                power,
            };
            ray_of(specular.then_some(e))
        })
        .collect()
}

/// Continues photons that already scattered elsewhere (e.g. in the GPU bounce map): each
/// ray's next hit is stored with the ray's bounce index.
pub fn continue_paths(
    scene: &Scene,
    bvh: &SceneBvh,
    rays: &[PhotonRay],
    s: &PhotonTraceSettings,
    seed: u64,
) -> PhotonSet {
    continue_paths_checked(scene, bvh, rays, s, seed, &Unchecked)
        .unwrap_or_else(|e| panic!("photon trace: {e}"))
}

/// [`continue_paths`] under `control` (see [`emit_and_trace_checked`]).
pub fn continue_paths_checked(
    scene: &Scene,
    bvh: &SceneBvh,
    rays: &[PhotonRay],
    s: &PhotonTraceSettings,
    seed: u64,
    control: &dyn TraceControl,
) -> Result<PhotonSet> {
    continue_paths_from(scene, bvh, rays, s, seed, control, None)
}

/// Where continued photons came from: a light at `position` whose photons are spaced by
/// the angle `spacing` (rad), for the differentials of the first segment.
#[derive(Clone, Copy, Debug)]
pub struct FirstSegment {
    pub position: glam::Vec3,
    pub spacing: f32,
}

/// [`continue_paths_checked`] for photons that left a light at `first.position` (the ISPM
/// bounce map): with differentials, the first segment is re-cast on the CPU from the light
/// to the ray's origin, so that photons whose first scattering was a mirror or glass carry
/// that segment's footprint (and count as caustic photons) instead of starting with a zero
/// footprint; after a diffuse or glossy first scattering they start at their origin, as
/// after any re-emission.
pub fn continue_paths_from(
    scene: &Scene,
    bvh: &SceneBvh,
    rays: &[PhotonRay],
    s: &PhotonTraceSettings,
    seed: u64,
    control: &dyn TraceControl,
    first: Option<FirstSegment>,
) -> Result<PhotonSet> {
    let mut set = trace_chunks(rays.len() as u64, control, |i, out| {
        let mut rng = Rng::new(seed, STREAM_CONTINUE, i);
        let ray = &rays[i as usize];
        let recast = match (first, &s.differentials) {
            (Some(f), Some(ds)) => recast_first_segment(scene, bvh, ray, f, ds),
            _ => None,
        };
        let (diff, kind) = match recast {
            Some((diff, kind)) => (diff, Some(kind)),
            None => (Differentials::emitted(ray.direction.into()), None),
        };
        follow(scene, bvh, ray, diff, kind, s, &mut rng, out);
    })?;
    set.emitted = rays.len() as u64;
    finish_footprints(&mut set, s);
    Ok(set)
}

/// The differentials of a continued photon after its first segment, from the light at
/// `f.position` to the ray's origin, and its first scattering when that was through a delta
/// lobe (the lobe is told from the ray's direction); `None` otherwise.
fn recast_first_segment(
    scene: &Scene,
    bvh: &SceneBvh,
    ray: &PhotonRay,
    f: FirstSegment,
    ds: &DifferentialSettings,
) -> Option<(Differentials, PathKind)> {
    let origin = glam::Vec3::from(ray.origin);
    let wi = glam::Vec3::from(ray.direction);
    let to = origin - f.position;
    let dist = to.length();
    if dist <= 0.0 || !dist.is_finite() {
        return None;
    }
    let d = to / dist;
    let hit = bvh.intersect(f.position, d, dist * 1.01 + 1e-3)?;
    let it = Interaction::new(scene, &hit, d);
    // The ray's origin is offset off the surface: the re-cast hit must be that surface.
    if (it.position - origin).length() > 1e-2 * dist + 1e-3 {
        return None;
    }
    let n = it.frame.n * if d.dot(it.ng) < 0.0 { 1.0 } else { -1.0 };
    let m = it.material;
    let reflected = wi.dot(d - 2.0 * d.dot(n) * n) > 0.9999;
    let lobe = if reflected && m.has_specular() && m.is_mirror() {
        Lobe::Mirror
    } else if reflected && m.has_transmission() {
        Lobe::GlassReflect
    } else if m.has_transmission() && wi.dot(n) < 0.0 {
        Lobe::GlassRefract
    } else {
        return None;
    };
    let mut diff = Differentials::emitted(d).scaled(f.spacing / ds.spacing);
    diff.transfer(d, hit.t, it.ng);
    scatter_differentials(scene, &it, &hit, d, wi, lobe, &mut diff);
    Some((diff, PathKind::Caustic))
}

/// Once all photons are traced (§4.3, "after photon tracing has completed"): turns each
/// footprint's skewed semi-diameters into the ellipse's principal semi-axes (see
/// [`differential::principal_axes`] for why), compresses those of diffusely reflected
/// photons against their geometric-mean semi-axis (see [`differential::compress`] for why
/// that reference), caps every footprint's elongation at
/// [`differential::MAX_ELONGATION`], clamps every semi-axis to `r_max` and records each
/// photon's footprint radius.
fn finish_footprints(set: &mut PhotonSet, s: &PhotonTraceSettings) {
    let Some(ds) = &s.differentials else {
        return;
    };
    for f in &mut set.footprints {
        f.axes = differential::principal_axes(f.axes);
    }
    let diffuse = |f: &&FootprintAxes| f.kind == PathKind::Diffuse;
    let reference = differential::reference_length(
        set.footprints
            .iter()
            .filter(diffuse)
            .flat_map(|f| f.axes.map(|a| a.length())),
    );
    for (p, f) in set.photons.iter_mut().zip(&mut set.footprints) {
        f.axes = f.axes.map(|a| match reference {
            Some(l) if f.kind == PathKind::Diffuse => differential::compress(a, l),
            _ => a,
        });
        f.axes = differential::cap_elongation(f.axes, differential::MAX_ELONGATION)
            .map(|a| differential::clamp_axis(a, ds.r_max));
        p.footprint_radius = f.radius();
    }
}

/// What a photon trace reports to and asks of its caller.
pub trait TraceControl: Sync {
    /// Reports that `fraction` of the paths are traced.
    fn advance(&self, fraction: f64);
    /// True once the trace should stop (asked between paths).
    fn stopped(&self) -> bool;
    /// Most bytes the stored photons may take, if limited.
    fn budget(&self) -> Option<u64>;
}

/// No progress, no cancellation, no memory budget.
pub(crate) struct Unchecked;
impl TraceControl for Unchecked {
    fn advance(&self, _: f64) {}
    fn stopped(&self) -> bool {
        false
    }
    fn budget(&self) -> Option<u64> {
        None
    }
}

/// A trace reporting to a [`Progress`] as stage `name`, within the memory the process can
/// get (a third of it for the stored photons: the chunks, their concatenation and the
/// structure built over them each hold a copy or more).
pub struct Checked<'a> {
    progress: &'a dyn Progress,
    name: &'a str,
    budget: Option<u64>,
    stop: AtomicBool,
}

impl<'a> Checked<'a> {
    pub fn new(progress: &'a dyn Progress, name: &'a str) -> Self {
        Checked {
            progress,
            name,
            budget: memory::available().map(|a| a / 3),
            stop: AtomicBool::new(false),
        }
    }
}

impl TraceControl for Checked<'_> {
    fn advance(&self, fraction: f64) {
        if !self.progress.update(self.name, fraction) {
            self.stop.store(true, Ordering::Relaxed);
        }
    }
    fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed) || self.progress.cancelled()
    }
    fn budget(&self) -> Option<u64> {
        self.budget
    }
}

/// Chunks traced before the memory need of the whole trace is extrapolated from them.
const EXTRAPOLATE_AFTER: u64 = 8;

/// Bytes a stored photon takes while tracing (the record and its footprint).
const STORED_BYTES: u64 =
    (std::mem::size_of::<Photon>() + std::mem::size_of::<FootprintAxes>()) as u64;

/// Runs `path(i, set)` for every `i < n` in parallel chunks and concatenates the chunks' sets
/// in order. Stops with `Cancelled` when `control` asks, and with `OutOfMemory` when the
/// stored photons outgrow its budget (the need is extrapolated from the chunks done).
fn trace_chunks(
    n: u64,
    control: &dyn TraceControl,
    path: impl Fn(u64, &mut PhotonSet) + Sync,
) -> Result<PhotonSet> {
    let chunks = n.div_ceil(CHUNK);
    let done = AtomicU64::new(0);
    let stored = AtomicU64::new(0);
    let over_budget = AtomicBool::new(false);
    let sets: Vec<PhotonSet> = (0..chunks)
        .into_par_iter()
        .map(|chunk| {
            let mut set = PhotonSet::default();
            if over_budget.load(Ordering::Relaxed) {
                return set;
            }
            for i in chunk * CHUNK..((chunk + 1) * CHUNK).min(n) {
                if i % 64 == 0 && control.stopped() {
                    return set;
                }
                path(i, &mut set);
            }
            let bytes = set.photons.len() as u64 * STORED_BYTES;
            let total = stored.fetch_add(bytes, Ordering::Relaxed) + bytes;
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            // Past the first chunks, stop as soon as the extrapolated total won't fit.
            let expected = if d >= EXTRAPOLATE_AFTER {
                (total as f64 * chunks as f64 / d as f64) as u64
            } else {
                total
            };
            if control.budget().is_some_and(|b| expected > b) {
                over_budget.store(true, Ordering::Relaxed);
            }
            control.advance(d as f64 / chunks as f64);
            set
        })
        .collect();
    if over_budget.load(Ordering::Relaxed) {
        let done = done.load(Ordering::Relaxed).max(1);
        let stored = stored.load(Ordering::Relaxed);
        return Err(Error::OutOfMemory {
            what: format!("the photons of {n} paths"),
            needed: (stored as f64 * chunks as f64 / done as f64) as u64 * 3,
            available: memory::available().unwrap_or(0),
        });
    }
    if control.stopped() {
        return Err(Error::Cancelled);
    }
    let count: usize = sets.iter().map(|s| s.photons.len()).sum();
    let mut all = PhotonSet {
        photons: memory::try_with_capacity(count, || format!("{count} photons"))?,
        ..Default::default()
    };
    for set in sets {
        all.append(set);
    }
    Ok(all)
}

/// Follows one photon until it is absorbed, escapes or reaches the bounce limit.
#[allow(clippy::too_many_arguments)]
fn follow(
    scene: &Scene,
    bvh: &SceneBvh,
    ray: &PhotonRay,
    mut diff: Differentials,
    first_kind: Option<PathKind>,
    s: &PhotonTraceSettings,
    rng: &mut Rng,
    out: &mut PhotonSet,
) {
    let (mut o, mut d) = (ray.origin.into(), glam::Vec3::from(ray.direction));
    let mut power = glam::Vec3::from(ray.power);
    let mut density = ray.path_density;
    let mut bounce = ray.bounce;
    // Photons continued from elsewhere (the ISPM bounce map) start their differentials at
    // their origin, as after a diffuse re-emission.
    let mut kind = match first_kind {
        Some(k) => k,
        None if bounce == 0 => PathKind::Direct,
        None => PathKind::Diffuse,
    };
    if power.max_element() <= 0.0 || !power.is_finite() {
        out.absorbed += 1;
        return;
    }
    loop {
        let Some(hit) = bvh.intersect(o, d, f32::INFINITY) else {
            out.escaped += 1;
            return;
        };
        let it = Interaction::new(scene, &hit, d);
        let wo = -d;
        if s.differentials.is_some() {
            diff.transfer(d, hit.t, it.ng);
        }

        // Store the photon where a non-delta lobe can reflect it towards a viewer.
        if it.material.stores_photons() && (bounce > 0 || s.store_direct) {
            let normal = it.frame.n * it.ng.dot(wo).signum();
            out.store(Photon {
                position: it.position.into(),
                bounce,
                incident: wo.into(),
                path_density: density,
                power: power.into(),
                normal: normal.into(),
                ..Default::default()
            });
            if let Some(ds) = &s.differentials {
                let axes = diff.footprint_axes(ds.spacing, ds.smoothing);
                out.footprints.push(FootprintAxes { axes, kind });
            }
        }
        if bounce >= s.max_bounces {
            out.truncated += 1;
            return;
        }

        let Some(sc) = scatter(&it, wo, power, rng) else {
            out.absorbed += 1;
            return;
        };
        power = sc.power;
        if s.differentials.is_some() {
            scatter_differentials(scene, &it, &hit, d, sc.wi, sc.lobe, &mut diff);
            diff.survive(sc.q);
            // Light focused by a delta lobe or by rough glass keeps its caustic kind: its
            // footprints keep the size their density gives them (the uniform scaling of
            // the diffuse ones would spread rough glass's caustic: gather 1.035 of Mitsuba
            // on the roughdielectric sphere with it, 1.000 at half the smoothing).
            let focused = sc.lobe.is_delta() || sc.lobe == Lobe::RoughRefract;
            kind = match (kind, focused) {
                (PathKind::Direct | PathKind::Caustic, true) => PathKind::Caustic,
                _ => PathKind::Diffuse,
            };
        }
        density *= path_density_factor(&it.material, sc.lobe);
        bounce += 1;
        o = it.spawn(sc.wi);
        d = sc.wi;
    }
}

/// A photon's scattering that survived Russian roulette.
pub struct Scattered {
    /// Unit direction of the scattered photon.
    pub wi: glam::Vec3,
    /// Its power after the roulette (Φ·w/q).
    pub power: glam::Vec3,
    /// The survival probability.
    pub q: f32,
    pub lobe: Lobe,
}

/// Scatters a photon of `power` arriving at `it` from direction `wo` (pointing away from the
/// surface): [`scatter_local`] in the interaction's shading frame. `None`: absorbed.
pub(crate) fn scatter(
    it: &Interaction,
    wo: glam::Vec3,
    power: glam::Vec3,
    rng: &mut Rng,
) -> Option<Scattered> {
    let f = &it.frame;
    let sc = scatter_local(&it.material, f.to_local(wo), f.to_local(it.ng), power, rng)?;
    Some(Scattered {
        wi: f.to_world(sc.wi),
        ..sc
    })
}

/// A photon's scattering in a shading frame (+z = the shading normal; `wo` and `wi` local,
/// `ng` the geometric normal in it): samples the BSDF (reflections must stay on the
/// arrival side of `ng`, refractions cross), then Russian roulette with
/// q = min(1, max(Φ·w)/max(Φ)). `None`: absorbed. The GPU trace runs the same formulas on
/// the same random numbers (`gpu/shaders/photon/scatter.wgsl`, parity test
/// `tests/gpu_photon_scatter.rs`).
pub fn scatter_local(
    m: &crate::bsdf::Material,
    wo: glam::Vec3,
    ng: glam::Vec3,
    power: glam::Vec3,
    rng: &mut Rng,
) -> Option<Scattered> {
    let bs = m.sample_adjoint(wo, rng)?;
    let same_side = bs.wi.dot(ng) * wo.dot(ng) > 0.0;
    if same_side == bs.lobe.crosses() {
        return None;
    }
    let scattered = power * bs.weight;
    let q = (scattered.max_element() / power.max_element()).min(1.0);
    if q.is_nan() || q <= 0.0 || rng.next_f32() >= q {
        return None;
    }
    Some(Scattered {
        wi: bs.wi,
        power: scattered / q,
        q,
        lobe: bs.lobe,
    })
}

/// Updates differentials for a scattering from `d` to `wi` through `lobe` (Igehy 1999 for
/// the delta lobes, re-emission for diffuse and glossy ones).
fn scatter_differentials(
    scene: &Scene,
    it: &Interaction,
    hit: &crate::trace::Hit,
    d: glam::Vec3,
    wi: glam::Vec3,
    lobe: Lobe,
    diff: &mut Differentials,
) {
    // Normal facing the incident side, and its derivative along the footprint.
    let sign = if d.dot(it.ng) < 0.0 { 1.0 } else { -1.0 };
    let n = it.frame.n * sign;
    let dn = diff.dp.map(|dp| normal_derivative(scene, hit, dp) * sign);
    match lobe {
        Lobe::Mirror | Lobe::GlassReflect => diff.reflect(d, n, dn),
        Lobe::GlassRefract => {
            // A thin slab (`Material::thin`) passes light straight through.
            let ior = if it.material.thin.is_some() {
                1.0
            } else {
                it.material.ior
            };
            let eta = if sign > 0.0 { 1.0 / ior } else { ior };
            diff.refract(d, wi, n, eta, dn);
        }
        Lobe::Diffuse | Lobe::Glossy | Lobe::RoughRefract => diff.reemit(wi),
    }
}

/// Derivative of the interpolated (unit) vertex normal at `hit` along the surface offset `dp`.
fn normal_derivative(scene: &Scene, hit: &crate::trace::Hit, dp: glam::Vec3) -> glam::Vec3 {
    let ([p0, p1, p2], [n0, n1, n2]) = scene.corners(hit.triangle as usize);
    let (e1, e2) = (p1 - p0, p2 - p0);
    // Barycentric derivatives: dp = du·e1 + dv·e2, solved by least squares.
    let (a, b, c) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let det = a * c - b * b;
    if det.abs() < 1e-20 {
        return glam::Vec3::ZERO;
    }
    let (r1, r2) = (dp.dot(e1), dp.dot(e2));
    let du = (c * r1 - b * r2) / det;
    let dv = (a * r2 - b * r1) / det;
    let w = 1.0 - hit.u - hit.v;
    let nn = n0 * w + n1 * hit.u + n2 * hit.v;
    let len = nn.length();
    if len < 1e-12 {
        return glam::Vec3::ZERO;
    }
    let n = nn / len;
    let dnn = du * (n1 - n0) + dv * (n2 - n0);
    (dnn - n * n.dot(dnn)) / len
}
