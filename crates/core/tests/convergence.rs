//! The path tracer converges at the Monte Carlo rate: error against a high-sample render
//! of the same scene falls as 1/√spp.

use gi_core::{render, scene::builtin, Silent};

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
        // 4× the samples halves the error; the reference's own noise (1/32 of the 4-spp
        // error) and the spread of an RMSE over 1728 values keep the ratio within ±25%.
        let ratio = w[0] / w[1];
        assert!(
            (1.5..=2.5).contains(&ratio),
            "errors {errors:?}: ratio {ratio}"
        );
    }
}
