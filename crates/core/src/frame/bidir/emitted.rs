//! VPLs of the sources that the reflective shadow maps do not see (issue 28): emitting
//! surfaces (area lights), directional lights (the sun) and the environment (the sky).
//! Their photons are emitted on the CPU by power (`scene::sources::Sources`, as photon
//! tracing emits them) and each one's first hit y1 becomes a VPL, in one more group of
//! `vpls_per_light` slots after the lights' (the lighting pass and the light subpaths treat
//! the group as one more light: the two-bounce term pairs its VPLs with the bundles, and
//! [`super::subpaths`] continues them).
//!
//! What is counted where (no path counted twice): the source's own vertex y0 (a point on an
//! emitter, or a direction of the sun or the sky) is never a VPL, so its emitted radiance
//! reaches the camera only through the direct light (the `direct` frame's sampled emitter
//! points, the sun's shadow map, the sky through the bundles) and the G-buffer; a VPL at y1
//! carries only the light y1 reflects, also when y1 lies on an emitter. The one-bounce
//! light x3 ↔ y1 ↔ y0 has no bundle strategy (a bundle hit x2 is lit by point and spot
//! lights only), so these VPLs take it alone (MIS weight 1, marked by a negative `pdf` in
//! their records) with ‖x3 − y1‖² clamped from below at [`ALONE_MIN_DIST`] of the scene's
//! diagonal (the 1/d² spike of VPLs next to x3, which the bundles remove for the RSM's
//! VPLs).

use super::subpaths::Head;
use super::vpls::{Records, VplMaps};
use crate::raster::exact_models::{material_word, model_of, record_stand_in};
use crate::raster::vpl::{cube_views, VplRaw};
use crate::sampling::Rng;
use crate::scene::light::{Emission, Light};
use crate::scene::light_views;
use crate::scene::sources::{Source, Sources};
use crate::scene::Scene;
use crate::trace::{Interaction, SceneBvh};
use bytemuck::Zeroable;
use glam::{Mat4, Vec2, Vec3};

/// The lower bound of ‖x3 − y1‖ for the one-bounce light of these VPLs, as a fraction of
/// the scene's bounding diagonal. Measured on the emitting cube of `tests/bidir.rs` (the
/// one-bounce light, 8 frames): −2.6% at 0 and at 1%, −3.8% at 2%; the sun scene's depth-2
/// mean −0.5% at 0.5%, −0.6% at 2%.
pub(super) const ALONE_MIN_DIST: f32 = 0.01;

/// The sources that the RSM does not see (all but point and spot lights), or `None` when
/// the scene has none that emit.
pub(super) fn sources(scene: &Scene) -> Option<Sources> {
    let s = Sources::filtered(scene, |s| match s {
        Source::Light(i) => !scene.lights[i].is_local(),
        _ => true,
    });
    (!s.is_empty()).then_some(s)
}

/// Emissions a slot tries before it is left empty (a source whose photons nearly all miss).
const MAX_TRIES: u32 = 64;

/// `n` photons of `sources`, the source of photon k drawn by power with u = (k + ξ)/n
/// (stratified over the sources' shares), each photon carrying its source's power over n;
/// the first hit of each. Issue 48: a photon of the sun or the sky leaves the scene more
/// often than not (they are emitted from the disc of the scene's bounding sphere), and an
/// empty slot made one frame's one-bounce light under the sky vary by 1.9% of the image. So
/// each slot of a source with two or more slots emits until a photon hits (inverse binomial
/// sampling): with h slots and N emissions in all, (h − 1)/(N − 1) is an unbiased estimate of
/// the source's hit probability, independent of where the hits lie, and it scales the hits'
/// power. A source with one slot takes one emission (`None` where it misses). A sun's slots
/// take one emission each instead, their points on the disc stratified (a Fibonacci
/// lattice under a random offset): its photons then cover the sunlit surfaces evenly (the
/// sun's one-bounce light varied by 2.1% of the image a frame, its VPLs drawn at random).
/// The emitters' slots likewise, their cosine directions stratified.
pub(super) fn heads(
    scene: &Scene,
    bvh: &SceneBvh,
    sources: &Sources,
    n: u32,
    seed: u64,
) -> Vec<Option<Head>> {
    let (mut rngs, chosen) = slot_sources(sources, n, seed);
    let mut offset_rng = Rng::new(seed, 0xe3d2, 0);
    let offset = offset_rng.next_2d();
    let slots_of = |s: Source| {
        chosen
            .iter()
            .filter(|c| c.is_some_and(|c| c.0 == s))
            .count()
    };
    let mut tries: Vec<(Source, u32, u32)> = Vec::new();
    let mut out: Vec<Option<Head>> = Vec::with_capacity(n as usize);
    for (rng, c) in rngs.iter_mut().zip(&chosen) {
        let Some((source, p)) = *c else {
            out.push(None);
            continue;
        };
        let h = slots_of(source);
        let share = p * n as f32;
        let mut head = None;
        let mut used = 0;
        let j = tries.iter().find(|t| t.0 == source).map_or(0, |t| t.1);
        if let Some(sun) = directional(scene, source).filter(|_| h >= 2) {
            // The sun: its slots' points stratified over the disc, one emission each.
            let u = lattice(j, h as u32, offset);
            let e = sun.emit_directional(rng.next_2d(), u, sources.bounds);
            head = hit_head(scene, bvh, e, share);
            used = 1;
        } else if source == Source::Emitters && h >= 2 {
            // The emitters: their slots' directions stratified (where the photons land
            // follows them), one emission each.
            let u = lattice(j, h as u32, offset);
            head = sources
                .emitters
                .emit_sample_towards(scene, rng, Some(u))
                .and_then(|(e, _)| hit_head(scene, bvh, e, share));
            used = 1;
        } else {
            let max_tries = if h >= 2 { MAX_TRIES } else { 1 };
            while head.is_none() && used < max_tries {
                used += 1;
                head = sources
                    .emit_from(scene, source, rng)
                    .and_then(|e| hit_head(scene, bvh, e, share));
            }
        }
        match tries.iter_mut().find(|t| t.0 == source) {
            Some(t) => (t.1, t.2) = (t.1 + used, t.2 + head.is_some() as u32),
            None => tries.push((source, used, head.is_some() as u32)),
        }
        out.push(head);
    }
    // The hit probability's estimate per source (1 for a source of one slot: its single
    // emission already counts its misses).
    for (h, c) in out.iter_mut().zip(&chosen) {
        let (Some(h), Some((source, _))) = (h, c) else {
            continue;
        };
        let Some(&(_, emitted, hits)) = tries.iter().find(|t| t.0 == *source) else {
            continue;
        };
        let stratified = directional(scene, *source).is_some() || *source == Source::Emitters;
        if slots_of(*source) >= 2 && !stratified {
            let p_hit = if hits >= 2 && emitted >= 2 {
                (hits - 1) as f32 / (emitted - 1) as f32
            } else {
                hits as f32 / emitted.max(1) as f32
            };
            h.alpha *= p_hit;
        }
    }
    out
}

/// The source of each of `n` slots, drawn by power with u = (k + ξ)/n, its probability,
/// and the slots' generators after that draw (which [`heads`] goes on with).
pub(super) fn slot_sources(
    sources: &Sources,
    n: u32,
    seed: u64,
) -> (Vec<Rng>, Vec<Option<(Source, f32)>>) {
    let mut rngs: Vec<Rng> = (0..n).map(|k| Rng::new(seed, 0xe3d1, k as u64)).collect();
    let chosen = rngs
        .iter_mut()
        .enumerate()
        .map(|(k, rng)| sources.choose((k as f32 + rng.next_f32()) / n as f32))
        .collect();
    (rngs, chosen)
}

/// The directional light of `source`, if it is one.
fn directional(scene: &Scene, source: Source) -> Option<&Light> {
    match source {
        Source::Light(i) => scene.lights.get(i).filter(|l| !l.is_local()),
        _ => None,
    }
}

/// Point `j` of `n` of a Fibonacci lattice in [0, 1)², moved by `offset` (mod 1):
/// stratified in both coordinates.
pub(super) fn lattice(j: u32, n: u32, offset: Vec2) -> Vec2 {
    let golden = 0.618_034f32;
    Vec2::new(
        ((j as f32 + 0.5) / n as f32 + offset.x).fract(),
        (j as f32 * golden + offset.y).fract(),
    )
}

/// The first hit of photon `e` as a subpath head, its power divided by `share` (the
/// photons' count times the source's probability), or `None` where it leaves the scene or
/// carries nothing.
pub(super) fn hit_head(scene: &Scene, bvh: &SceneBvh, e: Emission, share: f32) -> Option<Head> {
    let power = e.power / share;
    if !(power.is_finite() && power.max_element() > 0.0) {
        return None;
    }
    let hit = bvh.intersect(e.origin, e.direction, f32::INFINITY)?;
    let it = Interaction::new(scene, &hit, e.direction);
    let to_light = -e.direction;
    let cos_g = it.ng.dot(to_light).abs().max(1e-6);
    let ratio = (it.frame.n.dot(to_light).abs() / cos_g).min(10.0);
    Some(Head {
        origin: e.origin,
        position: it.position,
        ng: it.ng,
        ns: it.frame.n,
        to_light,
        material: it.material,
        model: model_of(scene, it.triangle, &it.material),
        alpha: power * ratio,
    })
}

/// The records of `heads` (one slot each, from slot `first`), appended to the VPL records:
/// on the side the light arrives from, zero flux on purely specular surfaces (the subpath
/// still continues from them), `pdf` −1 (no bundle strategy: MIS weight 1).
pub(super) fn append_records(
    scene: &Scene,
    heads: &[Option<Head>],
    maps: &VplMaps,
    records: &mut Records,
) {
    let (lo, hi) = light_views::bounds(scene);
    let diag = (hi - lo).length().max(1e-6);
    for h in heads {
        let slot = records.raws.len();
        let mut raw = VplRaw::zeroed();
        let mut m = [Mat4::IDENTITY; 6];
        if let Some(h) = h {
            let flip = if h.ng.dot(h.to_light) < 0.0 {
                -1.0
            } else {
                1.0
            };
            let (ng, ns) = (h.ng * flip, h.ns * flip);
            let p = h.position + ng * (1e-4 * diag);
            let texel_scale;
            (m, texel_scale) = cube_views(p, lo, hi, maps.size);
            let flux = if h.material.is_purely_specular() {
                Vec3::ZERO
            } else {
                h.alpha
            };
            let uber = record_stand_in(scene, h.model, &h.material);
            raw = VplRaw {
                position: p.into(),
                first_layer: 0,
                flux: flux.into(),
                texel_scale,
                to_light: h.to_light.into(),
                fresnel: material_word(uber.fresnel, h.model),
                diffuse: uber.diffuse.into(),
                roughness: uber.roughness,
                specular: uber.specular.into(),
                pdf: -1.0,
                ns: ns.into(),
                light_flux: 0.0,
                ng: ng.into(),
                light_dist2: 0.0,
            };
        }
        raw.first_layer = slot as u32 * 6;
        records.raws.push(raw);
        records.matrices.extend_from_slice(&m);
    }
}
