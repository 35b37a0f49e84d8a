//! The path tracer converges at the Monte Carlo rate or better: error against a
//! high-sample render of the same scene falls at least as 1/√spp; its low-discrepancy
//! sampler converges to the independent sampler's mean with less error.

use gi_core::sampling::Rng;
use gi_core::trace::direct::DirectLight;
use gi_core::trace::light_vertex::Connection;
use gi_core::trace::path::{radiance, PathSettings, Strategy};
use gi_core::trace::SceneBvh;
use gi_core::{render, scene::builtin, Silent};
use glam::Vec3;

#[test]
fn error_falls_as_inverse_sqrt_spp() {
    let scene = builtin::load("cornell").unwrap();
    let at = |spp: u32, seed: u64| {
        let s = gi_core::options!(Path, spp: spp, width: 24, height: 24, seed: seed);
        render(&scene, &s, &Silent).unwrap().radiance
    };
    let reference = at(4096, 1000);
    let errors: Vec<f64> = [4u32, 16, 64]
        .iter()
        .map(|&spp| at(spp, spp as u64).rmse(&reference))
        .collect();
    for w in errors.windows(2) {
        // 4× the samples at least halves the error (1/√spp; the low-discrepancy sampler
        // does better); the reference's own noise (1/32 of the 4-spp error) and the spread
        // of an RMSE over 1728 values keep the ratio above 2 - 25%. The reference's noise
        // caps it: a ratio above 8 would mean errors below the reference's own.
        let ratio = w[0] / w[1];
        assert!(
            (1.5..=8.0).contains(&ratio),
            "errors {errors:?}: ratio {ratio}"
        );
    }
}

/// Pixel estimates of `spp` samples of pixel (x, y) by the Sobol sampler or the independent
/// one, one per seed.
fn pixel_estimates(sobol: bool, (x, y): (u32, u32), spp: u32, seeds: u64) -> Vec<Vec3> {
    let scene = builtin::load("cornell").unwrap();
    let bvh = SceneBvh::build(&scene);
    let lights = DirectLight::of(&scene);
    let cam = &scene.camera;
    let ps = PathSettings {
        max_depth: 7,
        rr_depth: 3,
        light_traced: false,
        strategy: Strategy::Mis,
        light_vertex: Connection::Mis,
        first_ray_suns: true,
    };
    // The camera at 24×24: pixels a few degrees wide, with edges and shadows in them.
    let (sx, sy) = (cam.width as f32 / 24.0, cam.height as f32 / 24.0);
    let pixel = (y * 24 + x) as u64;
    (0..seeds)
        .map(|seed| {
            let mut sum = Vec3::ZERO;
            for s in 0..spp {
                let mut rng = if sobol {
                    Rng::sobol(seed, pixel, s)
                } else {
                    Rng::new(seed, pixel, s as u64)
                };
                let j = rng.next_2d();
                let dir = cam.direction((x as f32 + j.x) * sx, (y as f32 + j.y) * sy);
                sum += radiance(&scene, &bvh, &lights, (cam.position, dir), &mut rng, &ps);
            }
            sum / spp as f32
        })
        .collect()
}

/// On pixels of the Cornell box (a box's edge against the wall, the floor by a box's
/// shadow, the back wall's corner, the ceiling), 64 samples of the Sobol sampler average
/// over 48 seeds to the independent sampler's mean (within 4 standard errors of the
/// difference) and their mean squared error against it, summed over the pixels, is below
/// the independent sampler's.
#[test]
fn sobol_sampler_is_unbiased_and_beats_independent_samples() {
    let (spp, seeds) = (64, 48);
    let (mut mse_sobol, mut mse_indep) = (0.0f64, 0.0f64);
    for px in [(9u32, 14u32), (14, 20), (2, 3), (12, 1)] {
        let reference = pixel_estimates(false, px, 4096, 4);
        let reference = reference.iter().copied().sum::<Vec3>() / reference.len() as f32;
        let stats = |v: &[Vec3]| {
            let n = v.len() as f64;
            let mean = v.iter().map(|e| e.element_sum() as f64 / 3.0).sum::<f64>() / n;
            let mse = v
                .iter()
                .map(|e| ((*e - reference).length_squared() / 3.0) as f64)
                .sum::<f64>()
                / n;
            (mean, mse)
        };
        let (m_s, e_s) = stats(&pixel_estimates(true, px, spp, seeds));
        let (m_i, e_i) = stats(&pixel_estimates(false, px, spp, seeds));
        // The standard error of the difference of the two means, from the independent
        // sampler's spread (which bounds the Sobol sampler's) and the reference's noise.
        let se = (2.0 * e_i / seeds as f64 + e_i / 256.0).sqrt();
        assert!(
            (m_s - m_i).abs() < 4.0 * se + 1e-4,
            "pixel {px:?}: Sobol mean {m_s}, independent {m_i}, se {se}"
        );
        mse_sobol += e_s;
        mse_indep += e_i;
    }
    assert!(
        mse_sobol < 0.8 * mse_indep,
        "MSE at {spp} spp: Sobol {mse_sobol}, independent {mse_indep}"
    );
}
