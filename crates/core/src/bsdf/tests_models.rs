//! Mitsuba's models beside the uber BSDF (coated plastics, conductors, Beckmann): energy,
//! reciprocity, sampling against the pdf, and the closed forms they must reproduce.

use super::tests::{albedo_by_sampling, assert_reciprocal, chi_square, dir};
use super::*;
use crate::sampling::Rng;
use std::f32::consts::PI;

/// Gold's RGB complex index in Mitsuba 3.9.1's RGB variants (python/gi/mitsuba/metals.py).
const AU_ETA: Vec3 = Vec3::new(0.143036, 0.375307, 1.44205);
const AU_K: Vec3 = Vec3::new(3.983, 2.38556, 1.60336);

fn plastic(rho: Vec3, roughness: f32, dist: Distribution, nonlinear: bool) -> Material {
    Material {
        diffuse: rho,
        specular: Vec3::ONE,
        roughness,
        distribution: dist,
        coating: Some(Coating::new(
            1.49 / 1.000277,
            nonlinear,
            roughness * roughness,
            dist,
        )),
        ..Default::default()
    }
}

fn conductor(roughness: f32, dist: Distribution, eta: Vec3, k: Vec3) -> Material {
    Material {
        diffuse: Vec3::ZERO,
        specular: Vec3::ONE,
        roughness,
        distribution: dist,
        conductor: Some(Conductor::new(eta, k)),
        ..Default::default()
    }
}

fn models() -> Vec<Material> {
    let mut out = Vec::new();
    for dist in [Distribution::Ggx, Distribution::Beckmann] {
        for r in [0.0f32, 0.1, 0.3162, 0.7] {
            for rho in [Vec3::ONE, Vec3::new(0.8, 0.3, 0.05)] {
                for nonlinear in [false, true] {
                    out.push(plastic(rho, r, dist, nonlinear));
                }
            }
            out.push(conductor(r, dist, AU_ETA, AU_K));
            out.push(conductor(r, dist, Vec3::ZERO, Vec3::ONE));
            if r > 0.0 {
                // The uber BSDF with Beckmann's distribution.
                out.push(Material {
                    diffuse: Vec3::splat(0.5),
                    specular: Vec3::splat(0.04),
                    fresnel: true,
                    roughness: r,
                    distribution: dist,
                    ..Default::default()
                });
            }
        }
    }
    out
}

/// White furnace: no direction reflects more than it receives. The models are
/// single-scattering (the perfect conductor "none" loses the energy of masked
/// microfacets), so they may lose energy; they never gain more than 4 standard errors.
#[test]
fn models_conserve_energy() {
    for (i, m) in models().iter().enumerate() {
        for &c in &[1.0f32, 0.7, 0.3, 0.05, -0.5] {
            let (a, se) = albedo_by_sampling(m, dir(c, 0.3), 20_000, i as u64);
            let limit = Vec3::ONE + 4.0 * se + Vec3::splat(1e-4);
            assert!(
                a.cmple(limit).all(),
                "{i} {m:?} cos {c}: albedo {a} (se {se})"
            );
        }
    }
}

/// Every non-delta sample's weight is eval·|cos|/pdf, with `pdf` the density `pdf` gives;
/// the density integrates to at most 1 (the rest: delta lobes and samples below the horizon).
#[test]
fn sample_weight_is_eval_cos_over_pdf_and_pdf_integrates_to_at_most_one() {
    let mut rng = Rng::new(3, 0, 0);
    for (i, m) in models().iter().enumerate() {
        let wo = dir(0.6, 0.2);
        for _ in 0..300 {
            let Some(s) = m.sample(wo, &mut rng) else {
                continue;
            };
            if s.lobe.is_delta() {
                continue;
            }
            let pdf = m.pdf(wo, s.wi);
            assert!((pdf - s.pdf).abs() <= 1e-4 * pdf, "{i}: {pdf} vs {}", s.pdf);
            let w = m.eval(wo, s.wi) * s.wi.z.abs() / pdf;
            assert!((w - s.weight).abs().max_element() <= 1e-4 * w.max_element().max(1e-3));
        }
        // ∫ pdf over the hemisphere of wo (midpoint rule in cos θ and φ, 600²).
        let n = 600;
        let mut total = 0.0f64;
        for a in 0..n {
            for b in 0..n {
                let z = (a as f32 + 0.5) / n as f32;
                let phi = (b as f32 + 0.5) / n as f32 * std::f32::consts::TAU;
                total += m.pdf(wo, dir(z, phi)) as f64;
            }
        }
        total *= std::f64::consts::TAU / (n * n) as f64;
        assert!(total <= 1.0 + 2e-3, "{i} {m:?}: ∫pdf = {total}");
    }
}

#[test]
fn models_are_reciprocal() {
    assert_reciprocal(&models(), 100);
}

#[test]
fn models_sample_their_pdf_chi_square() {
    let cases = [
        plastic(Vec3::new(0.6, 0.3, 0.2), 0.3162, Distribution::Ggx, false),
        plastic(Vec3::new(0.6, 0.3, 0.2), 0.5, Distribution::Beckmann, true),
        plastic(Vec3::splat(0.5), 0.0, Distribution::Ggx, false),
        conductor(0.4, Distribution::Beckmann, AU_ETA, AU_K),
        conductor(0.6, Distribution::Ggx, AU_ETA, AU_K),
    ];
    let views = [dir(0.9, 0.4), dir(0.3, 2.0), dir(-0.6, 4.0)];
    let tests = (cases.len() * views.len()) as f64;
    let alpha = 1.0 - (1.0 - 0.01f64).powf(1.0 / tests);
    for (i, m) in cases.iter().enumerate() {
        for (j, wo) in views.iter().enumerate() {
            let p = chi_square(m, m, *wo, (100 + i * 10 + j) as u64);
            assert!(p > alpha, "model {i} view {j}: p = {p:e}");
        }
    }
    // And the test fails where Beckmann is sampled but GGX's pdf claimed.
    let b = conductor(0.5, Distribution::Beckmann, AU_ETA, AU_K);
    let g = conductor(0.5, Distribution::Ggx, AU_ETA, AU_K);
    assert!(chi_square(&b, &g, dir(0.7, 0.0), 5) < 1e-6);
}

/// Smooth plastic's albedo in closed form (Mitsuba's formula integrated): the specular
/// F(μ), plus ρ'·(1 − F(μ))·(2∫(1 − F)μ')/η², checked by quadrature of `eval` plus the delta
/// lobe. With ρ = 1 and the linear model it is ≈ 1 (the two fits of Mitsuba are each
/// within 0.6%): what "coating" means.
#[test]
fn smooth_plastic_albedo_matches_closed_form() {
    for nonlinear in [false, true] {
        let rho = Vec3::new(1.0, 0.5, 0.1);
        let m = plastic(rho, 0.0, Distribution::Ggx, nonlinear);
        let c = m.coating.unwrap();
        let eta = c.eta;
        for mu in [0.9f32, 0.5, 0.2] {
            let wo = dir(mu, 0.0);
            let n = 400;
            let mut sum = Vec3::ZERO;
            for a in 0..n {
                for b in 0..n {
                    let z = (a as f32 + 0.5) / n as f32;
                    let phi = (b as f32 + 0.5) / n as f32 * std::f32::consts::TAU;
                    sum += m.eval(wo, dir(z, phi)) * z;
                }
            }
            sum *= std::f32::consts::TAU / (n * n) as f32;
            let spec: Vec3 = m.delta_lobes(wo).map(|s| s.weight).sum();
            let f = fresnel::dielectric(mu, eta).0;
            let fdr_int = fresnel::diffuse_reflectance(1.0 / eta);
            let fdr_ext = fresnel::diffuse_reflectance(eta);
            let base = if nonlinear {
                rho / (Vec3::ONE - rho * fdr_int)
            } else {
                rho / (1.0 - fdr_int)
            };
            // Quadrature of 2∫(1 − F)μ dμ, not the fit, is what `eval` integrates to.
            let mut t = 0.0;
            for a in 0..20_000 {
                let z = (a as f32 + 0.5) / 20_000.0;
                t += (1.0 - fresnel::dielectric(z, eta).0) * 2.0 * z / 20_000.0;
            }
            let expected = Vec3::splat(f) + base * ((1.0 - f) * t / (eta * eta));
            let got = spec + sum;
            assert!(
                (got - expected).abs().max_element() < 2e-3,
                "{got} vs {expected}"
            );
            if !nonlinear {
                // ρ = 1 (red): the coating conserves what the base reflects.
                assert!((got.x - 1.0).abs() < 0.01, "{got}");
                assert!((1.0 - fdr_ext - (1.0 - fdr_int) * eta * eta).abs() < 0.01);
            }
        }
    }
}

/// The rough coating tends to the smooth one: at α = 1e-6 the transmittance table is
/// 1 − F(μ) and the internal reflectance the smooth one's (by Mitsuba's rule).
#[test]
fn rough_coating_tends_to_the_smooth_one() {
    for dist in [Distribution::Ggx, Distribution::Beckmann] {
        let c = Coating::new(1.49, false, 1e-6, dist);
        assert!(c.rough);
        for i in [4usize, 12, 20, 31] {
            let mu = i as f32 / (coated::TABLE - 1) as f32;
            let smooth = 1.0 - fresnel::dielectric(mu, 1.49).0;
            assert!(
                (c.transmittance[i] - smooth).abs() < 2e-3,
                "{dist:?} μ {mu}: {} vs {smooth}",
                c.transmittance[i]
            );
        }
        // Mitsuba's rule (2·mean of R(μ)μ over 64 cosines in linspace(0, 1)) with the
        // smooth internal reflectance.
        let smooth: f32 = (0..64)
            .map(|i| {
                let mu = (i as f32 / 63.0).max(1e-6);
                2.0 * fresnel::dielectric(mu, 1.0 / 1.49).0 * mu / 64.0
            })
            .sum();
        assert!(
            (c.internal - smooth).abs() < 2e-3,
            "{dist:?}: {} vs {smooth}",
            c.internal
        );
        // Rougher coatings transmit more at grazing angles and less near the normal.
        let r = Coating::new(1.49, false, 0.3, dist);
        assert!(r.t(0.05) > c.t(0.05) && r.t(1.0) < c.t(1.0) + 1e-4);
    }
}

/// A smooth conductor is a mirror reflecting the exact conductor Fresnel term.
#[test]
fn smooth_conductor_reflects_its_fresnel_term() {
    let m = conductor(0.0, Distribution::Ggx, AU_ETA, AU_K);
    for mu in [1.0f32, 0.5, 0.1] {
        let wo = dir(mu, 1.0);
        let (a, _) = albedo_by_sampling(&m, wo, 1000, 2);
        let f = fresnel::conductor(mu, AU_ETA, AU_K);
        assert!((a - f).abs().max_element() < 1e-5, "{a} vs {f}");
    }
}

/// The GPU's uber stand-in has about the model's hemispherical albedo (cosine-weighted
/// over viewing directions): within 3% + 0.015 per channel. Measured: the smooth linear
/// coating within 1%; the rough nonlinear Beckmann one 1.8% low in red, 0.011 low in blue
/// (its rough lobe is Schlick-GGX in place of the dielectric Beckmann lobe). The
/// conductors' F0 is exact.
#[test]
fn uber_equivalent_keeps_the_mean_albedo() {
    let mean_albedo = |m: &Material| {
        let mut s = Vec3::ZERO;
        let n = 16;
        for i in 0..n {
            let mu = (i as f32 + 0.5) / n as f32;
            let (a, _) = albedo_by_sampling(m, dir(mu, 0.0), 20_000, i as u64);
            s += a * 2.0 * mu / n as f32;
        }
        s
    };
    for m in [
        plastic(Vec3::new(0.8, 0.3, 0.05), 0.0, Distribution::Ggx, false),
        plastic(
            Vec3::new(0.8, 0.3, 0.05),
            0.3162,
            Distribution::Beckmann,
            true,
        ),
    ] {
        let (a, b) = (mean_albedo(&m), mean_albedo(&m.uber_equivalent()));
        let bound = 0.03 * a + Vec3::splat(0.015);
        assert!((a - b).abs().cmple(bound).all(), "{a} vs {b}");
    }
    let au = conductor(0.3, Distribution::Ggx, AU_ETA, AU_K).uber_equivalent();
    assert!(au.conductor.is_none() && au.fresnel);
    assert!(
        (au.specular - fresnel::conductor(1.0, AU_ETA, AU_K))
            .abs()
            .max_element()
            < 1e-6
    );
}

/// Mitsuba 3.9.1's own values (scalar_rgb `BSDF::eval`, which includes cos θ of the
/// outgoing direction) at (cos θ, φ) pairs, printed by scripts/data/mitsuba_bsdf_values.py:
/// gi's eval·cos agrees to 1e-4 relative where the formulas are closed (smooth plastic,
/// conductors) and to 1.5% for the rough coatings (gi's 32-entry transmittance table and its
/// own quadrature against Mitsuba's 64 entries).
/// (case, (cos θ, φ) of gi's wo, the same of wi, Mitsuba's value).
type MitsubaEval = (&'static str, (f32, f32), (f32, f32), [f32; 3]);

#[rustfmt::skip]
const MITSUBA_EVALS: &[MitsubaEval] = &[
    ("plastic", (0.9, 0.0), (0.7, 3.0), [0.17911, 0.0671663, 0.0111944]),
    ("plastic", (0.5, 0.0), (0.5, PI + 0.1), [0.116684, 0.0437567, 0.00729278]),
    ("plastic", (0.2, 1.0), (0.95, 2.0), [0.169649, 0.0636184, 0.0106031]),
    ("plastic", (0.3, 0.0), (0.28, PI), [0.0482077, 0.0180779, 0.00301298]),
    ("plastic_nl", (0.9, 0.0), (0.7, 3.0), [0.13902, 0.0334275, 0.0047238]),
    ("plastic_nl", (0.5, 0.0), (0.5, PI + 0.1), [0.0905671, 0.0217769, 0.0030774]),
    ("plastic_nl", (0.2, 1.0), (0.95, 2.0), [0.131677, 0.0316618, 0.00447428]),
    ("plastic_nl", (0.3, 0.0), (0.28, PI), [0.0374174, 0.00899704, 0.00127142]),
    ("rp_beck", (0.9, 0.0), (0.7, 3.0), [0.187335, 0.0796655, 0.0258306]),
    ("rp_beck", (0.5, 0.0), (0.5, PI + 0.1), [0.775105, 0.705163, 0.670192]),
    ("rp_beck", (0.2, 1.0), (0.95, 2.0), [0.167826, 0.0629346, 0.0104891]),
    ("rp_beck", (0.3, 0.0), (0.28, PI), [5.71039, 5.68119, 5.6666]),
    ("rp_ggx_nl", (0.9, 0.0), (0.7, 3.0), [0.128182, 0.0532545, 0.0275157]),
    ("rp_ggx_nl", (0.5, 0.0), (0.5, PI + 0.1), [0.184686, 0.136805, 0.120357]),
    ("rp_ggx_nl", (0.2, 1.0), (0.95, 2.0), [0.122587, 0.0377232, 0.00857088]),
    ("rp_ggx_nl", (0.3, 0.0), (0.28, PI), [0.46945, 0.446877, 0.439122]),
    ("rc_au_ggx", (0.9, 0.0), (0.7, 3.0), [0.681258, 0.565051, 0.231539]),
    ("rc_au_ggx", (0.5, 0.0), (0.5, PI + 0.1), [2.60268, 2.17541, 1.00259]),
    ("rc_au_ggx", (0.2, 1.0), (0.95, 2.0), [0.0452944, 0.0375685, 0.0153701]),
    ("rc_au_ggx", (0.3, 0.0), (0.28, PI), [5.2344, 4.54244, 2.56569]),
    ("rc_cu_beck", (0.9, 0.0), (0.7, 3.0), [0.693199, 0.451383, 0.372984]),
    ("rc_cu_beck", (0.5, 0.0), (0.5, PI + 0.1), [1.56235, 1.03355, 0.877908]),
    ("rc_cu_beck", (0.2, 1.0), (0.95, 2.0), [0.000138889, 9.04344e-05, 7.47007e-05]),
    ("rc_cu_beck", (0.3, 0.0), (0.28, PI), [2.64962, 1.88019, 1.67774]),
];

fn mitsuba_case(name: &str) -> Material {
    let rho = Vec3::new(0.8, 0.3, 0.05);
    let cu_eta = Vec3::new(0.201005, 0.92375, 1.10222);
    let cu_k = Vec3::new(3.91326, 2.45305, 2.14209);
    match name {
        "plastic" => plastic(rho, 0.0, Distribution::Ggx, false),
        "plastic_nl" => plastic(rho, 0.0, Distribution::Ggx, true),
        "rp_beck" => plastic(rho, 0.1f32.sqrt(), Distribution::Beckmann, false),
        "rp_ggx_nl" => plastic(rho, 0.3f32.sqrt(), Distribution::Ggx, true),
        "rc_au_ggx" => conductor(0.2f32.sqrt(), Distribution::Ggx, AU_ETA, AU_K),
        "rc_cu_beck" => conductor(0.3f32.sqrt(), Distribution::Beckmann, cu_eta, cu_k),
        _ => unreachable!(),
    }
}

#[test]
fn eval_matches_mitsuba() {
    for &(name, (ci, pi), (co, po), want) in MITSUBA_EVALS {
        let m = mitsuba_case(name);
        let (wo, wi) = (dir(ci, pi), dir(co, po));
        let got = m.eval(wo, wi) * wi.z;
        let want = Vec3::from(want);
        let tol = if name.starts_with("rp") { 0.015 } else { 1e-4 };
        let rel = ((got - want).abs() / want.max(Vec3::splat(1e-6))).max_element();
        assert!(
            rel < tol,
            "{name} {ci} {co}: gi {got}, Mitsuba {want} (rel {rel})"
        );
    }
}

/// A one-sided material met from behind (Mitsuba's BSDFs without `twosided`) reflects and
/// transmits nothing and keeps its emission; met from the front, or two-sided, it is itself.
#[test]
fn one_sided_back_is_black() {
    let n = Vec3::Z;
    let (towards_front, towards_back) = (-Vec3::new(0.3, 0.1, 1.0).normalize(), Vec3::Z);
    let wo = dir(0.6, 0.4);
    let wi = dir(0.8, 2.0);
    for base in models() {
        let m = Material {
            one_sided: true,
            emission: Vec3::new(1.0, 2.0, 3.0),
            ..base
        };
        assert_eq!(m.seen_from(n, towards_front), m);
        let two_sided = Material {
            one_sided: false,
            ..m
        };
        assert_eq!(two_sided.seen_from(n, towards_back), two_sided);
        let back = m.seen_from(n, towards_back);
        assert_eq!(back.emission, m.emission);
        assert_eq!(
            back.uber_equivalent(),
            back,
            "{m:?}: no exact model on the back"
        );
        let mut rng = Rng::new(3, 1, 0);
        for (o, i) in [(wo, wi), (-wo, -wi), (wo, -wi)] {
            assert_eq!(back.eval(o, i), Vec3::ZERO, "{m:?}");
            assert_eq!(back.pdf(o, i), 0.0, "{m:?}");
            assert!(back.sample(o, &mut rng).is_none(), "{m:?}");
        }
        assert!(!back.stores_photons() && back.lambertian().is_none_or(|f| f == Vec3::ZERO));
    }
}
