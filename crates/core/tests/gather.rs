//! Method `gather` (photon differentials + linear-BVH footprint photon map) against ground
//! truth: the analytic furnace and the reference path tracer.

use gi_core::photon::{emit_and_trace, PathKind};
use gi_core::scene::builtin;
use gi_core::trace::SceneBvh;
use gi_core::Image;
use gi_core::{render, Silent};

fn block_means(img: &Image, block: u32) -> Vec<glam::Vec3> {
    let (bw, bh) = (img.width / block, img.height / block);
    let mut out = vec![glam::Vec3::ZERO; (bw * bh) as usize];
    for y in 0..bh * block {
        for x in 0..bw * block {
            out[((y / block) * bw + x / block) as usize] += img.get(x, y) / (block * block) as f32;
        }
    }
    out
}

#[test]
fn furnace_matches_analytic() {
    let scene = builtin::load("furnace").unwrap();
    let s = gi_core::options!(Gather, spp: 1, width: 32, height: 32, photons: 200_000);
    let out = render(&scene, &s, &Silent).unwrap();
    // L = ρI/(πR²(1−ρ)) = 1/π for ρ = 0.5, I = R = 1. Direct light is exact (NEE); the
    // indirect half carries the photon noise (~0.3% for the image mean) and the footprint
    // bias, which on the smooth furnace is small: 3% bound.
    let expected = 1.0 / std::f32::consts::PI;
    let mean = out.radiance.mean();
    for c in 0..3 {
        let rel = (mean[c] - expected) / expected;
        assert!(
            rel.abs() < 0.03,
            "channel {c}: {} vs {expected} ({:+.2}%)",
            mean[c],
            rel * 100.0
        );
    }
}

#[test]
fn cornell_matches_reference() {
    let scene = builtin::load("cornell").unwrap();
    let size = (Some(48), Some(48));
    let reference = gi_core::options!(Path, spp: 512, width: size.0, height: size.1, seed: 9);
    let reference = render(&scene, &reference, &Silent).unwrap().radiance;
    let s = gi_core::options!(Gather, spp: 16, width: size.0, height: size.1, photons: 400_000);
    let out = render(&scene, &s, &Silent).unwrap().radiance;
    // Mean relative error over 8×8-pixel blocks, per channel: 3% (the bound;
    // measured 1.4–1.6% with the scale-free compression of diffuse footprints, 1.6–1.8% with
    // the paper's literal one, mostly footprint noise, with the image mean within 0.3%).
    let (a, b) = (block_means(&out, 8), block_means(&reference, 8));
    let mut err = glam::Vec3::ZERO;
    for (x, y) in a.iter().zip(&b) {
        err += ((*x - *y).abs() / y.max(glam::Vec3::splat(1e-3))) / a.len() as f32;
    }
    eprintln!("gather vs path, mean relative block error per channel: {err}");
    assert!(err.max_element() < 0.03, "mean relative block error {err}");
}

/// Photon differentials follow the focusing and defocusing of the curved mirror ring (the
/// paper's "Ring" scene): on the floor inside the ring, caustic photons (light → ring →
/// floor) spread over a far wider range of footprint radii than photons straight from the
/// light, with the focused ones (near the cardioid) smaller than any direct photon's.
/// Without the normal derivatives of curved surfaces, neither tail would appear.
#[test]
fn caustic_footprints_follow_focusing() {
    let scene = builtin::load("caustic-ring").unwrap();
    let bvh = SceneBvh::build(&scene);
    let photons = 200_000;
    let s = gi_core::options!(Gather, photons: photons);
    let mut ts = gi_core::frame::gather::gather_trace_settings(&scene, &s);
    ts.store_direct = true;
    let set = emit_and_trace(&scene, &bvh, photons, &ts, 1);
    let percentiles = |kind: PathKind| {
        let mut r: Vec<f32> = set
            .photons
            .iter()
            .zip(&set.footprints)
            .filter(|(p, f)| {
                f.kind == kind
                    && p.position[1].abs() < 1e-3
                    && p.position[0].hypot(p.position[2]) < 0.95
            })
            .map(|(_, f)| f.radius())
            .collect();
        assert!(r.len() > 1000, "{kind:?}: {} photons", r.len());
        r.sort_by(f32::total_cmp);
        let p = |q: usize| r[r.len() * q / 100];
        eprintln!(
            "{kind:?} radii (m): p5 {:.4} p50 {:.4} p90 {:.4}",
            p(5),
            p(50),
            p(90)
        );
        (p(5), p(90))
    };
    let (c5, c90) = percentiles(PathKind::Caustic);
    let (d5, d90) = percentiles(PathKind::Direct);
    assert!(
        c5 < 0.75 * d5,
        "focused caustic footprints: p5 {c5} vs direct p5 {d5}"
    );
    assert!(
        c90 > 2.0 * d90,
        "defocused caustic footprints: p90 {c90} vs direct p90 {d90}"
    );
}

/// Photons of `scene` traced as method `gather` does, with direct hits stored too.
fn trace_footprints(scene: &gi_core::Scene, photons: u64, seed: u64) -> gi_core::photon::PhotonSet {
    let bvh = SceneBvh::build(scene);
    let s = gi_core::options!(Gather, photons: photons);
    let mut ts = gi_core::frame::gather::gather_trace_settings(scene, &s);
    ts.store_direct = true;
    emit_and_trace(scene, &bvh, photons, &ts, seed)
}

/// Footprints are scale-free: the same scene in centimetres (coordinates ×100, intensities
/// ×100² so that irradiance is unchanged) gives every photon a footprint 100 times wider,
/// including the compressed diffuse ones (whose reference length scales with the scene).
#[test]
fn footprints_scale_with_the_scene() {
    use gi_core::scene::Light;
    let scene = builtin::load("cornell").unwrap();
    let k = 100.0f32;
    let mut big = scene.clone();
    // Every object scaled about the origin (objects are instances: their meshes stay, the
    // transforms and the flat view change).
    for object in 0..big.objects.len() {
        let transform =
            glam::Mat4::from_scale(glam::Vec3::splat(k)) * big.objects[object].transform;
        big.apply(&gi_core::scene::SceneUpdate::Transform { object, transform })
            .expect("a valid scale");
    }
    for l in &mut big.lights {
        match l {
            Light::Point {
                position,
                intensity,
            }
            | Light::Spot {
                position,
                intensity,
                ..
            } => {
                *position *= k;
                *intensity *= k * k;
            }
            Light::Directional { .. } => {}
        }
    }
    let (a, b) = (
        trace_footprints(&scene, 20_000, 3),
        trace_footprints(&big, 20_000, 3),
    );
    // The same random numbers trace the same paths, except where the surface offset of a
    // spawned ray (1e-4·(1 + |p|), not scale-free) changes a near-grazing hit: such a path
    // diverges, so photons are paired by position (b = k·a) and re-synchronised after a
    // mismatch by the nearest later pair that agrees.
    let same = |i: usize, j: usize| {
        let (pa, pb) = (&a.photons[i], &b.photons[j]);
        pa.bounce == pb.bounce
            && a.footprints[i].kind == b.footprints[j].kind
            && (pb.position() - k * pa.position()).length() < 1e-3 * k
    };
    let (mut i, mut j, mut unpaired, mut diffuse) = (0, 0, 0, 0);
    let mut deviation = Vec::new();
    while i < a.photons.len() && j < b.photons.len() {
        if !same(i, j) {
            let Some((di, dj)) = (1..64)
                .flat_map(|s| (0..=s).map(move |di| (di, s - di)))
                .find(|&(di, dj)| {
                    i + di < a.photons.len() && j + dj < b.photons.len() && same(i + di, j + dj)
                })
            else {
                break;
            };
            unpaired += di + dj;
            (i, j) = (i + di, j + dj);
        }
        let (ra, rb) = (a.photons[i].footprint_radius, b.photons[j].footprint_radius);
        let kind = a.footprints[i].kind;
        deviation.push((rb / (k * ra) - 1.0).abs());
        diffuse += (kind == PathKind::Diffuse) as usize;
        (i, j) = (i + 1, j + 1);
    }
    unpaired += (a.photons.len() - i) + (b.photons.len() - j);
    let paired = deviation.len();
    let p99 = {
        deviation.sort_by(f32::total_cmp);
        deviation[paired * 99 / 100]
    };
    eprintln!(
        "{paired} photon pairs ({diffuse} diffuse), {unpaired} unpaired; relative deviation \
         of the radius ratio from {k}: median {:e}, p99 {p99:e}, worst {:e}",
        deviation[paired / 2],
        deviation[paired - 1]
    );
    // Measured: 3% unpaired, median deviation 8e-5 (the reference length moves by that
    // much with the unpaired photons), p99 1.2e-4. The paper's literal ‖∂p‖^(−3/4) would
    // put every diffuse photon off by a factor 100^(3/4) ≈ 32.
    assert!(
        diffuse > 5000 && unpaired * 10 < paired,
        "{paired} paired, {unpaired} not"
    );
    assert!(p99 < 1e-3, "p99 relative deviation {p99}");
}

/// Median of `v` (sorted in place); NaN when empty.
fn median(v: &mut [f32]) -> f32 {
    v.sort_by(f32::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f32::NAN)
}

/// The paper's Table 3 claim, where it matters: in the bright region of a caustic, caustic
/// photons' footprints are far smaller than those of the diffusely reflected photons landing
/// there, so the gather resolves the caustic while smoothing the indirect light.
///
/// The region comes from photon counts alone (5 cm floor cells where the caustic photons'
/// power exceeds the direct light's), never from the footprints, so the comparison is not
/// true by construction. It measures the diffuse footprints' compression: diffuse photons
/// carry their whole path length and Russian-roulette widening, and the scale-free
/// compression keeps them near their geometric-mean size (measured: caustic median 0.025 m,
/// diffuse 0.147 m, ratio 0.17). The literal ‖∂p‖^(−3/4) of the paper, in this metre-scale
/// scene, shrinks the diffuse ones below the caustic ones and fails it (measured: diffuse
/// median 0.011 m, ratio 2.2). The margin 0.5 (a quarter of the area) is "far smaller"
/// with a factor 3 of headroom. The focusing itself is `caustic_footprints_follow_focusing`'s
/// business: without the ring's normal derivatives this ratio only rises to 0.25.
#[test]
fn caustic_footprints_are_far_smaller_where_the_caustic_is() {
    let scene = builtin::load("ring-room").unwrap();
    let set = trace_footprints(&scene, 400_000, 1);
    let table =
        gi_core::photon::footprint_map::radius_percentiles(&set, &[5.0, 25.0, 50.0, 75.0, 95.0]);
    for (kind, n, r) in &table {
        eprintln!("{kind:?}: {n} photons, radius p5/25/50/75/95 (m) {r:.4?}");
    }

    // Power per 5 cm floor cell, per kind.
    const CELL: f32 = 0.05;
    const N: usize = (4.0 / CELL) as usize;
    let cell = |p: &gi_core::photon::Photon| {
        let on_floor = p.position[1].abs() < 1e-3 && p.normal[1] > 0.9;
        let (x, z) = ((p.position[0] + 2.0) / CELL, (p.position[2] + 2.0) / CELL);
        (on_floor && (0.0..N as f32).contains(&x) && (0.0..N as f32).contains(&z))
            .then(|| z as usize * N + x as usize)
    };
    let (mut caustic, mut direct) = (vec![0.0f32; N * N], vec![0.0f32; N * N]);
    for (p, f) in set.photons.iter().zip(&set.footprints) {
        if let Some(c) = cell(p) {
            match f.kind {
                PathKind::Caustic => caustic[c] += p.power().element_sum(),
                PathKind::Direct => direct[c] += p.power().element_sum(),
                PathKind::Diffuse => {}
            }
        }
    }
    let in_caustic = |c: usize| caustic[c] > direct[c];
    let cells = (0..N * N).filter(|&c| in_caustic(c)).count();
    let radii = |kind: PathKind| {
        let mut r: Vec<f32> = set
            .photons
            .iter()
            .zip(&set.footprints)
            .filter(|(p, f)| f.kind == kind && cell(p).is_some_and(in_caustic))
            .map(|(_, f)| f.radius())
            .collect();
        let n = r.len();
        (n, median(&mut r))
    };
    let (nc, c50) = radii(PathKind::Caustic);
    let (nd, d50) = radii(PathKind::Diffuse);
    eprintln!(
        "caustic region: {cells} cells of {CELL} m; median radius caustic {c50:.4} m ({nc} photons), \
         diffuse {d50:.4} m ({nd} photons), ratio {:.3}",
        c50 / d50
    );
    assert!(nc > 1000 && nd > 1000, "{nc} caustic, {nd} diffuse photons");
    assert!(
        c50 < 0.5 * d50,
        "caustic median {c50} vs diffuse median {d50}"
    );
}

/// No streaks (issue 46, item 8): a photon refracted near the glass sphere's rim or arriving
/// at a grazing angle has a footprint hundreds of times longer than wide, which its few
/// neighbours cannot hide, and long thin bright lines crossed `cornell-glass`'s walls (the
/// README's viewer example at 20k photons). Every footprint is now at most
/// `MAX_ELONGATION` (4) times longer than wide: before, the caustic photons' p99 was 52
/// and their largest 160 at 20k photons, 2,600 at 200k (diffuse photons, whose principal
/// axes rather than skewed semi-diameters are compressed now, reached 6 and 14 before the
/// cap, p99.9 3).
#[test]
fn footprints_are_not_streaks() {
    use gi_core::photon::differential::{elongation, MAX_ELONGATION};
    let scene = builtin::load("cornell-glass").unwrap();
    let set = trace_footprints(&scene, 20_000, 5);
    for kind in [PathKind::Caustic, PathKind::Diffuse] {
        let e: Vec<f32> = set
            .footprints
            .iter()
            .filter(|f| f.kind == kind)
            .map(|f| elongation(f.axes))
            .collect();
        assert!(e.len() > 300, "{kind:?}: {} photons", e.len());
        let worst = e.iter().copied().fold(0.0f32, f32::max);
        eprintln!(
            "{kind:?}: {} footprints, largest elongation {worst}",
            e.len()
        );
        assert!(
            worst <= MAX_ELONGATION * 1.001,
            "{kind:?}: elongation {worst}"
        );
    }
}
