//! ISPM's first bounce traced in the CPU BVH (`FirstBounce::Traced`, the default on CPU
//! devices) against the rasterized bounce maps (section 4.2): the same photons in
//! distribution, so the same image in expectation.

use gi_core::photon::bounce::BounceMap;
use gi_core::photon::bounce::{trace_bounce_maps, FirstBounce};
use gi_core::photon::trace::Checked;
use gi_core::render;
use gi_core::sampling::Rng;
use gi_core::scene::builtin;
use gi_core::scene::light_views::light_views as bounce_layers;
use gi_core::trace::{Interaction, SceneBvh};
use gi_core::Silent;

/// Σ over a map's rays of their squared power (all channels summed): a bound on the variance
/// of its scattered power, whose texels scatter independently.
fn variance_bound(m: &BounceMap) -> f64 {
    m.rays
        .iter()
        .map(|r| (r.power.iter().sum::<f32>() as f64).powi(2))
        .sum()
}

/// The covered and expected scattered power of the photons of `light` (Σ over its hits of
/// Φ and Φ·ρ) from `n` independent emissions (`Light::emit`, uniform directions), with
/// their standard errors.
fn emitted_estimate(scene: &gi_core::Scene, bvh: &SceneBvh, n: u64) -> [(f64, f64); 2] {
    let mut sums = [[0.0f64; 2]; 2];
    for i in 0..n {
        let mut rng = Rng::new(9, 1, i);
        let e = scene.lights[0].emit(&mut rng, scene.bounds());
        let Some(hit) = bvh.intersect(e.origin, e.direction, f32::INFINITY) else {
            continue;
        };
        let it = Interaction::new(scene, &hit, e.direction);
        let rho = it
            .material
            .scatter_probability(it.frame.to_local(-e.direction));
        let x = [
            e.power.element_sum() as f64,
            (e.power * rho).element_sum() as f64,
        ];
        for (s, x) in sums.iter_mut().zip(x) {
            s[0] += x;
            s[1] += x * x;
        }
    }
    sums.map(|[s, s2]| {
        let mean = s / n as f64;
        (mean, ((s2 / n as f64 - mean * mean) / n as f64).sqrt())
    })
}

#[test]
fn traced_bounce_maps_are_unbiased() {
    // cornell-glass: a point light in an open box with a mirror and a glass sphere. The
    // traced map's covered power and expected scattered power against an independent
    // estimate from uniformly emitted photons (400k: standard errors about 0.05%). The
    // traced map's own noise is far smaller (one stratified photon per texel), so the
    // bound is 4 standard errors of the estimate plus 0.1%.
    let scene = builtin::load("cornell-glass").unwrap();
    let bvh = SceneBvh::build(&scene);
    let layers = bounce_layers(&scene, 20_000);
    let control = Checked::new(&Silent, "bounce maps");
    let traced = trace_bounce_maps(&scene, &bvh, &layers, 5, &control).unwrap();
    let [(incident, incident_se), (expected, expected_se)] =
        emitted_estimate(&scene, &bvh, 400_000);
    for (what, map, (mean, se)) in [
        (
            "incident",
            traced.incident_power.element_sum(),
            (incident, incident_se),
        ),
        (
            "expected",
            traced.expected_scattered_power.element_sum(),
            (expected, expected_se),
        ),
    ] {
        assert!(
            (map - mean).abs() < 4.0 * se + 1e-3 * mean,
            "{what}: traced {map} vs emitted {mean} ± {se}"
        );
    }
    // Not a closed room: a seventh of the light leaves through the open front.
    let total = scene.lights[0].power(scene.bounds()).element_sum() as f64;
    assert!(
        incident < 0.9 * total && incident > 0.7 * total,
        "{incident} of {total}"
    );
}

#[test]
fn traced_bounce_maps_match_the_rasterized_ones() {
    for name in ["cornell", "cornell-glass"] {
        let scene = builtin::load(name).unwrap();
        let photons = 20_000u64;
        let settings = gi_core::options!(Ispm, photons: photons, seed: 3);
        let raster = gi_core::frame::bounce_map(&scene, &settings).unwrap();
        let layers = bounce_layers(&scene, photons);
        let control = Checked::new(&Silent, "bounce maps");
        let traced =
            trace_bounce_maps(&scene, &SceneBvh::build(&scene), &layers, 3, &control).unwrap();
        assert_eq!(traced.texels, raster.texels, "{name}");
        // Coverage and the power before the scatter depend on the texels' points only: the
        // maps differ at texels on outlines and material boundaries. The rasterized maps
        // cover 0.2% less power than the traced ones and expect 0.5% less scattered power
        // (8 seeds; the traced maps agree with `traced_bounce_maps_are_unbiased`'s
        // independent estimate to 0.03%, so the loss is the raster's: the coverage is
        // decided at texel centres and the jittered point is moved on the centre's
        // triangle's plane, off it near edges).
        let texels = raster.texels as f64;
        let covered = (traced.covered as f64 - raster.covered as f64).abs();
        assert!(
            covered < 0.01 * texels,
            "{name}: {} vs {}",
            traced.covered,
            raster.covered
        );
        let rel = |a: glam::DVec3, b: glam::DVec3| (a - b).length() / b.length();
        let incident = rel(traced.incident_power, raster.incident_power);
        assert!(incident < 0.005, "{name}: incident power {incident}");
        let expected = rel(
            traced.expected_scattered_power,
            raster.expected_scattered_power,
        );
        assert!(
            expected < 0.01,
            "{name}: expected scattered power {expected}"
        );
        // The survivors are random (BSDF sampling, roulette): their power agrees within 4
        // standard deviations, and so do their numbers and the mirror and glass first hits.
        let (ts, rs) = (
            traced.scattered_power.element_sum(),
            raster.scattered_power.element_sum(),
        );
        let sd = (variance_bound(&traced) + variance_bound(&raster)).sqrt();
        assert!((ts - rs).abs() < 4.0 * sd, "{name}: {ts} vs {rs} ± {sd}");
        let (tn, rn) = (traced.rays.len() as f64, raster.rays.len() as f64);
        assert!(
            (tn - rn).abs() < 4.0 * (tn + rn).sqrt(),
            "{name}: {tn} vs {rn} rays"
        );
        let delta = |m: &BounceMap| m.first_delta.iter().filter(|&&d| d).count() as f64;
        let (td, rd) = (delta(&traced), delta(&raster));
        assert!(
            (td - rd).abs() < 4.0 * (td + rd).sqrt().max(1.0),
            "{name}: {td} vs {rd} delta first hits"
        );
        if name == "cornell-glass" {
            assert!(td > 100.0, "{td} delta first hits");
        }
        let lights = |m: &BounceMap| m.ray_lights.windows(2).all(|w| w[0] <= w[1]);
        assert!(lights(&traced), "{name}: rays grouped by light");
    }
}

/// The Cornell box with its walls made Mitsuba's models the uber BSDF does not render
/// (a nonlinear rough plastic and a rough conductor, Beckmann; a smooth plastic), which
/// the bounce maps sample through the G-buffer's exact records (`raster::exact_models`).
fn cornell_with_mitsuba_models() -> gi_core::Scene {
    use gi_core::bsdf::{Coating, Conductor, Distribution};
    use glam::Vec3;
    let mut scene = builtin::load("cornell").unwrap();
    let mut k = 0;
    for m in scene.materials.iter_mut() {
        if m.emission != Vec3::ZERO || m.diffuse == Vec3::ZERO {
            continue;
        }
        let beckmann = Distribution::Beckmann;
        match k % 3 {
            0 => {
                m.specular = Vec3::ONE;
                m.roughness = 0.5;
                m.distribution = beckmann;
                m.coating = Some(Coating::new(1.5, true, 0.25, beckmann));
            }
            1 => {
                m.diffuse = Vec3::ZERO;
                m.specular = Vec3::ONE;
                m.roughness = 0.45;
                m.distribution = beckmann;
                m.conductor = Some(Conductor::new(
                    Vec3::new(0.2, 0.92, 1.1),
                    Vec3::new(3.9, 2.45, 2.14),
                ));
            }
            _ => {
                m.specular = Vec3::ONE;
                m.roughness = 0.0;
                m.coating = Some(Coating::new(1.5, false, 0.0, Distribution::Ggx));
            }
        }
        k += 1;
    }
    assert!(k >= 3);
    scene
}

#[test]
fn bounce_maps_sample_the_exact_models() {
    // The rasterized first bounce of Mitsuba's models (exact records, `bounce.wgsl`'s
    // `exact_*`) against the traced one (the CPU's `Material`, matched to Mitsuba): the
    // expected scattered power (Σ Φ·scatter probability) within 1% and the scattered power
    // within 4 standard deviations, as `traced_bounce_maps_match_the_rasterized_ones`
    // holds the uber materials. Measured: 0.41% and 0.7 sd. Not a discriminating test of
    // the models: the uber stand-ins keep each model's mean albedo, and their traced maps
    // differ from the exact ones by 0.25% (expected) and 1 sd (scattered) in these totals;
    // their lobes' shapes, which the totals do not see, are what differ.
    let scene = cornell_with_mitsuba_models();
    let photons = 40_000u64;
    let settings = gi_core::options!(Ispm, photons: photons, seed: 3);
    let raster = gi_core::frame::bounce_map(&scene, &settings).unwrap();
    let layers = bounce_layers(&scene, photons);
    let control = Checked::new(&Silent, "bounce maps");
    let traced = trace_bounce_maps(&scene, &SceneBvh::build(&scene), &layers, 3, &control).unwrap();
    let rel = |a: glam::DVec3, b: glam::DVec3| (a - b).length() / b.length();
    let expected = rel(
        traced.expected_scattered_power,
        raster.expected_scattered_power,
    );
    assert!(expected < 0.01, "expected scattered power {expected}");
    let (ts, rs) = (
        traced.scattered_power.element_sum(),
        raster.scattered_power.element_sum(),
    );
    let sd = (variance_bound(&traced) + variance_bound(&raster)).sqrt();
    assert!((ts - rs).abs() < 4.0 * sd, "{ts} vs {rs} ± {sd}");
}

#[test]
fn first_bounce_choice_keeps_the_image() {
    let mut scene = builtin::load("cornell-glass").unwrap();
    scene.camera = scene.camera.with_size(64, 48);
    let image = |first_bounce: FirstBounce, seed: u64| {
        let settings = gi_core::options!(Ispm, photons: 20_000, spp: 1, seed: seed, first_bounce: first_bounce);
        let out = render(&scene, &settings, &Silent).unwrap();
        assert_eq!(out.stats.first_bounce, first_bounce.name());
        out.radiance.mean().element_sum() as f64
    };
    let shifts: Vec<f64> = (1..=6)
        .map(|seed| image(FirstBounce::Traced, seed) / image(FirstBounce::Raster, seed) - 1.0)
        .collect();
    // The same image up to the rasterized maps' loss of first-scatter power (measured with
    // `traced_bounce_maps_are_unbiased`'s estimate: -0.5% of the expected scattered power
    // on this scene, -0.2% of the coverage), which reaches the indirect light: the traced
    // image was +0.68% ± 0.20% brighter over these seeds. Bound: the mean shift under 1.5%
    // and each under 2.5% (a lost or doubled light, a wrong texel power, would be tens of
    // percent).
    let mean = shifts.iter().sum::<f64>() / shifts.len() as f64;
    assert!(mean.abs() < 0.015, "mean shift {mean}: {shifts:?}");
    assert!(shifts.iter().all(|s| s.abs() < 0.025), "shifts {shifts:?}");
}

#[test]
fn first_bounce_names_parse() {
    for f in FirstBounce::ALL {
        assert_eq!(f.name().parse::<FirstBounce>().unwrap(), *f);
    }
    let e = "rays".parse::<FirstBounce>().unwrap_err().to_string();
    assert!(e.contains("first_bounce"), "{e}");
}
