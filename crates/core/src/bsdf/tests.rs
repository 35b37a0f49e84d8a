//! Energy conservation, reciprocity and chi-square tests of the uber BSDF.

use super::*;
use crate::sampling::{chi_square, uniform_sphere, Rng};

pub(super) fn dir(cos_theta: f32, phi: f32) -> Vec3 {
    let s = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), cos_theta)
}

/// Mean sample weight over `n` samples: an unbiased estimate of the albedo, with its standard error.
pub(super) fn albedo_by_sampling(m: &Material, wo: Vec3, n: usize, seed: u64) -> (Vec3, Vec3) {
    let mut rng = Rng::new(seed, 1, 0);
    let mut sum = glam::DVec3::ZERO;
    let mut sum2 = glam::DVec3::ZERO;
    for _ in 0..n {
        if let Some(s) = m.sample(wo, &mut rng) {
            let w = s.weight.as_dvec3();
            sum += w;
            sum2 += w * w;
        }
    }
    let mean = sum / n as f64;
    let var = (sum2 / n as f64 - mean * mean).max(glam::DVec3::ZERO);
    (mean.as_vec3(), (var / n as f64).sqrt().as_vec3())
}

fn material_grid() -> Vec<Material> {
    let mut out = Vec::new();
    for &d in &[0.0f32, 0.5, 1.0] {
        for &s in &[0.0f32, 0.04, 0.5, 1.0] {
            for &r in &[0.0f32, 0.2, 0.6, 1.0] {
                for &fresnel in &[false, true] {
                    for &t in &[0.0f32, 1.0 - d] {
                        out.push(Material {
                            diffuse: Vec3::splat(d),
                            specular: Vec3::splat(s),
                            roughness: r,
                            fresnel,
                            transmission: Vec3::splat(t),
                            ior: 1.5,
                            ..Material::default()
                        });
                    }
                }
            }
        }
    }
    out
}

#[test]
fn albedo_never_exceeds_one() {
    for (i, m) in material_grid().iter().enumerate() {
        for &c in &[1.0f32, 0.7, 0.3, 0.05] {
            let wo = dir(c, 0.3);
            let (a, se) = albedo_by_sampling(m, wo, 20_000, i as u64);
            // 1 plus four standard errors of the estimate (plus float slack): a real excess
            // of more than a fraction of a percent fails.
            let limit = Vec3::ONE + 4.0 * se + Vec3::splat(1e-4);
            assert!(
                a.cmple(limit).all(),
                "material {m:?} cos {c}: albedo {a} (se {se})"
            );
        }
    }
}

#[test]
fn lambertian_albedo_is_exact() {
    let m = Material {
        diffuse: Vec3::new(0.2, 0.5, 0.9),
        ..Default::default()
    };
    let mut rng = Rng::new(5, 0, 0);
    for _ in 0..1000 {
        let wo = uniform_sphere(rng.next_2d());
        let s = m
            .sample(wo, &mut rng)
            .expect("a Lambertian sample is never absorbed");
        // Each cosine-weighted sample carries exactly the albedo.
        assert!((s.weight - m.diffuse).abs().max_element() < 1e-5);
        assert!(
            s.wi.z * wo.z > 0.0,
            "two-sided: the sample stays on the viewer's side"
        );
    }
    // And ∫ f cos dω = ρL by quadrature, independent of the sampler.
    let wo = dir(0.6, 1.0);
    let n = 400;
    let mut sum = Vec3::ZERO;
    for i in 0..n {
        for j in 0..n {
            let z = (i as f32 + 0.5) / n as f32;
            let phi = (j as f32 + 0.5) / n as f32 * std::f32::consts::TAU;
            let wi = dir(z, phi);
            sum += m.eval(wo, wi) * z * (std::f32::consts::TAU / (n * n) as f32);
        }
    }
    assert!((sum - m.diffuse).abs().max_element() < 1e-3, "{sum}");
    assert!((m.scatter_probability(wo) - m.diffuse).abs().max_element() < 1e-6);
}

#[test]
fn mirror_and_glass_conserve_energy_exactly() {
    let mirror = Material {
        diffuse: Vec3::ZERO,
        specular: Vec3::splat(0.9),
        ..Default::default()
    };
    let glass = Material {
        diffuse: Vec3::ZERO,
        transmission: Vec3::ONE,
        ior: 1.5,
        ..Default::default()
    };
    for &c in &[1.0f32, 0.5, 0.1] {
        let (a, _) = albedo_by_sampling(&mirror, dir(c, 0.0), 1000, 1);
        assert!((a - Vec3::splat(0.9)).abs().max_element() < 1e-5);
        let (a, _) = albedo_by_sampling(&glass, dir(c, 0.0), 1000, 1);
        assert!((a - Vec3::ONE).abs().max_element() < 1e-5);
        // From inside, beyond the critical angle, everything reflects.
        let (a, _) = albedo_by_sampling(&glass, dir(-c, 0.0), 1000, 1);
        assert!((a - Vec3::ONE).abs().max_element() < 1e-5);
    }
}

/// Checks f(a, b) = f(b, a) within 1e-4 of the larger for `pairs` random direction pairs per
/// material (one random sequence over all).
pub(super) fn assert_reciprocal(materials: &[Material], pairs: usize) {
    let mut rng = Rng::new(9, 0, 0);
    for m in materials {
        for _ in 0..pairs {
            let a = uniform_sphere(rng.next_2d());
            let b = uniform_sphere(rng.next_2d());
            let (f1, f2) = (m.eval(a, b), m.eval(b, a));
            let scale = f1.max_element().max(f2.max_element()).max(1e-6);
            assert!(
                (f1 - f2).abs().max_element() / scale < 1e-4,
                "{m:?}: {f1} vs {f2}"
            );
        }
    }
}

#[test]
fn non_delta_part_is_reciprocal() {
    assert_reciprocal(&material_grid(), 50);
}

/// Pearson chi-square test of `sampler.sample` against `reference.pdf` over a (cos θ, φ)
/// grid of the sphere; returns the p-value.
pub(super) fn chi_square(sampler: &Material, reference: &Material, wo: Vec3, seed: u64) -> f64 {
    const NZ: usize = 16;
    const NP: usize = 32;
    const SUB: usize = 24;
    let n = 400_000usize;
    let mut observed = vec![0.0f64; NZ * NP];
    let mut rng = Rng::new(seed, 0, 0);
    for _ in 0..n {
        if let Some(s) = sampler.sample(wo, &mut rng) {
            if s.lobe.is_delta() {
                continue;
            }
            let z = s.wi.z.clamp(-1.0, 1.0);
            let phi = s.wi.y.atan2(s.wi.x).rem_euclid(std::f32::consts::TAU);
            let iz = (((z + 1.0) * 0.5 * NZ as f32) as usize).min(NZ - 1);
            let ip = ((phi / std::f32::consts::TAU * NP as f32) as usize).min(NP - 1);
            observed[iz * NP + ip] += 1.0;
        }
    }
    let grid = chi_square::Grid {
        rows: NZ,
        columns: NP,
        sub: SUB,
    };
    let expected = grid.expected(n, |z, phi| {
        reference.pdf(wo, dir(z as f32, phi as f32)) as f64
    });
    chi_square::p_value(&observed, &expected)
}

#[test]
fn sampling_matches_pdf_chi_square() {
    let cases = [
        Material {
            diffuse: Vec3::splat(0.7),
            ..Default::default()
        },
        Material {
            diffuse: Vec3::ZERO,
            specular: Vec3::splat(0.9),
            roughness: 0.5,
            ..Default::default()
        },
        Material {
            diffuse: Vec3::ZERO,
            specular: Vec3::splat(0.9),
            roughness: 0.3,
            fresnel: true,
            ..Default::default()
        },
        Material {
            diffuse: Vec3::new(0.6, 0.3, 0.2),
            specular: Vec3::splat(0.04),
            roughness: 0.4,
            fresnel: true,
            ..Default::default()
        },
        Material {
            diffuse: Vec3::splat(0.3),
            specular: Vec3::splat(0.3),
            roughness: 0.8,
            ..Default::default()
        },
        Material {
            diffuse: Vec3::splat(0.3),
            specular: Vec3::splat(0.2),
            roughness: 0.5,
            transmission: Vec3::splat(0.5),
            ..Default::default()
        },
    ];
    let views = [dir(0.9, 0.4), dir(0.4, 2.0), dir(-0.6, 4.0)];
    let tests = (cases.len() * views.len()) as f64;
    // Šidák-corrected 1% significance over all tests.
    let alpha = 1.0 - (1.0 - 0.01f64).powf(1.0 / tests);
    for (i, m) in cases.iter().enumerate() {
        for (j, wo) in views.iter().enumerate() {
            let p = chi_square(m, m, *wo, (i * 10 + j) as u64);
            assert!(p > alpha, "material {i} view {j}: p = {p:e}");
        }
    }
}

#[test]
fn chi_square_detects_a_wrong_pdf() {
    // Guard against a test that cannot fail: samples of one roughness checked against the
    // pdf of a slightly different one must be rejected.
    let m = Material {
        diffuse: Vec3::ZERO,
        specular: Vec3::splat(0.9),
        roughness: 0.5,
        ..Default::default()
    };
    let wrong = Material {
        roughness: 0.45,
        ..m
    };
    assert!(chi_square(&m, &wrong, dir(0.7, 0.0), 3) < 1e-6);
}

/// `delta_lobes` (the splitting of the specular paths) has the expectation of `sample`
/// restricted to the delta lobes: per lobe, the summed sample weights over n draws, divided
/// by n, equal the lobe's expected weight, and the directions agree. Over the material grid
/// (mirrors, glass, mixtures) from both sides and at grazing angles (total internal
/// reflection from inside). Tolerance: 5 standard errors of the per-lobe mean (each sample
/// weight is bounded by 1/p of its lobe, so the mean is well behaved) plus 1e-4.
#[test]
fn delta_lobes_match_sampling_in_expectation() {
    let n = 20_000usize;
    for (mi, m) in material_grid().iter().enumerate() {
        for (ci, &cos) in [0.95f32, 0.5, 0.1, -0.3, -0.9].iter().enumerate() {
            let wo = dir(cos, 0.7);
            let mut rng = Rng::new(7, mi as u64, ci as u64);
            let lobes = [Lobe::Mirror, Lobe::GlassReflect, Lobe::GlassRefract];
            let mut sum = [glam::DVec3::ZERO; 3];
            let mut sum2 = [glam::DVec3::ZERO; 3];
            for _ in 0..n {
                let Some(s) = m.sample(wo, &mut rng) else {
                    continue;
                };
                if let Some(i) = lobes.iter().position(|l| *l == s.lobe) {
                    let w = s.weight.as_dvec3();
                    sum[i] += w;
                    sum2[i] += w * w;
                    let split = m.delta_lobes(wo).find(|d| d.lobe == s.lobe);
                    let split = split.expect("a sampled delta lobe is among the split ones");
                    assert!((split.wi - s.wi).length() < 1e-5, "{:?}", s.lobe);
                }
            }
            for (i, lobe) in lobes.iter().enumerate() {
                let mean = sum[i] / n as f64;
                let se =
                    ((sum2[i] / n as f64 - mean * mean).max(glam::DVec3::ZERO) / n as f64).sqrt();
                let split = m
                    .delta_lobes(wo)
                    .find(|d| d.lobe == *lobe)
                    .map_or(glam::DVec3::ZERO, |d| d.weight.as_dvec3());
                let err = (split - mean).abs();
                assert!(
                    err.cmple(se * 5.0 + 1e-4).all(),
                    "material {mi} cos {cos} {lobe:?}: split {split} sampled {mean} ± {se}"
                );
            }
        }
    }
}

/// `Material::lambertian` claims a constant BSDF only where `eval` is one: over the grid,
/// every material it accepts evaluates to ρ/π for directions on one side and 0 across,
/// and every material it rejects differs from that somewhere (so the fast path of the
/// photon gathers, `photon::knn`, cannot change an estimate).
#[test]
fn lambertian_shortcut_equals_eval() {
    let dirs: Vec<Vec3> = (0..12)
        .flat_map(|i| (0..6).map(move |j| dir(0.05 + 0.08 * i as f32, 1.1 * j as f32)))
        .collect();
    let (mut accepted, mut rejected) = (0, 0);
    for m in material_grid() {
        let constant = m.diffuse * std::f32::consts::FRAC_1_PI;
        let matches = dirs.iter().all(|&wo| {
            dirs.iter().all(|&wi| {
                let same = (m.eval(wo, wi) - constant).abs().max_element()
                    <= 1e-6 * (1.0 + constant.max_element());
                let across = m.eval(wo, -wi) == Vec3::ZERO && m.eval(-wo, wi) == Vec3::ZERO;
                same && across
            })
        });
        match m.lambertian() {
            Some(f) => {
                assert_eq!(f, constant);
                assert!(matches, "{m:?} is not Lambertian");
                accepted += 1;
            }
            None => {
                assert!(!matches || m.diffuse == Vec3::ZERO, "{m:?} is Lambertian");
                rejected += 1;
            }
        }
    }
    assert!(accepted > 0 && rejected > 0, "{accepted} / {rejected}");
}

/// The short path of Lambertian materials gives bit for bit what the general `sample`,
/// `eval` and `pdf` give (so images do not change), over albedos, directions on both sides
/// and Sobol draws; and only materials with a diffuse lobe alone take it.
#[test]
fn lambertian_short_path_equals_the_general_one() {
    let mut r = Rng::new(11, 12, 13);
    for k in 0..2000u32 {
        let m = Material {
            diffuse: Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) + Vec3::splat(1e-3),
            ..Default::default()
        };
        assert!(m.is_lambertian());
        let wo = dir(
            r.next_f32() * 2.0 - 1.0,
            r.next_f32() * std::f32::consts::TAU,
        );
        let wi = dir(
            r.next_f32() * 2.0 - 1.0,
            r.next_f32() * std::f32::consts::TAU,
        );
        if wo.z * wi.z > 0.0 {
            assert_eq!(m.eval(wo, wi), m.eval_general(wo, wi));
            assert_eq!(m.pdf(wo, wi), m.pdf_general(wo, wi));
        }
        let sign = if wo.z < 0.0 { -1.0 } else { 1.0 };
        let (mut a, mut b) = (
            Rng::sobol(5, k as u64, k % 64),
            Rng::sobol(5, k as u64, k % 64),
        );
        let (x, y) = (m.sample(wo, &mut a), m.sample_general(wo, sign, &mut b));
        let (x, y) = (x.unwrap(), y.unwrap());
        assert_eq!(
            (x.wi, x.weight, x.pdf, x.lobe),
            (y.wi, y.weight, y.pdf, y.lobe)
        );
        assert_eq!(a.next_f32(), b.next_f32(), "the same number of draws");
    }
    let not = [
        Material {
            specular: Vec3::splat(0.1),
            ..Default::default()
        },
        Material {
            fresnel: true,
            ..Default::default()
        },
        Material {
            transmission: Vec3::splat(0.5),
            ..Default::default()
        },
        Material {
            diffuse: Vec3::ZERO,
            ..Default::default()
        },
    ];
    assert!(not.iter().all(|m| !m.is_lambertian()));
}
