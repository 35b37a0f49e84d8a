//! Step 4 of an `ispm` frame: temporal reuse (Jozwowski 2002) and the CPU photon trace of
//! the bounces after the first. The ring of the last frames' photons loses what the
//! frame's changes made stale; each light's first-scatter rays are traced on, sized
//! (volume radii, the caustic density bound), compensated at boundaries and pushed. The
//! sources the bounce maps cannot see (emitting surfaces, directional lights, the sky: the
//! paper's §7 limitation) get their share of the photons by power, emitted on the CPU and
//! traced where the bounce maps' rays are, and are kept in the ring after the lights.

use super::super::context::FrameCtx;
use super::super::options::IspmOptions;
use super::super::{FrameParams, RenderStats};
use crate::cancel::Progress;
use crate::error::{Error, Result};
use crate::gpu::photon::emitted;
use crate::gpu::photon::resident::{self, ResidentPhotons, Sizing};
use crate::gpu::photon::scene::GpuPhotonScene;
use crate::gpu::GpuContext;
use crate::photon::bounce::BounceMap;
use crate::photon::focus::Focus;
use crate::photon::lbvh::Aabb;
use crate::photon::radius::{SceneExtent, VolumeRadius, Z_RATIO};
use crate::photon::ring::PhotonRing;
use crate::photon::sky_guide::SkyGuide;
use crate::photon::sky_pilot::KeptPilot;
use crate::photon::trace::{
    continue_paths_from, emit_aimed_caustics, emit_aimed_sky, emit_and_trace_sources, Checked,
    FirstSegment,
};
use crate::photon::{boundary, Photon, PhotonRay, PhotonTraceSettings};
use crate::scene::light_views::LightView;
use crate::scene::{Light, Scene, Source, Sources};
use crate::trace::SceneBvh;
use glam::Vec3;
use std::borrow::Cow;
use std::time::Instant;

/// Fewest pilot photons of the sky (`SkyGuide`), whatever its share of the frame's.
const PILOT_MIN: u64 = 4096;
/// The sky's plain photons per aimed one where a pilot found openings (`SkyGuide`; any
/// split is unbiased). The aimed photons nearly all enter (window room, 200k plain photons:
/// 2.5k of theirs stored, 180k of as many aimed ones'), so they set the frame's cost. Window
/// room, 200k photons, seeds 1-8, three pilot seeds: stored photons 230k at 1, 60k at 4;
/// with every marked pilot ray a kernel the indirect light's spread is 1.9-2.7% at 1 and
/// 1.9-3.0% at 4 (22% without aimed photons), the frame's over seeds 1-4 1.3-1.7% and
/// 1.0-1.7% (docs/bench/sky-openings.md).
const PLAIN_PER_AIMED: u64 = 4;

/// What changed since the photons in the ring were traced.
pub(in crate::frame) struct Invalidation<'a> {
    /// Materials changed: every photon is stale.
    pub all: bool,
    pub lights: &'a [usize],
    /// Objects moved, with their bounds before the move.
    pub moved: &'a [(usize, Aabb)],
}

/// Drops the photons of `ring` that `invalid` made stale: all of them, a light's, or those
/// within reach of a moved object (its bounds before and after, grown by the largest
/// kernel, `radius.r_max`: the frame's volume radii).
pub(super) fn invalidate(
    ring: &mut PhotonRing,
    invalid: &Invalidation,
    scene: &Scene,
    radius: VolumeRadius,
) {
    if invalid.all {
        ring.clear();
    }
    for &l in invalid.lights {
        ring.invalidate_light(l);
    }
    let grow = radius.r_max;
    for (object, before) in invalid.moved {
        let o = &scene.objects[*object];
        let after = super::super::object_bounds(scene, o);
        let b = before.union(after);
        ring.invalidate_region(Aabb {
            min: b.min - Vec3::splat(grow),
            max: b.max + Vec3::splat(grow),
        });
    }
}

/// The GPU trace's device and scene (`photon_trace` resolved to `gpu`).
#[derive(Clone, Copy)]
pub(super) struct OnGpu<'a> {
    pub ctx: &'a GpuContext,
    pub scene: &'a GpuPhotonScene,
}

/// The photon trace of a frame: its inputs and where it puts its photons.
pub(super) struct Trace<'a> {
    /// Continue the bounce maps' rays on the GPU; `None`: on the CPU.
    pub gpu: Option<OnGpu<'a>>,
    /// With `gpu`: leave the photons on the GPU, sized so (`super::resident`); `None`: read
    /// them back into the ring.
    pub resident: Option<Sizing>,
    pub scene: &'a Scene,
    pub bvh: &'a SceneBvh,
    pub options: &'a IspmOptions,
    pub params: &'a FrameParams,
    pub layers: &'a [LightView],
    /// The frame's photon budget (the bounce maps' share sized `layers`).
    pub budget: PhotonBudget,
    /// The scene's extent, made once a frame: each light's volume radii derive from it.
    pub extent: SceneExtent,
    /// Frame number the photons are stored under.
    pub frame: u64,
    /// Compensate each photon's boundary loss (photon side); progressive passes at full
    /// resolution compensate per pixel instead (`progressive::query_coverage`).
    pub compensate: bool,
    /// The sky's pilot, kept from frame to frame until the geometry, materials or sky
    /// change (`photon/sky_pilot.rs`).
    pub sky_pilot: &'a KeptPilot,
    pub progress: &'a dyn Progress,
}

impl Trace<'_> {
    /// The photon-trace settings of the later bounces.
    fn settings(&self) -> PhotonTraceSettings {
        let (o, p) = (self.options, self.params);
        if o.footprint_volumes {
            PhotonTraceSettings {
                store_direct: false,
                ..super::super::options::derived::trace_settings(
                    self.scene,
                    o.photons,
                    o.max_depth,
                    o.refine.smoothing,
                    &o.kernel,
                    p.radius_scale,
                )
            }
        } else {
            PhotonTraceSettings {
                max_bounces: o.max_depth - 1,
                store_direct: false,
                differentials: None,
            }
        }
    }

    /// Traces the rays of `bm` on per light and pushes each light's photons into `ring`;
    /// adds the stages "cpu trace", "gpu trace" (the continuation on the GPU, with its
    /// upload and readback) and "boundary compensation" (when compensating). With
    /// `resident`, the photons stay on the GPU: returned, and the ring gets none.
    pub fn run(
        &self,
        bm: &BounceMap,
        ring: &mut PhotonRing,
        fc: &mut FrameCtx,
    ) -> Result<Option<ResidentPhotons>> {
        if let (Some(g), Some(sizing)) = (self.gpu, self.resident) {
            return self.run_resident(g, sizing, bm, ring, fc).map(Some);
        }
        let stats = &mut fc.stats;
        let t = Instant::now();
        let mut compensation = 0.0;
        let gpu_seconds = std::cell::Cell::new(0.0);
        let pts = self.settings();
        // Photon focusing: lights whose projection maps hold every specular object get
        // their mirror and glass first hits from aimed CPU photons instead of the bounce
        // map.
        let focus = Focus::of_scene(
            self.scene,
            if self.options.refine.photon_focus > 0.0 {
                1.0
            } else {
                0.0
            },
        );
        let mut start = 0;
        while start < bm.rays.len() {
            let light = bm.ray_lights[start];
            let end = start
                + bm.ray_lights[start..]
                    .iter()
                    .take_while(|&&l| l == light)
                    .count();
            let mut photons =
                self.trace_light(bm, start..end, &pts, &focus, stats, &gpu_seconds)?;
            self.size(ring, light as usize, &mut photons);
            let tc = Instant::now();
            let compensated = self.compensated(light, &photons)?;
            compensation += tc.elapsed().as_secs_f64();
            ring.push(self.frame, light as usize, photons, compensated);
            start = end;
            let done = start as f64 / bm.rays.len() as f64;
            if !self.progress.update("cpu trace", done) {
                return Err(Error::Cancelled);
            }
        }
        // The sources the bounce maps do not see: emitted on the CPU, traced where `photon_trace` says.
        for (source, n) in self.cpu_sources() {
            let key = ring_key(self.scene, source);
            let mut photons = self.trace_source(source, n, &pts, stats, &gpu_seconds)?;
            self.size(ring, key, &mut photons);
            let tc = Instant::now();
            let compensated = self.compensated(key as u32, &photons)?;
            compensation += tc.elapsed().as_secs_f64();
            ring.push(self.frame, key, photons, compensated);
            crate::cancel::check(self.progress)?;
        }
        // The trace's time less the compensation's, the GPU's and the sky pilot's, which
        // it interleaves; "sky pilot" only where the sky's photons were traced (0: kept).
        let gpu = gpu_seconds.get();
        let pilot = self.sky_pilot.take_seconds();
        let others = compensation + gpu + pilot.unwrap_or(0.0);
        fc.add_stage("cpu trace", t.elapsed().as_secs_f64() - others);
        if let Some(seconds) = pilot {
            fc.add_stage("sky pilot", seconds);
        }
        if self.gpu.is_some() {
            fc.add_stage("gpu trace", gpu);
        }
        if self.compensate {
            fc.add_stage("boundary compensation", compensation);
        }
        Ok(None)
    }

    /// [`Self::run`] with the photons left on the GPU (the checks of
    /// `super::resident::readback_reason` passed: bounce-map photons only, nothing aimed,
    /// no compensation): each light's rays continued on the GPU, the records joined and
    /// sized there; the ring gets each light's entry without photons (a new generation).
    fn run_resident(
        &self,
        g: OnGpu,
        sizing: Sizing,
        bm: &BounceMap,
        ring: &mut PhotonRing,
        fc: &mut FrameCtx,
    ) -> Result<ResidentPhotons> {
        let t = Instant::now();
        let pts = self.settings();
        let mut traced = Vec::new();
        let mut start = 0;
        while start < bm.rays.len() {
            let light = bm.ray_lights[start];
            let n = bm.ray_lights[start..].iter().take_while(|&&l| l == light);
            let end = start + n.count();
            let rays = &bm.rays[start..end];
            let seed = self.seed(light);
            traced.push(resident::continue_paths(g.ctx, g.scene, rays, &pts, seed)?);
            ring.push(self.frame, light as usize, Vec::new(), Vec::new());
            start = end;
            crate::cancel::check(self.progress)?;
        }
        let photons = resident::join(g.ctx, &traced, sizing)?;
        fc.stats.caustic_photons += photons.caustic as u64;
        fc.add_stage("cpu trace", 0.0);
        fc.add_stage("gpu trace", t.elapsed().as_secs_f64());
        Ok(photons)
    }

    /// The random seed of `light`'s photons.
    fn seed(&self, light: u32) -> u64 {
        self.params.seed ^ (light as u64).wrapping_mul(0xA24B_AED4_963E_E407)
    }

    /// The photons of one light: its first-scatter rays `range` of `bm` traced on, and
    /// (photon focusing) its aimed caustic photons.
    fn trace_light(
        &self,
        bm: &BounceMap,
        range: std::ops::Range<usize>,
        pts: &PhotonTraceSettings,
        focus: &Focus,
        stats: &mut RenderStats,
        gpu_seconds: &std::cell::Cell<f64>,
    ) -> Result<Vec<Photon>> {
        let (scene, bvh) = (self.scene, self.bvh);
        let light = bm.ray_lights[range.start];
        let seed = self.seed(light);
        let control = Checked::new(self.progress, "cpu trace");
        let aimed = focus.covers_all(light as usize);
        // Aimed: the bounce map's own mirror and glass first hits are dropped.
        let rays: Cow<[PhotonRay]> = if aimed {
            range
                .filter(|&i| !bm.first_delta[i])
                .map(|i| bm.rays[i])
                .collect()
        } else {
            Cow::Borrowed(&bm.rays[range])
        };
        // With footprints, photons that met a mirror or glass first carry the footprint
        // of their first segment from the light (re-cast on the CPU).
        let first = self
            .options
            .footprint_volumes
            .then(|| first_segment(scene, self.layers, light as usize));
        let mut photons = match self.gpu {
            Some(g) => {
                let tg = Instant::now();
                let set =
                    crate::gpu::photon::trace::continue_paths(g.ctx, g.scene, &rays, pts, seed);
                gpu_seconds.set(gpu_seconds.get() + tg.elapsed().as_secs_f64());
                set?.photons
            }
            None => continue_paths_from(scene, bvh, &rays, pts, seed, &control, first)?.photons,
        };
        if aimed {
            let texels: u64 = self
                .layers
                .iter()
                .filter(|l| l.light == light as usize)
                .map(|l| l.res as u64 * l.res as u64)
                .sum();
            let share = self.options.refine.photon_focus as f64;
            let n = ((texels as f64 * share).round() as u64).max(1);
            let li = light as usize;
            let tg = Instant::now();
            let set = match self.gpu {
                Some(g) => emitted::trace_aimed_caustics(
                    g.ctx, g.scene, scene, bvh, li, n, pts, seed, focus,
                )?,
                None => emit_aimed_caustics(scene, bvh, li, n, pts, seed, &control, focus)?,
            };
            if self.gpu.is_some() {
                gpu_seconds.set(gpu_seconds.get() + tg.elapsed().as_secs_f64());
            }
            stats.photons_emitted += n;
            photons.extend(set.photons);
        }
        stats.caustic_photons += photons
            .iter()
            .filter(|p| crate::photon::density::is_caustic(p))
            .count() as u64;
        Ok(photons)
    }

    /// The sources whose photons the bounce maps leave out (area lights, directional lights,
    /// the sky), each with its share by power of the photons the maps do not take.
    fn cpu_sources(&self) -> Vec<(Source, u64)> {
        let cpu = self.budget.cpu;
        let sources = non_local_sources(self.scene);
        let total = sources.power().element_sum() as f64;
        sources
            .list
            .iter()
            .filter_map(|(s, p)| {
                let n = (cpu as f64 * p.element_sum() as f64 / total).round() as u64;
                (n > 0 && total > 0.0).then_some((*s, n))
            })
            .collect()
    }

    /// `n` photons of `source` emitted on the CPU and traced on the CPU or the GPU (the
    /// sky's pilot on the CPU), stored from their second hit on (the first is direct
    /// light) as the bounce maps' photons are.
    fn trace_source(
        &self,
        source: Source,
        n: u64,
        pts: &PhotonTraceSettings,
        stats: &mut RenderStats,
        gpu_seconds: &std::cell::Cell<f64>,
    ) -> Result<Vec<Photon>> {
        let only = Sources::filtered(self.scene, |s| s == source);
        let key = ring_key(self.scene, source);
        let control = Checked::new(self.progress, "cpu trace");
        let seed = self.seed(key as u32);
        let mut focus = Focus::default();
        if source == Source::Environment {
            // The sky's photons, plain and aimed at the openings a pilot of as many found
            // (photon/sky_guide.rs: the balance heuristic of the two, unbiased); the pilot
            // kept while the scene's geometry, materials and sky are (photon/sky_pilot.rs).
            let pilot = n.max(PILOT_MIN);
            let rays = self
                .sky_pilot
                .rays(self.scene, self.bvh, pilot, pts, &control)?;
            let aimed = (n / PLAIN_PER_AIMED).max(1);
            focus.sky = SkyGuide::new(&rays, pilot, self.scene.bounds(), n, aimed);
        }
        let (scene, tg) = (self.scene, Instant::now());
        let mut set = match self.gpu {
            Some(g) => emitted::trace_sources(g.ctx, g.scene, scene, &only, n, pts, seed, &focus)?,
            None => emit_and_trace_sources(scene, self.bvh, &only, n, pts, seed, &control, &focus)?,
        };
        if let Some(guide) = &focus.sky {
            let aimed = match self.gpu {
                Some(g) => emitted::trace_aimed_sky(g.ctx, g.scene, scene, guide, pts, seed)?,
                None => emit_aimed_sky(scene, self.bvh, guide, n, pts, seed, &control)?,
            };
            stats.photons_emitted += guide.aimed();
            set.photons.extend(aimed.photons);
        }
        if self.gpu.is_some() {
            gpu_seconds.set(gpu_seconds.get() + tg.elapsed().as_secs_f64());
        }
        stats.photons_emitted += n;
        stats.caustic_photons += set
            .photons
            .iter()
            .filter(|p| crate::photon::density::is_caustic(p))
            .count() as u64;
        Ok(set.photons)
    }

    /// Decides the photons' volume radii, once, for the photon count the ring will hold
    /// (the splat reads `footprint_radius`), bounded by the caustic density where asked.
    fn size(&self, ring: &PhotonRing, light: usize, photons: &mut [Photon]) {
        let (o, p) = (self.options, self.params);
        let frames = (ring.held(light) + 1).min(ring.frames()) as u64;
        let radius = VolumeRadius::of_extent(self.extent, o.photons * frames, o.kernel_scale)
            .scaled(p.radius_scale);
        for photon in photons.iter_mut() {
            photon.footprint_radius = radius.of(photon);
        }
        if o.refine.caustic_density_bound {
            crate::photon::density::bound_volume_radii(photons, p.radius_scale, radius.r_max);
        }
    }

    /// The photons with their power divided by the share of their kernel on surfaces
    /// (empty when not compensating).
    fn compensated(&self, light: u32, photons: &[Photon]) -> Result<Vec<Photon>> {
        if !self.compensate {
            return Ok(Vec::new());
        }
        let mut compensated = photons.to_vec();
        let progress = self.progress;
        progress.update("boundary compensation", 0.0);
        boundary::compensate_until(
            self.scene,
            self.bvh,
            &mut compensated,
            |p| p.footprint_radius,
            Z_RATIO,
            self.seed(light),
            &|| progress.cancelled(),
        );
        crate::cancel::check(progress)?;
        Ok(compensated)
    }
}

/// Where the frame's photons go, split by power: made once a frame ([`PhotonBudget::of`])
/// and passed to the steps that need it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct PhotonBudget {
    /// The bounce maps' texels (point and spot lights).
    pub maps: u64,
    /// The photons emitted on the CPU from the other sources.
    pub cpu: u64,
}

impl PhotonBudget {
    /// The split of `photons` for `scene`.
    pub fn of(scene: &Scene, photons: u64) -> PhotonBudget {
        let total = Sources::of(scene).power().element_sum() as f64;
        let cpu = non_local_sources(scene).power().element_sum() as f64;
        if total.is_nan() || total <= 0.0 {
            return PhotonBudget {
                maps: photons,
                cpu: 0,
            };
        }
        let cpu = (photons as f64 * cpu / total).round() as u64;
        PhotonBudget {
            maps: photons - cpu.min(photons),
            cpu: cpu.min(photons),
        }
    }
}

/// The sources that the bounce maps do not see.
fn non_local_sources(scene: &Scene) -> Sources {
    Sources::filtered(scene, |s| match s {
        Source::Light(i) => !scene.lights[i].is_local(),
        _ => true,
    })
}

/// The ring's key of a source's photons: a light's index, the emitters and the environment
/// after the lights.
fn ring_key(scene: &Scene, source: Source) -> usize {
    match source {
        Source::Light(i) => i,
        Source::Emitters => scene.lights.len(),
        Source::Environment => scene.lights.len() + 1,
    }
}

/// The light of bounce-map photons of `light` and their angular spacing: the light's solid
/// angle over its bounce-map texels (a spot's square map covers about 4/π of its cone).
fn first_segment(scene: &Scene, layers: &[LightView], light: usize) -> FirstSegment {
    let l = &scene.lights[light];
    let texels: f64 = layers
        .iter()
        .filter(|b| b.light == light)
        .map(|b| (b.res as f64).powi(2))
        .sum();
    let omega = match l {
        Light::Spot { .. } => l.solid_angle() * 4.0 / std::f32::consts::PI,
        _ => l.solid_angle(),
    };
    FirstSegment {
        position: l.position(),
        spacing: (omega as f64 / texels.max(1.0)).sqrt() as f32,
    }
}
