//! The photons of the sources the bounce maps do not see (area lights, the sun and other
//! directional lights, the sky) and the point lights' photons aimed at specular objects
//! (photon focusing) traced on the GPU: emitted on the CPU exactly as
//! `photon::trace::emit_and_trace_sources`, `emit_aimed_sky` and `emit_aimed_caustics`
//! emit them (the same
//! generator and draws: the same first segments, bit for bit), then followed from bounce 0
//! by the continuation pass ([`super::trace::continue_paths`]), which draws its own numbers
//! for the scatterings. Emission is cheap next to tracing (one source draw and a point and
//! direction per photon), and one pass follows every source's photons.

use super::scene::GpuPhotonScene;
use super::trace::continue_paths;
use crate::error::Result;
use crate::gpu::GpuContext;
use crate::photon::focus::Focus;
use crate::photon::sky_guide::SkyGuide;
use crate::photon::trace::{aimed_caustic_rays, aimed_sky_rays, emitted_rays};
use crate::photon::{PhotonSet, PhotonTraceSettings};
use crate::scene::{Scene, Sources};
use crate::trace::SceneBvh;

/// The GPU streams of the plain and the aimed photons (the continuation's numbers are a
/// hash of the path's index and the seed: two traces of one seed must not share them).
const STREAM_PLAIN: u64 = 0x6770_7565_0000_0001;
const STREAM_AIMED_SKY: u64 = 0x6770_7565_0000_0002;
const STREAM_AIMED_CAUSTICS: u64 = 0x6770_7565_0000_0003;

/// `n` photons of `sources` emitted as `emit_and_trace_sources(…, n, s, seed, …, focus)`
/// emits them and traced on the GPU with `s` (no differentials: a setting error).
#[allow(clippy::too_many_arguments)]
pub fn trace_sources(
    ctx: &GpuContext,
    gpu_scene: &GpuPhotonScene,
    scene: &Scene,
    sources: &Sources,
    n: u64,
    s: &PhotonTraceSettings,
    seed: u64,
    focus: &Focus,
) -> Result<PhotonSet> {
    let rays = emitted_rays(scene, sources, n, seed, focus);
    continue_paths(ctx, gpu_scene, &rays, s, stream(seed, STREAM_PLAIN))
}

/// The sky's aimed photons of `guide` emitted as `emit_aimed_sky(…, seed, …)` emits them
/// and traced on the GPU with `s`.
pub fn trace_aimed_sky(
    ctx: &GpuContext,
    gpu_scene: &GpuPhotonScene,
    scene: &Scene,
    guide: &SkyGuide,
    s: &PhotonTraceSettings,
    seed: u64,
) -> Result<PhotonSet> {
    let rays = aimed_sky_rays(scene, guide, seed);
    continue_paths(ctx, gpu_scene, &rays, s, stream(seed, STREAM_AIMED_SKY))
}

/// Light `li`'s `n` photons aimed by `focus` at the specular objects, emitted as
/// `emit_aimed_caustics(…, li, n, s, seed, …, focus)` emits them (its first-hit test, one
/// ray on `bvh` a photon, included) and traced on the GPU with `s`.
#[allow(clippy::too_many_arguments)]
pub fn trace_aimed_caustics(
    ctx: &GpuContext,
    gpu_scene: &GpuPhotonScene,
    scene: &Scene,
    bvh: &SceneBvh,
    li: usize,
    n: u64,
    s: &PhotonTraceSettings,
    seed: u64,
    focus: &Focus,
) -> Result<PhotonSet> {
    let rays = aimed_caustic_rays(scene, bvh, li, n, seed, focus);
    continue_paths(
        ctx,
        gpu_scene,
        &rays,
        s,
        stream(seed, STREAM_AIMED_CAUSTICS),
    )
}

fn stream(seed: u64, stream: u64) -> u64 {
    seed ^ stream.wrapping_mul(0x9E37_79B9_7F4A_7C15)
}
