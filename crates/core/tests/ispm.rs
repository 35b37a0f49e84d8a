//! Method `ispm` (GPU bounce map + CPU photon tracing + GPU photon volumes, lavapipe in CI).
//!
//! - furnace: the indirect part (ispm − direct) against the analytic value;
//! - bounce-map power bookkeeping (emitted = light power, first scatter = ρ × emitted);
//! - Cornell box against the reference path tracer (block error, image mean, SSIM);
//! - caustic: the caustic region is brighter than its surroundings.

mod common;

use common::{block_means, lit_pixels, load, max_difference, mean, run};
use gi_core::frame::options::IspmOptions;
use gi_core::frame::options::VolumeShape;
use gi_core::{render, scene::builtin, Method, RenderOutput, Scene};
use gi_core::{MethodOptions, RenderOptions, Silent};
use glam::DVec3;
use std::f64::consts::PI;

/// ISPM at full-resolution splats (subsample 1): the accuracy tests measure the estimator,
/// the subsampled path has its own comparison.
fn ispm_settings(size: u32) -> gi_core::RenderOptions {
    gi_core::options!(Ispm, subsample: 1, spp: 1, width: size, height: size, seed: 7)
}

/// Furnace (ρ = 0.5, I = 1, R = 1): indirect radiance = ρE0/(π(1−ρ)) − ρE0/π = 0.5/π.
#[test]
fn furnace_indirect_matches_analytic() {
    let scene = load("furnace");
    let s = ispm_settings(48);
    let ispm = run(&scene, &s);
    let direct = run(&scene, &s.clone().with_method(gi_core::Method::Direct));
    let indirect = mean(&ispm.radiance) - mean(&direct.radiance);
    let expected = 0.5 / PI;
    eprintln!(
        "furnace indirect {indirect:?} expected {expected:.5}; stats {:?}",
        ispm.stats
    );
    for c in indirect.to_array() {
        assert!(
            (c / expected - 1.0).abs() < 0.03,
            "{indirect:?} vs {expected}"
        );
    }
}

/// Bounce-map texels carry the light's power; the first scatter keeps ρ of it (furnace,
/// closed sphere: every texel hits); all rays are stored at bounce 1 by the CPU tracer, and
/// each later bounce keeps ρ of the one before.
#[test]
fn bounce_map_power_bookkeeping() {
    let scene = load("furnace");
    let s = ispm_settings(16).with("photons", 100_000);
    let bm = gi_core::frame::bounce_map(&scene, &s).expect("bounce map");
    let power = 4.0 * PI;
    eprintln!(
        "texels {} covered {} incident {:?} scattered {:?} expected {:?} rays {}",
        bm.texels,
        bm.covered,
        bm.incident_power,
        bm.scattered_power,
        bm.expected_scattered_power,
        bm.rays.len()
    );
    assert_eq!(bm.covered, bm.texels);
    for c in bm.incident_power.to_array() {
        assert!((c / power - 1.0).abs() < 1e-3, "{c} vs {power}");
    }
    // Russian roulette keeps the largest channel: survivors ≈ ρ·texels, each with Φ/ρ·ρ.
    let expected = 0.5 * power;
    let n = bm.covered as f64;
    let sigma = expected * (0.5 / (0.5 * n)).sqrt();
    for (c, e) in bm
        .scattered_power
        .to_array()
        .into_iter()
        .zip(bm.expected_scattered_power.to_array())
    {
        assert!((e / expected - 1.0).abs() < 1e-3, "{e}");
        assert!(
            (c - expected).abs() < 4.0 * sigma,
            "{c} vs {expected} ± {sigma}"
        );
    }
    // Stored at bounce 1: the sum of the rays' power.
    let bvh = gi_core::trace::SceneBvh::build(&scene);
    let pts = gi_core::photon::PhotonTraceSettings {
        max_bounces: 4,
        store_direct: false,
        differentials: None,
    };
    let set = gi_core::photon::continue_paths(&scene, &bvh, &bm.rays, &pts, 1);
    let stored = set.power_per_bounce();
    assert_eq!(stored[0], DVec3::ZERO);
    let rel = (stored[1] - bm.scattered_power).abs().max_element() / expected;
    assert!(rel < 1e-4, "{:?} vs {:?}", stored[1], bm.scattered_power);
    // Later bounces on the CPU: each photon stored at bounce k − 1 scatters on with
    // probability ρ = 0.5 (Russian roulette on the grey albedo) carrying its power, and
    // every scattered ray hits the closed sphere, so the power stored at bounce k is
    // ρ × that of bounce k − 1, within 4σ of the Bernoulli sum (σ² = Σ Φ²·ρ(1 − ρ)).
    for k in 2..=4u32 {
        let parents: Vec<f64> = set
            .photons
            .iter()
            .filter(|p| p.bounce == k - 1)
            .map(|p| p.power[0] as f64)
            .collect();
        let prev: f64 = parents.iter().sum();
        let sigma = (parents.iter().map(|p| p * p * 0.25).sum::<f64>()).sqrt();
        eprintln!(
            "bounce {k}: stored {:.5} expected {:.5} ± {sigma:.5}",
            stored[k as usize].x,
            0.5 * prev
        );
        assert!(
            (stored[k as usize].x - 0.5 * prev).abs() < 4.0 * sigma,
            "bounce {k}: {} vs {} ± {sigma}",
            stored[k as usize].x,
            0.5 * prev
        );
    }
}

/// Mean radiance per channel over pixels `keep`.
fn region_mean(img: &gi_core::image::Image, keep: &[bool]) -> DVec3 {
    let (sum, n) = img
        .pixels
        .iter()
        .zip(keep)
        .filter(|(_, k)| **k)
        .fold((DVec3::ZERO, 0usize), |(s, n), (p, _)| {
            (s + p.as_dvec3(), n + 1)
        });
    sum / n.max(1) as f64
}

/// Cornell box: ISPM (direct + photon volumes, 400k bounce-map photons) against the path
/// tracer (512 spp), 48×48, with the issue's criteria:
/// - mean relative error per channel over the 36 blocks of 8×8 pixels ≤ 3% (the metric of
///   `gather`'s test; pixels alone carry the reference's own noise, ~4% at 512 spp);
/// - the image mean per channel within 3%;
/// - SSIM of luminance (7×7 windows, all pixels) ≥ 0.95: the kernel blurs contact shadows
///   and the reference is noisy, so the images are not identical at pixel scale;
///   0.95 still fails for visible blotches or a misplaced splat.
///
/// On failure the images and their difference are written to target/test-output.
#[test]
fn cornell_matches_path_tracer() {
    let scene = load("cornell");
    let size = 48;
    let ispm = run(
        &scene,
        &ispm_settings(size).with("photons", 400_000).with("spp", 4),
    );
    let path = run(
        &scene,
        &ispm_settings(size)
            .with_method(gi_core::Method::Path)
            .with("spp", 512),
    );
    let (a, b) = (mean(&ispm.radiance), mean(&path.radiance));
    let rel = (a / b - DVec3::ONE).abs();
    let (ba, bb) = (
        block_means(&ispm.radiance, 8),
        block_means(&path.radiance, 8),
    );
    let block_err = ba
        .iter()
        .zip(&bb)
        .map(|(x, y)| (*x - *y).abs() / y.max(DVec3::splat(1e-3)))
        .sum::<DVec3>()
        / ba.len() as f64;
    let all = vec![true; (size * size) as usize];
    let ssim = common::ssim(&ispm.radiance, &path.radiance, &all);
    eprintln!(
        "cornell ispm {a:?} path {b:?} rel {rel:?}; mean relative 8x8-block error {block_err:?}; \
         SSIM {ssim:.4}; {:?}",
        ispm.stats
    );
    let ok = rel.max_element() < 0.03 && block_err.max_element() < 0.03 && ssim >= 0.95;
    if !ok {
        let dir = common::output_dir();
        let mut diff = ispm.radiance.clone();
        for (d, p) in diff.pixels.iter_mut().zip(&path.radiance.pixels) {
            *d = (*d - *p).abs();
        }
        for (name, img) in [
            ("ispm-cornell.pfm", &ispm.radiance),
            ("ispm-cornell-path.pfm", &path.radiance),
            ("ispm-cornell-diff.pfm", &diff),
        ] {
            let _ = common::write_pfm(&dir.join(name), img);
        }
        eprintln!("images written to {}", dir.display());
    }
    assert!(rel.max_element() < 0.03, "image mean {a:?} vs {b:?}");
    assert!(block_err.max_element() < 0.03, "block error {block_err:?}");
    assert!(ssim >= 0.95, "SSIM {ssim}");

    // Subsampled splatting (k = 2) with joint bilateral upsampling: same criteria for the
    // image mean, and the mean absolute difference to k = 1 is under 10% of the mean (measured
    // 6%: both images carry their own kernel noise at 48×48).
    let sub = run(
        &scene,
        &ispm_settings(size)
            .with("subsample", 2)
            .with("photons", 400_000),
    );
    let c = mean(&sub.radiance);
    let rel2 = (c / b - DVec3::ONE).abs();
    let diff: f64 = sub
        .radiance
        .pixels
        .iter()
        .zip(&ispm.radiance.pixels)
        .map(|(p, q)| (*p - *q).abs().element_sum() as f64)
        .sum::<f64>()
        / ispm
            .radiance
            .pixels
            .iter()
            .map(|p| p.element_sum() as f64)
            .sum::<f64>();
    eprintln!("cornell subsample 2: {c:?} rel {rel2:?}, mean |k2 − k1| / mean {diff:.4}");
    assert!(sub.stats.stages.iter().any(|(n, _)| n == "upsample"));
    assert!(rel2.max_element() < 0.03, "{c:?} vs {b:?}");
    assert!(diff < 0.10, "{diff}");
}

/// The renders a caustic test compares: ISPM with `s`, the same frame's direct light, the
/// reference path tracer at `path_spp`, and an independent reference (another seed) that
/// picks the region. Selecting the brightest pixels of the very image we compare against
/// would pick its upward noise (measured +18% on `path` at 32 spp) and bias the comparison.
struct CausticRenders {
    ispm: RenderOutput,
    direct: RenderOutput,
    path: RenderOutput,
    select: RenderOutput,
}

fn caustic_renders(scene: &Scene, s: &gi_core::RenderOptions, path_spp: u32) -> CausticRenders {
    let with = |method, seed| {
        s.clone()
            .with_method(method)
            .with("spp", path_spp)
            .with("seed", seed)
    };
    CausticRenders {
        ispm: run(scene, s),
        direct: run(scene, &s.clone().with_method(gi_core::Method::Direct)),
        path: run(scene, &with(Method::Path, s.common.seed)),
        select: run(scene, &with(Method::Path, 1234)),
    }
}

/// The pixels of `region` whose light-traced caustic radiance in `select` is at or above the
/// `percentile` of the region's.
fn brightest_caustic(select: &RenderOutput, region: &[bool], percentile: usize) -> Vec<bool> {
    let mut c: Vec<f32> = select
        .caustics
        .pixels
        .iter()
        .zip(region)
        .filter(|(_, f)| **f)
        .map(|(p, _)| p.x)
        .collect();
    c.sort_by(f32::total_cmp);
    let threshold = c[c.len() * percentile / 100];
    select
        .caustics
        .pixels
        .iter()
        .zip(region)
        .map(|(p, f)| *f && p.x >= threshold && p.x > 0.0)
        .collect()
}

/// Caustic ring: the mirror focuses light into a cardioid on the floor. In the ISPM
/// indirect image (ispm − direct) the caustic (the brightest 3% of a reference's
/// light-traced caustic image on the floor inside the ring) is more than 3× brighter than
/// the rest of that floor, and its total radiance matches the path tracer's there within 10%.
#[test]
fn caustic_ring_is_brighter_than_surroundings() {
    let scene = load("caustic-ring");
    let size = 96;
    let s = ispm_settings(size).with("photons", 400_000);
    let CausticRenders {
        ispm,
        direct,
        path,
        select,
    } = caustic_renders(&scene, &s, 32);
    let floor: Vec<bool> = path
        .position
        .pixels
        .iter()
        .map(|p| p.y.abs() < 1e-3 && (p.x * p.x + p.z * p.z).sqrt() < 0.95)
        .collect();
    let ring = brightest_caustic(&select, &floor, 97);
    let rest: Vec<bool> = floor.iter().zip(&ring).map(|(f, r)| *f && !r).collect();
    let indirect = |img: &gi_core::image::Image, keep: &[bool]| {
        region_mean(img, keep) - region_mean(&direct.radiance, keep)
    };
    let (ci, ri) = (
        indirect(&ispm.radiance, &ring),
        indirect(&ispm.radiance, &rest),
    );
    let (ti, tp) = (
        region_mean(&ispm.radiance, &ring),
        region_mean(&path.radiance, &ring),
    );
    eprintln!(
        "caustic: ispm indirect {ci:?} vs rest {ri:?}; total ispm {ti:?} path {tp:?}; {:?}",
        ispm.stats
    );
    assert!(ci.x > 3.0 * ri.x, "{ci:?} vs {ri:?}");
    assert!((ti.x / tp.x - 1.0).abs() < 0.10, "{ti:?} vs {tp:?}");
}

#[test]
fn ispm_settings_are_validated() {
    assert_eq!("ispm".parse::<Method>().ok(), Some(Method::Ispm));
    let defaults = IspmOptions::default();
    let ok = RenderOptions::of(MethodOptions::Ispm(defaults.clone()));
    assert_eq!((defaults.kernel_scale, defaults.subsample), (1.0, 2));
    assert!(ok.validate().is_ok());
    let with = |change: fn(&mut IspmOptions)| {
        let mut o = defaults.clone();
        change(&mut o);
        RenderOptions::of(MethodOptions::Ispm(o))
    };
    for bad in [
        with(|o| o.subsample = 0),
        with(|o| o.subsample = 9),
        with(|o| o.kernel_scale = 0.0),
        with(|o| o.kernel_scale = f32::NAN),
    ] {
        assert!(matches!(
            bad.validate(),
            Err(gi_core::Error::Setting { .. })
        ));
    }
}

/// A photon budget whose bounce maps would not fit is a setting error, not a crash.
#[test]
fn huge_photon_budget_is_a_setting_error() {
    let s = ispm_settings(8).with("photons", 900_000_000);
    let e = render(&load("cornell"), &s, &Silent).err();
    assert!(matches!(e, Some(gi_core::Error::Setting { .. })), "{e:?}");
}

/// Photon volumes sized by photon-differential footprints (the `gather` method's photons)
/// instead of the path-density heuristic: the furnace's indirect light stays right.
/// Bounce-map photons start their differentials at the bounce (zero footprint), so their
/// volumes are small and noisy; measured +2.8% at 100k photons, bound 5%.
#[test]
fn footprint_sized_volumes_match_furnace() {
    let scene = gi_core::scene::builtin::load("furnace").unwrap();
    let base = gi_core::options!(Path, spp: 1, width: 32, height: 32, photons: 100_000);
    let direct = gi_core::render(
        &scene,
        &base.clone().with_method(gi_core::Method::Direct),
        &Silent,
    )
    .unwrap();
    let ispm = base
        .with_method(gi_core::Method::Ispm)
        .with("footprint_volumes", true);
    let out = gi_core::render(&scene, &ispm, &Silent).unwrap();
    let indirect = (out.radiance.mean() - direct.radiance.mean()).x;
    let expected = 0.5 / std::f32::consts::PI;
    assert!(
        (indirect / expected - 1.0).abs() < 0.05,
        "{indirect} vs {expected}"
    );
}

/// `cornell-glass`: the glass sphere focuses a caustic on the floor and both spheres are
/// seen directly. Caustic region: the brightest 5% of a reference's light-traced caustic
/// image on the floor (about 90 pixels at 128²; the focused spot is a few pixels wide, and
/// ISPM shades pixel centres while the reference box-filters pixels, which over the
/// brightest 1–2% alone reads 5–10% high: measured at 64² and 128²). Criteria: ISPM's
/// indirect light there is more than 3× that of the rest of the floor; its total radiance
/// there matches the path tracer's within 10%; and the pixels that see the mirror or the
/// glass sphere (traced backwards on the CPU, otherwise black in a rasterizer) match the
/// path tracer's mean within 10% per channel. Measured values are printed.
#[test]
fn cornell_glass_caustic_and_specular_surfaces() {
    let scene = load("cornell-glass");
    let size = 128;
    let s = ispm_settings(size).with("photons", 400_000);
    let CausticRenders {
        ispm,
        direct,
        path,
        select,
    } = caustic_renders(&scene, &s, 64);
    let spheres = [
        (glam::Vec3::new(0.4, 0.4, 0.25), 0.4f32),
        (glam::Vec3::new(-0.45, 0.4, -0.4), 0.4),
    ];
    let on_sphere: Vec<bool> = path
        .position
        .pixels
        .iter()
        .zip(&path.depth)
        .map(|(p, d)| *d > 0.0 && spheres.iter().any(|(c, r)| (*p - *c).length() < r + 1e-3))
        .collect();
    let floor: Vec<bool> = path
        .position
        .pixels
        .iter()
        .zip(&on_sphere)
        .map(|(p, s)| !s && p.y.abs() < 1e-3)
        .collect();
    let caustic = brightest_caustic(&select, &floor, 95);
    let rest: Vec<bool> = floor.iter().zip(&caustic).map(|(f, c)| *f && !c).collect();
    let indirect =
        |keep: &[bool]| region_mean(&ispm.radiance, keep) - region_mean(&direct.radiance, keep);
    let (ci, ri) = (indirect(&caustic), indirect(&rest));
    let (ti, tp) = (
        region_mean(&ispm.radiance, &caustic),
        region_mean(&path.radiance, &caustic),
    );
    let (si, sp) = (
        region_mean(&ispm.radiance, &on_sphere),
        region_mean(&path.radiance, &on_sphere),
    );
    eprintln!(
        "cornell-glass caustic ({} px): ispm indirect {ci:?} vs rest {ri:?}; total ispm {ti:?} \
         path {tp:?}; spheres ({} px) ispm {si:?} path {sp:?}; {:?}",
        caustic.iter().filter(|c| **c).count(),
        on_sphere.iter().filter(|c| **c).count(),
        ispm.stats
    );
    assert!(
        ci.min_element() > 3.0 * ri.max_element(),
        "{ci:?} vs {ri:?}"
    );
    let rel = (ti / tp - DVec3::ONE).abs();
    assert!(rel.max_element() < 0.10, "caustic {ti:?} vs {tp:?}");
    let rel = (si / sp - DVec3::ONE).abs();
    assert!(rel.max_element() < 0.10, "spheres {si:?} vs {sp:?}");
}

/// The indirect AOV of `s` with volume shape `shape`, and (stored photons, volumes drawn as
/// quads).
fn indirect_with(
    scene: &Scene,
    s: &gi_core::RenderOptions,
    shape: VolumeShape,
) -> (gi_core::Image, (u64, u64)) {
    let out = run(
        scene,
        &s.clone()
            .with("volume_shape", shape)
            .with("estimator", gi_core::estimate::Estimator::Volumes),
    );
    let counts = (out.stats.photons_stored, out.stats.volume_quads);
    let img = out
        .aovs
        .into_iter()
        .find(|(n, _)| n == "indirect")
        .map(|(_, img)| img)
        .expect("indirect AOV");
    (img, counts)
}

/// Photon volumes drawn as screen-aligned quads, as icosahedra, and per photon by size
/// (`auto`) give the same indirect image: every shape feeds the same exact ellipsoid test,
/// so a pixel that differs means a bound that is not conservative (a quad too small, a wrong
/// near-plane fallback). Quad and icosahedron draw the photons in the same order, so equal
/// coverage blends the same terms in the same order; `auto` reorders the photons (small ones
/// first), which changes only the float summation order: tolerance 1e-4 of the image's
/// largest pixel (an f32 sum of a few hundred terms is off by ~1e-5 relative).
/// Cases: the Cornell box at subsample 1 and 2 (the half-pixel shift of the volume view);
/// the furnace, whose camera sits inside the sphere among the photons, so that volumes
/// reach behind the eye plane (the quad's full-screen fallback) or lie wholly behind it; and
/// the Cornell box with 3× larger volumes at 128², where `auto` draws both shapes and the
/// back-wall icosahedra reach past the far plane (before their depth was clamped they lost
/// up to 2% of a pixel there, which this test found).
/// Besides equal lit-pixel counts, the tolerance is checked to be tight: volumes 3% smaller
/// (kernel_scale 0.97) differ from it by more than 100× the tolerance.
#[test]
fn volume_shapes_give_the_same_image() {
    let cases = [
        ("cornell", 64, 1, 1.0),
        ("cornell", 64, 2, 1.0),
        ("furnace", 32, 1, 4.0),
        ("cornell", 128, 1, 3.0),
    ];
    for (name, size, subsample, kernel_scale) in cases {
        let scene = load(name);
        let s = ispm_settings(size)
            .with("photons", 50_000)
            .with("subsample", subsample)
            .with("kernel_scale", kernel_scale);
        let (ico, _) = indirect_with(&scene, &s, VolumeShape::Icosahedron);
        let (quad, _) = indirect_with(&scene, &s, VolumeShape::Quad);
        let (auto, quads) = indirect_with(&scene, &s, VolumeShape::Auto);
        let scale = ico
            .pixels
            .iter()
            .map(|p| p.max_element())
            .fold(0.0, f32::max);
        let (dq, da) = (
            max_difference(&quad, &ico, scale),
            max_difference(&auto, &ico, scale),
        );
        let lit = lit_pixels(&ico);
        eprintln!(
            "{name} {size}² k={subsample}: max pixel {scale:.4}, lit {lit}/{}, \
             |quad − ico| {dq:.2e}, |auto − ico| {da:.2e} (of the max pixel); \
             auto drew {} of {} volumes as quads",
            size * size,
            quads.1,
            quads.0
        );
        assert!(scale > 0.0, "no indirect light");
        assert!(lit > size as usize * size as usize / 2, "{lit} lit pixels");
        assert_eq!(lit_pixels(&quad), lit, "quad covers other pixels");
        assert_eq!(lit_pixels(&auto), lit, "auto covers other pixels");
        assert!(dq < 1e-4, "quad differs from icosahedron by {dq}");
        assert!(da < 1e-4, "auto differs from icosahedron by {da}");
        if kernel_scale == 3.0 {
            assert!(0 < quads.1 && quads.1 < quads.0, "auto drew one shape only");
        }
        if name == "cornell" && size == 64 && subsample == 1 {
            let (smaller, _) = indirect_with(
                &scene,
                &s.clone().with("kernel_scale", 0.97),
                VolumeShape::Quad,
            );
            let d = max_difference(&smaller, &ico, scale);
            eprintln!("cornell with 3% smaller volumes: {d:.2e}");
            assert!(d > 1e-2, "{d}");
        }
    }
}

#[test]
fn volume_shape_setting_parses() {
    assert_eq!(
        gi_core::frame::options::IspmOptions::default().volume_shape,
        VolumeShape::Auto
    );
    assert_eq!("quad".parse::<VolumeShape>().ok(), Some(VolumeShape::Quad));
    let e = "cube".parse::<VolumeShape>().err();
    assert!(
        matches!(e, Some(gi_core::Error::Setting { name, .. }) if name == "volume_shape"),
        "{e:?}"
    );
}

/// The joint bilateral upsampling (subsample 2) gives no indirect light to pixels whose
/// surface has no non-delta lobe: `caustic-ring`'s mirror ring, next to the bright caustic
/// on the floor, has indirect 0 at every pixel whose centre sees the ring (its photon
/// estimate term is 0 there: f = 0). Before, the normalised bilateral weights handed it
/// the floor's light (0.66 at a rim pixel of 48x48, measured against `path`'s 0). The rest
/// of the image keeps its indirect light.
#[test]
fn upsampling_gives_mirrors_no_indirect_light() {
    use gi_core::trace::SceneBvh;
    let scene = load("caustic-ring");
    let s = ispm_settings(48)
        .with("subsample", 2)
        .with("photons", 50_000);
    let out = run(&scene, &s);
    let indirect = &out
        .aovs
        .iter()
        .find(|(n, _)| n == "indirect")
        .expect("indirect AOV")
        .1;
    let mut posed = scene.clone();
    posed.camera = posed.camera.with_size(48, 48);
    let bvh = SceneBvh::build(&posed);
    let cam = &posed.camera;
    // Whether the ray through (x, y) (pixel units) meets a mirror first.
    let on_mirror = |x: f32, y: f32| {
        bvh.intersect(cam.position, cam.direction(x, y), f32::INFINITY)
            .is_some_and(|h| posed.material_of(h.triangle as usize).is_purely_specular())
    };
    let (mut mirror, mut lit) = (0, 0);
    for y in 0..48u32 {
        for x in 0..48u32 {
            let v = indirect.pixels[(y * 48 + x) as usize];
            let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
            // Pixels whose centre and whole footprint see the ring (the G-buffer sample is
            // the rasterizer's, which may differ from a ray at a silhouette).
            let inside = [
                (0.0, 0.0),
                (-0.5, -0.5),
                (0.5, -0.5),
                (-0.5, 0.5),
                (0.5, 0.5),
            ]
            .iter()
            .all(|(dx, dy)| on_mirror(fx + dx, fy + dy));
            if inside {
                mirror += 1;
                assert_eq!(
                    v,
                    glam::Vec3::ZERO,
                    "mirror pixel ({x}, {y}) has indirect {v}"
                );
            } else if v.max_element() > 0.0 {
                lit += 1;
            }
        }
    }
    assert!(mirror > 50, "{mirror} mirror pixels");
    assert!(lit > 500, "{lit} pixels with indirect light");
}

/// The joint bilateral upsampling keeps a texture's detail in the indirect light: on
/// `cornell` with a checkered floor (4×4-texel squares of albedo 0.1 and 0.8), the
/// subsample-2 indirect image's floor pixels are compared with the subsample-1 image of the
/// same photons. Each Lambertian pixel rescales its low-resolution samples' light by the
/// ratio of its albedo to theirs, so the checker's squares come out at their own albedo
/// instead of their neighbours' (bound and measurements below).
#[test]
fn upsampling_keeps_texture_detail_in_indirect_light() {
    use std::collections::HashMap;
    let mut json: serde_json::Value =
        serde_json::from_str(builtin::json("cornell").expect("cornell")).expect("json");
    json["materials"]["checker"] =
        serde_json::json!({"diffuse": [1, 1, 1], "diffuse_texture": "checker"});
    json["objects"][0]["material"] = serde_json::json!("checker");
    let textures = common::checker_textures();
    let scene = Scene::from_json_textured(
        &json.to_string(),
        "checker-cornell",
        &HashMap::new(),
        &textures,
    )
    .expect("scene");
    let indirect = |subsample: u32| {
        let s = ispm_settings(96)
            .with("subsample", subsample)
            .with("photons", 100_000);
        let out = run(&scene, &s);
        out.aovs
            .into_iter()
            .find(|(n, _)| n == "indirect")
            .expect("indirect AOV")
            .1
    };
    let (full, up) = (indirect(1), indirect(2));
    // The floor: the bottom fifth of the image, between the walls.
    let (mut se, mut sr) = (0.0f64, 0.0f64);
    for y in 80..96usize {
        for x in 24..72usize {
            let (a, b) = (full.pixels[y * 96 + x], up.pixels[y * 96 + x]);
            se += (a - b).length_squared() as f64;
            sr += a.length_squared() as f64;
        }
    }
    let rel = (se / sr).sqrt();
    eprintln!("checkered floor: relative RMS difference of subsample 2 from 1: {rel:.4}");
    // Measured 0.058 (the two splat resolutions' noise and the upsampling's blur), and 0.31
    // without the albedo ratio (the squares took their neighbours' albedo): the bound sits
    // between them, 2.5x above the one and half the other.
    assert!(rel < 0.15, "{rel}");
}

/// The Cornell box lit by a 0.5 m emitting square in its ceiling instead of its point light
/// (no point or spot light: the bounce maps are empty and every photon is emitted on the
/// CPU), with `extra` lights.
fn area_lit_cornell(size: u32, extra: &str) -> Scene {
    let boxes = r#"
        {"shape": {"type": "box", "size": [0.6, 1.2, 0.6]}, "material": "white",
         "transform": {"rotate": [0, 20, 0], "translate": [-0.35, 0.6, -0.3]}},
        {"shape": {"type": "box", "size": [0.6, 0.6, 0.6]}, "material": "white",
         "transform": {"rotate": [0, -20, 0], "translate": [0.35, 0.3, 0.3]}}"#;
    let json = common::area_lit_box(size, extra, "", boxes);
    Scene::from_json(&json, "area-cornell", &std::collections::HashMap::new()).unwrap()
}

/// `ispm` on the 32² `scene` (400k photons, 4 spp), its indirect AOV's mean, and the path
/// tracer's indirect light (256 spp: all bounces, the default depth 64, minus max_depth 1:
/// direct light and the lamp seen).
fn indirect_and_reference(scene: &Scene) -> (RenderOutput, DVec3, DVec3) {
    let out = run(
        scene,
        &ispm_settings(32).with("photons", 400_000).with("spp", 4),
    );
    let indirect = out
        .aovs
        .iter()
        .find(|(n, _)| n == "indirect")
        .map(|(_, img)| mean(img))
        .expect("indirect AOV");
    let path = |depth: u32| {
        let s = ispm_settings(32)
            .with_method(gi_core::Method::Path)
            .with("spp", 256)
            .with("max_depth", depth);
        mean(&run(scene, &s).radiance)
    };
    let reference = path(64) - path(1);
    (out, indirect, reference)
}

/// `ispm`'s photons leave emitting surfaces too (their first hits traced on the CPU, the
/// bounce maps see point and spot lights only): in the area-lit Cornell box, the indirect
/// AOV's mean is the path tracer's indirect light (all bounces, the default depth 64, minus
/// max_depth 1: direct light and the lamp seen) within 4%, with the area light alone and with a point light
/// taking part of the photon budget. The bound: 3% for the kernel estimate as in the
/// furnace, plus the reference's noise in a difference of two means (about 1%); measured
/// under 1%.
#[test]
fn area_light_photons_give_ispm_indirect_light() {
    for extra in [
        "",
        r#"{"type": "point", "position": [0.5, 1.5, 0.5], "intensity": [1, 1, 1]}"#,
    ] {
        let scene = area_lit_cornell(32, extra);
        let (out, indirect, reference) = indirect_and_reference(&scene);
        let rel = (indirect / reference - DVec3::ONE).abs();
        eprintln!(
            "area-lit cornell (extra: {extra:?}): ispm indirect {indirect:?} vs path {reference:?}: \
             {rel:?}; {:?}",
            out.stats
        );
        assert!(out.stats.photons_emitted > 0);
        assert!(rel.max_element() < 0.04, "{indirect:?} vs {reference:?}");
    }
}

/// `ispm`'s photons leave a sun (a parallel beam over the scene's bounding disc) and a sky
/// (directions drawn by radiance over the disc) too, traced on the CPU: in an open scene
/// (a floor, a back wall and two boxes under both), the indirect AOV's mean is the path
/// tracer's indirect light within 4%, the bound of the area-lit case above (the kernel
/// estimate's 3% and the reference's noise).
#[test]
fn sun_and_sky_photons_give_ispm_indirect_light() {
    let json = r#"{
        "camera": {"position": [0, 1.5, 3.5], "look_at": [0, 0.4, 0], "fov": 45,
                   "width": 32, "height": 32},
        "lights": [{"type": "directional", "direction": [0.4, -1, -0.3],
                    "irradiance": [3, 2.8, 2.5], "angular_diameter": 2}],
        "environment": {"radiance": [0.2, 0.3, 0.5]},
        "materials": {"white": {"diffuse": [0.73, 0.73, 0.73]},
                      "red": {"diffuse": [0.63, 0.065, 0.05]}},
        "objects": [
            {"shape": {"type": "quad", "size": [4, 4]}, "material": "white"},
            {"shape": {"type": "quad", "size": [4, 2]}, "material": "red",
             "transform": {"rotate": [90, 0, 0], "translate": [0, 1, -1]}},
            {"shape": {"type": "box", "size": [0.6, 1.2, 0.6]}, "material": "white",
             "transform": {"rotate": [0, 20, 0], "translate": [-0.5, 0.6, -0.3]}},
            {"shape": {"type": "box", "size": [0.6, 0.6, 0.6]}, "material": "red",
             "transform": {"rotate": [0, -20, 0], "translate": [0.5, 0.3, 0.3]}}
        ]
    }"#;
    let scene = Scene::from_json(json, "sun-sky", &std::collections::HashMap::new()).unwrap();
    let (out, indirect, reference) = indirect_and_reference(&scene);
    let rel = (indirect / reference - DVec3::ONE).abs();
    eprintln!("sun and sky: ispm indirect {indirect:?} vs path {reference:?}: {rel:?}");
    assert!(out.stats.photons_emitted > 0);
    assert!(rel.max_element() < 0.04, "{indirect:?} vs {reference:?}");
}
