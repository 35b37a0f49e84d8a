//! Light subpaths longer than one vertex (issue 29), instant-radiosity style: from every
//! first VPL y1 (`vpls_per_light` a light; issue 48: before, only from the VPL each ray
//! bundle is paired with, 16 subpaths a light at the defaults, whose few samples made one
//! frame's image mean vary by ±4% on `cornell`) a light subpath is continued on the CPU by
//! BSDF sampling, and each of its later vertices y2, y3, … becomes a VPL with its own cube
//! shadow map. A bundle connects to the subpath of the VPL it is paired with (§4.3's
//! pairing). Each path length has two strategies, combined by MIS as the one-bounce
//! light's (§4.2):
//!
//! - depth 1: direct light (the `direct` frame);
//! - depth 2: x3 ↔ y1 (VPLs) and x3 → x2 ↔ light (bundles), combined by MIS (§4.2);
//! - depth d ≥ 3: (A) x3 → x2 (bundle) ↔ y_{d−2} (the VPL of order d − 2: y1 from the RSM
//!   for d = 3, a vertex of a traced subpath for d ≥ 4), the lighting pass connecting a
//!   bundle's hit to every vertex of its bundle's subpath; (B) x3 ↔ y_{d−1}, every subpath
//!   vertex a VPL at the pixel. They differ in how the vertex next to x3 is drawn: from x3 by
//!   the bundles (area density D(ω)·|ng·ω|/d², D the bundles' density of directions) or from
//!   y_{d−2} by the subpath (n1 subpaths a light, `mis_density` each); balance heuristic on
//!   those. Where x2 and y_{d−2} are close (1/d² in A) B's density grows as fast, so A needs
//!   no clamp (it had one, ‖x2 − y‖ ≥ 10% of the diagonal, that dropped 11% of the
//!   two-bounce light on `cornell-anim`; `docs/bench/bidir-breakdown.md`), and the same
//!   holds for B where x3 and y_{d−1} are close.
//!
//! Throughput: a subpath starts from its VPL's flux α1 (the flux the lighting pass uses,
//! shading cosine included) and carries α_{j+1} = α_j · f(y_j)·|ns·ω|/p(ω) (the BSDF
//! sample's weight), with Russian roulette after the first [`RR_FREE`] vertices (continue
//! with probability q = min(0.95, max channel of the weight), α /= q): unbiased, and the
//! subpaths end after about RR_FREE + 1/(1 − albedo) vertices whatever `max_depth` is. A vertex's record carries α_j
//! times |ns·ω_in|/|ng·ω_in| (≤ 10), as the RSM's VPLs do (their flux has the geometric
//! cosine, the path tracer the shading one).
//!
//! Bias: in the single-strategy modes (`bidir_strategy` vpl or bundle) only A runs, with the
//! clamp; vertices on purely specular surfaces are passed through, not connected. The
//! records live in a fixed budget of slots ([`EXTRA_PER_SUBPATH`] per subpath on average
//! beyond the first vertex); when it runs out the highest orders are dropped first (and A's
//! weights still count on B for them: a small loss at those orders).

use super::super::options::BidirOptions;
use super::super::FrameParams;
use super::vpls::{Records, Vpl, VplMaps};
use crate::bsdf::Material;
use crate::raster::exact_models::{material_word, model_of, record_stand_in};
use crate::raster::vpl::{cube_views, VplRaw};
use crate::sampling::{Frame, Rng};
use crate::scene::light_views;
use crate::scene::Scene;
use crate::trace::{Interaction, SceneBvh};
use bytemuck::Zeroable;
use glam::{Mat4, Vec3};

/// Slots per subpath, on average, for its vertices after the first (y3, y4, …): y3 and y4,
/// then Russian roulette at the albedo ρ leaves about ρ/(1 − ρ) more (ρ = 0.5: 1, ρ = 0.67:
/// 2).
pub(super) const EXTRA_PER_SUBPATH: u32 = 4;

/// Vertices of a subpath traced without Russian roulette (y2 … y4).
const RR_FREE: u32 = 3;

/// A vertex y_j (j ≥ 2) of a light subpath.
#[derive(Clone, Copy, Debug)]
struct Vertex {
    position: Vec3,
    /// Normals on the side the light arrives from.
    ns: Vec3,
    ng: Vec3,
    /// Unit direction towards y_{j−1}.
    to_prev: Vec3,
    material: Material,
    /// Its exact model's record index + 1 (`model_of`; 0: uber).
    model: u32,
    /// Flux of the record (zero on purely specular surfaces).
    flux: Vec3,
    /// Area density of this vertex per subpath as its predecessor's (MIS) sampling gives it:
    /// q_prev · |ns_prev·ω|/π · |ng·ω| / d² (`mis_density`); 1e30 after a purely specular
    /// vertex (only the light subpath reaches it).
    density: f32,
    /// The roulette's continuation probability at this vertex as the MIS weights take it
    /// (`mis_continuation`).
    continuation: f32,
}

/// The continuation probability the MIS weights give a vertex of order `order` (the
/// subpath's y_order): 1 for the vertices traced from without roulette (y1 … y3), else the
/// roulette's q of a diffuse sample there, min(0.95, max albedo). The lighting pass takes the
/// same value (1 for y1, the record's otherwise for later vertices), so that the weights of
/// the two strategies sum to one.
fn mis_continuation(order: u32, m: &Material) -> f32 {
    if order <= RR_FREE {
        1.0
    } else {
        (m.diffuse + m.specular).max_element().clamp(0.0, 0.95)
    }
}

/// The area density the MIS weights give a vertex `position` (geometric normal `ng`) drawn
/// from `prev` (shading normal `ns_prev`, continuation `q`): a cosine density at `prev`,
/// whatever its BSDF (`bidir.wgsl` takes the same: the weights then sum to one; only their
/// variance depends on how close this is to the sampling).
pub(super) fn mis_density(prev: Vec3, ns_prev: Vec3, q: f32, position: Vec3, ng: Vec3) -> f32 {
    let d = position - prev;
    let d2 = d.length_squared().max(1e-12);
    let w = d / d2.sqrt();
    q * ns_prev.dot(w).abs() / std::f32::consts::PI * ng.dot(w).abs() / d2
}

/// The subpaths' VPL records, to be appended after the RSM's VPLs.
struct Subpaths {
    pub raws: Vec<VplRaw>,
    pub matrices: Vec<Mat4>,
    /// Subpaths with at least one vertex.
    pub placed: usize,
    /// Slots up to the last one holding a vertex (the lighting pass's strategy-B loop runs
    /// over these alone).
    pub used: usize,
}

/// Slots for subpath vertices: one per (light, VPL) for the first vertex y2 (every VPL is
/// continued: `n1` subpaths a light), and [`EXTRA_PER_SUBPATH`] per subpath for the rest, as
/// far as `max_slots` (the VPLs the GPU's shadow-map layers hold) leaves room after the
/// `first` slots of the first VPLs. Zero when `max_depth` asks for no vertex after y1
/// (depth < 3: strategy B of depth d takes y_{d−1}) or there are no bundles.
pub(super) fn slots(
    lights: u32,
    n1: u32,
    bundles: u32,
    max_depth: u32,
    first: u32,
    max_slots: u32,
) -> u32 {
    if max_depth < 3 || bundles == 0 {
        return 0;
    }
    let heads = lights * n1;
    let extra = if max_depth > 3 {
        heads * EXTRA_PER_SUBPATH
    } else {
        0
    };
    let room = max_slots.saturating_sub(first);
    if room < heads {
        // No room for the subpaths: the GPU's VPL-count error follows from the caller.
        return heads + extra;
    }
    heads + extra.min(room - heads)
}

/// The VPL the lighting pass pairs bundle `b` with: ⌊(b + u)·n1/n2⌋, u the pixel's offset
/// (`bidir.wgsl`'s `pixel_pair_offset`; its subpath is the one strategy A of that bundle
/// continues at that pixel).
#[cfg(test)]
fn paired_vpl(b: u32, pair_offset: f32, n1: u32, n2: u32) -> u32 {
    (((b as f32 + pair_offset) * n1 as f32 / n2 as f32) as u32).min(n1.saturating_sub(1))
}

/// The first vertex of a light subpath (y1): an RSM VPL, or the first hit of a photon
/// emitted by a source the RSM does not see ([`super::emitted`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Head {
    /// Where its light left the source (y0: the light's position, the emission's origin).
    pub origin: Vec3,
    pub position: Vec3,
    /// Geometric and shading normals (any side).
    pub ng: Vec3,
    pub ns: Vec3,
    /// Unit direction towards where the light came from (ω1,0).
    pub to_light: Vec3,
    pub material: Material,
    /// Its exact model's record index + 1 (`raster::exact_models::model_of`; 0: uber).
    pub model: u32,
    /// α1: the VPL's flux, shading-cosine corrected as its record.
    pub alpha: Vec3,
}

impl Head {
    /// The head of RSM VPL `v` (its light a point or spot light). Its material is the
    /// scene's exact one (a Mitsuba conductor or coating, not the uber stand-in the RSM
    /// holds: the subpath samples it on the CPU), found by the ray from the light to the
    /// texel; the texel's uber parameters where that ray meets another surface first (a
    /// texel the rasterizer saw past an edge).
    pub fn of_rsm(scene: &Scene, bvh: &SceneBvh, v: &Vpl) -> Head {
        let t = &v.texel;
        let light = &scene.lights[v.light];
        let to_light = (light.position() - t.position).normalize_or_zero();
        let cos_g = t.ng.dot(to_light).abs().max(1e-6);
        let ratio = (t.ns.dot(to_light).abs() / cos_g).min(10.0);
        let uber = Material {
            diffuse: t.diffuse,
            specular: t.specular,
            roughness: t.roughness,
            fresnel: t.fresnel,
            transmission: Vec3::ZERO,
            ..Material::default()
        };
        let (material, model) =
            exact_material(scene, bvh, light.position(), t.position).unwrap_or((uber, 0));
        Head {
            origin: light.position(),
            position: t.position,
            ng: t.ng,
            ns: t.ns,
            to_light,
            material,
            model,
            alpha: v.flux * ratio,
        }
    }
}

/// The material of the surface at `point` as the ray from `from` meets it, and its exact
/// model's record index + 1 (`model_of`): `None` where the ray meets nothing within 0.1% of
/// the distance (plus a 1e-4 floor) around `point`.
fn exact_material(
    scene: &Scene,
    bvh: &SceneBvh,
    from: Vec3,
    point: Vec3,
) -> Option<(Material, u32)> {
    let d = point - from;
    let dist = d.length();
    if !(dist > 0.0 && dist.is_finite()) {
        return None;
    }
    let dir = d / dist;
    let tol = 1e-3 * dist + 1e-4;
    let hit = bvh.intersect(from, dir, dist + tol)?;
    let it = Interaction::new(scene, &hit, dir);
    ((it.position - point).length() <= tol)
        .then_some((it.material, model_of(scene, it.triangle, &it.material)))
}

/// The first vertex after `h`'s and the ones after it, up to `max_len` (orders 2 … ≤
/// max_depth − 1), by BSDF sampling with Russian roulette.
/// With `light_traced` (the head of a point or spot light's RSM) a delta lobe sampled at
/// the head ends the subpath: those paths are the light tracer's
/// ([`super::specular_paths::caustics`]).
fn trace(
    scene: &Scene,
    bvh: &SceneBvh,
    h: &Head,
    max_len: u32,
    light_traced: bool,
    rng: &mut Rng,
) -> Vec<Vertex> {
    let mut alpha = h.alpha;
    let mut material = h.material;
    let (mut position, mut ng, mut frame, mut w_prev) =
        (h.position, h.ng, Frame::new(h.ns), h.to_light);
    let mut out = Vec::new();
    // MIS: the predecessor's continuation and whether it was purely specular.
    let (mut q_mis, mut ns_prev, mut specular_prev) =
        (1.0f32, h.ns, h.material.is_purely_specular());
    while (out.len() as u32) < max_len {
        let Some(bs) = material.sample_adjoint(frame.to_local(w_prev), rng) else {
            break;
        };
        if light_traced && out.is_empty() && bs.lobe.is_delta() {
            break;
        }
        let wi = frame.to_world(bs.wi);
        let same_side = wi.dot(ng) * w_prev.dot(ng) > 0.0;
        if same_side == bs.lobe.crosses() {
            break;
        }
        // Roulette only past the first RR_FREE vertices: every subpath reaches y2 … y4
        // (depths 4–6), whose light would otherwise vary with how many of the frame's few
        // subpaths survive.
        let q = if (out.len() as u32) < RR_FREE {
            1.0
        } else {
            bs.weight.max_element().min(0.95)
        };
        if q.is_nan() || q <= 0.0 || (q < 1.0 && rng.next_f32() >= q) {
            break;
        }
        alpha *= bs.weight / q;
        let eps = 1e-4 * (1.0 + position.abs().max_element());
        let origin = position + ng * eps * wi.dot(ng).signum();
        let Some(hit) = bvh.intersect(origin, wi, f32::INFINITY) else {
            break;
        };
        let it = Interaction::new(scene, &hit, wi);
        let flip = if it.ng.dot(wi) > 0.0 { -1.0 } else { 1.0 };
        let (ng_f, ns_f) = (it.ng * flip, it.frame.n * flip);
        let to_prev = -wi;
        let cos_g = ng_f.dot(to_prev).abs().max(1e-6);
        let ratio = (ns_f.dot(to_prev).abs() / cos_g).min(10.0);
        let flux = if it.material.is_purely_specular() || !alpha.is_finite() {
            Vec3::ZERO
        } else {
            alpha * ratio
        };
        let density = if specular_prev {
            1e30
        } else {
            mis_density(position, ns_prev, q_mis, it.position, ng_f)
        };
        let continuation = mis_continuation(out.len() as u32 + 2, &it.material);
        out.push(Vertex {
            position: it.position,
            ns: ns_f,
            ng: ng_f,
            to_prev,
            material: it.material,
            model: model_of(scene, it.triangle, &it.material),
            flux,
            density,
            continuation,
        });
        (q_mis, ns_prev, specular_prev) = (continuation, ns_f, it.material.is_purely_specular());
        (position, ng, frame, w_prev, material) =
            (it.position, it.ng, it.frame, to_prev, it.material);
    }
    out
}

/// Appends to the RSM's VPL `records` (n1 per light) the frame's light subpaths, one per
/// (light, bundle) from the VPL the bundle is paired with, filling the rest of `maps`'
/// capacity; returns how many subpaths have a vertex and how many slots from the first
/// hold the vertices. See [`subpaths`].
pub(super) fn append(
    scene: &Scene,
    bvh: &SceneBvh,
    groups: &[Vec<Option<Head>>],
    options: &BidirOptions,
    frame: &FrameParams,
    maps: &VplMaps,
    records: &mut Records,
) -> (usize, usize) {
    let first = records.raws.len() as u32;
    let out = subpaths(scene, bvh, groups, options, maps, first, frame.seed);
    records.raws.extend(out.raws);
    records.matrices.extend(out.matrices);
    (out.placed, out.used)
}

/// The subpaths as records for slots `first`, `first + 1`, … (`slots` of them): one subpath
/// from each first VPL y1 (`n1` a light), the first vertex of subpath (light j, VPL k) in
/// slot `first + j·n1 + k` (bundle b connects to the subpath of the VPL it is paired with,
/// `paired_vpl`), each record's
/// `light_dist2` holding the slot of the subpath's next vertex (0: none; the field is
/// unused beyond the RSM's VPLs). Later vertices are placed order by order, so that a full
/// budget drops the highest orders.
fn subpaths(
    scene: &Scene,
    bvh: &SceneBvh,
    groups: &[Vec<Option<Head>>],
    options: &BidirOptions,
    maps: &VplMaps,
    first: u32,
    seed: u64,
) -> Subpaths {
    let (n1, max_depth) = (options.vpls_per_light, options.max_depth);
    let (slots, size) = (maps.capacity.saturating_sub(first), maps.size);
    let lights = groups.len();
    let heads = lights * n1 as usize;
    let mut out = Subpaths {
        raws: vec![VplRaw::zeroed(); slots as usize],
        matrices: vec![Mat4::IDENTITY; slots as usize * 6],
        placed: 0,
        used: 0,
    };
    if slots == 0 || heads > slots as usize {
        return out;
    }
    let max_len = max_depth.saturating_sub(2);
    // The sun's, sky's and emitters' subpaths partly aimed at glass (issue 44 item 4).
    let aimed = super::glass_aim::aimed_groups(scene, bvh, groups, seed);
    let groups = aimed.as_deref().unwrap_or(groups);
    let mut paths: Vec<Vec<Vertex>> = vec![Vec::new(); heads];
    for (light, own) in groups.iter().enumerate() {
        for k in 0..n1 as usize {
            if let Some(Some(v)) = own.get(k) {
                let i = light * n1 as usize + k;
                let mut rng = Rng::new(seed, 0x5b9a, i as u64);
                let light_traced = scene.lights.get(light).is_some_and(|l| l.is_local());
                paths[i] = trace(scene, bvh, v, max_len, light_traced, &mut rng);
            }
        }
    }
    // Slots: heads fixed, then order by order.
    let mut slot_of: Vec<Vec<usize>> = paths.iter().map(|_| Vec::new()).collect();
    let mut next = heads;
    let longest = paths.iter().map(Vec::len).max().unwrap_or(0);
    for order in 0..longest {
        for (i, p) in paths.iter().enumerate() {
            if order >= p.len() || slot_of[i].len() < order {
                continue;
            }
            if order == 0 {
                slot_of[i].push(i);
            } else if next < slots as usize {
                slot_of[i].push(next);
                next += 1;
            }
        }
    }
    out.placed = slot_of.iter().filter(|s| !s.is_empty()).count();
    out.used = if out.placed == 0 { 0 } else { next };
    let (lo, hi) = light_views::bounds(scene);
    let diag = (hi - lo).length().max(1e-6);
    for (p, s) in paths.iter().zip(&slot_of) {
        for (j, &slot) in s.iter().enumerate() {
            let v = &p[j];
            let pos = v.position + v.ng * (1e-4 * diag);
            let (m, texel_scale) = cube_views(pos, lo, hi, size);
            out.matrices[slot * 6..slot * 6 + 6].copy_from_slice(&m);
            let next = s.get(j + 1).map_or(0.0, |&n| (first as usize + n) as f32);
            let uber = record_stand_in(scene, v.model, &v.material);
            out.raws[slot] = VplRaw {
                position: pos.into(),
                first_layer: 0,
                flux: v.flux.into(),
                texel_scale,
                to_light: v.to_prev.into(),
                fresnel: material_word(uber.fresnel, v.model),
                diffuse: uber.diffuse.into(),
                roughness: uber.roughness,
                specular: uber.specular.into(),
                pdf: v.density,
                ns: v.ns.into(),
                light_flux: v.continuation,
                ng: v.ng.into(),
                light_dist2: next,
            };
        }
    }
    for (slot, r) in out.raws.iter_mut().enumerate() {
        r.first_layer = (first as usize + slot) as u32 * 6;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slots_fit_the_budget_and_the_gpu() {
        assert_eq!(slots(1, 64, 16, 2, 64, 1000), 0);
        assert_eq!(slots(1, 64, 0, 7, 64, 1000), 0);
        assert_eq!(slots(2, 16, 4, 3, 32, 1000), 32);
        assert_eq!(slots(2, 16, 4, 7, 32, 1000), 32 * (1 + EXTRA_PER_SUBPATH));
        // The extra slots shrink to what the GPU holds.
        assert_eq!(slots(1, 16, 4, 64, 64, 100), 36);
    }

    /// `bidir.wgsl`'s 4×4 Bayer matrix of the pixels' pairing offsets.
    fn pixel_offsets() -> Vec<u32> {
        let wgsl = include_str!("../../raster/shaders/bidir.wgsl");
        let start = wgsl.find("array<u32, 16>(").expect("the Bayer matrix") + 15;
        let end = start + wgsl[start..].find(')').expect("its end");
        wgsl[start..end]
            .split(',')
            .map(|v| v.trim().trim_end_matches('u').parse().expect("an integer"))
            .collect()
    }

    #[test]
    fn every_2x2_block_pairs_the_bundles_with_all_vpls() {
        // Issue 48: with one pairing offset for the image, every pixel's strategy A took the
        // same n2 of the n1 subpaths. The pixels' offsets u + bayer/16 (mod 1): a 4×4 block
        // takes all 16 offsets, and at n1/n2 = 4 (the defaults, 64 VPLs and 16 bundles)
        // every aligned 2×2 block pairs bundle b with all of VPLs 4b … 4b + 3.
        let bayer = pixel_offsets();
        let mut sorted = bayer.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..16).collect::<Vec<u32>>());
        for u in [0.0, 0.1, 0.37, 0.9999] {
            for (bx, by) in [(0, 0), (2, 0), (0, 2), (2, 2)] {
                for b in 0..16 {
                    let mut ks: Vec<u32> = [(0, 0), (1, 0), (0, 1), (1, 1)]
                        .iter()
                        .map(|(x, y)| {
                            let o = (u + bayer[(by + y) * 4 + bx + x] as f32 / 16.0).fract();
                            paired_vpl(b, o, 64, 16)
                        })
                        .collect();
                    ks.sort_unstable();
                    assert_eq!(ks, (4 * b..4 * b + 4).collect::<Vec<u32>>(), "u {u} b {b}");
                }
            }
        }
    }

    #[test]
    fn every_bundle_pairs_with_a_vpl_in_range() {
        for (n1, n2) in [(64, 16), (8, 32), (1, 1), (5, 3)] {
            let ks: Vec<u32> = (0..n2).map(|b| paired_vpl(b, 0.999, n1, n2)).collect();
            assert!(ks.iter().all(|&k| k < n1), "{ks:?}");
            assert!(ks.windows(2).all(|w| w[0] <= w[1]), "{ks:?}");
        }
    }
}
