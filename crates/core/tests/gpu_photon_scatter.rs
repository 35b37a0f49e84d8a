//! CPU/GPU parity of a photon's scattering: `photon_scatter` in
//! `gpu/shaders/photon/scatter.wgsl` (the uber BSDF's sampling and the Russian roulette of
//! the GPU photon trace) against `photon::trace::scatter_local` on the same random numbers:
//! the CPU generator is cloned and its four draws (lobe, direction ×2, roulette) go to the
//! GPU, so both sides must pick the same lobe and return the same direction, power and
//! survival probability, or both absorb.
//!
//! Cases: diffuse, glossy (GGX, roughness 0.05–0.6, with and without Schlick), mirror,
//! mixtures, smooth glass (entering and leaving, total internal reflection), each with
//! `wo` on both sides and a geometric normal up to ~25° off the shading normal (so the
//! side checks reject some samples).
//!
//! Tolerances (f32 formulas in a different order, the shader compiler's fused
//! multiply-adds, and on real GPUs sin/cos within Vulkan's 2^-11 absolute error):
//! - direction: each component within 2e-3 absolute;
//! - power and q: within 2e-3 relative (+1e-6 absolute); for diffuse and glossy samples
//!   against the CPU's weight at the GPU's direction (`Material::eval`·cos/`pdf`): a sharp
//!   GGX lobe's sampled direction is ill-conditioned in f32 (1 + (α² − 1)u at u near 1;
//!   measured: 3 of 36k samples 1e-4 apart at roughness 0.05, their weights 0.75% apart),
//!   so its weight is checked where the GPU sampled.
//!
//! A discrete decision (lobe, Fresnel choice, horizon, side, roulette) may differ where
//! rounding decides it (a random number within rounding of its threshold: about 1e-6 of
//! the cases for each of four decisions); at most 1 case in 1000 may differ so, and every
//! difference of the continuous outputs fails.

use gi_core::bsdf::{Lobe, Material};
use gi_core::gpu;
use gi_core::gpu::photon::scatter_query::{scatter, GpuScattered, ScatterInput};
use gi_core::photon::trace::{scatter_local, Scattered};
use gi_core::sampling::{uniform_sphere, Rng};
use glam::{Vec3, Vec4};

fn materials() -> Vec<Material> {
    let d = Vec3::new(0.73, 0.065, 0.05);
    let s = Vec3::new(0.04, 0.5, 0.9);
    let glass = |ior: f32| Material {
        diffuse: Vec3::ZERO,
        transmission: Vec3::new(0.95, 0.9, 1.0),
        ior,
        ..Default::default()
    };
    let glossy = |roughness: f32, fresnel: bool, diffuse: Vec3| Material {
        diffuse,
        specular: s,
        roughness,
        fresnel,
        ..Default::default()
    };
    vec![
        Material {
            diffuse: d,
            ..Default::default()
        },
        glossy(0.3, true, d),
        glossy(0.05, true, d * 0.5),
        glossy(0.6, false, Vec3::ZERO),
        glossy(0.0, false, Vec3::ZERO),
        glossy(0.0, true, d),
        glass(1.5),
        glass(2.4),
        Material {
            specular: Vec3::splat(0.04),
            fresnel: true,
            ..glass(1.5)
        },
    ]
}

/// One case: material, local wo, local geometric normal, power, the CPU generator.
struct Case {
    m: Material,
    wo: Vec3,
    ng: Vec3,
    power: Vec3,
    rng: Rng,
}

fn cases(n_per_material: usize) -> Vec<Case> {
    let mut out = Vec::new();
    let mut r = Rng::new(45, 1, 0);
    for (k, m) in materials().into_iter().enumerate() {
        for i in 0..n_per_material {
            let wo = uniform_sphere(r.next_2d());
            let tilt = uniform_sphere(r.next_2d()) * 0.4;
            let ng = (Vec3::Z + tilt).normalize();
            let power = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) + 0.05;
            let rng = Rng::new(7, k as u64, i as u64);
            out.push(Case {
                m,
                wo,
                ng,
                power,
                rng,
            });
        }
    }
    out
}

/// The four numbers the CPU scatter draws, in its order.
fn draws(rng: &Rng) -> Vec4 {
    let mut r = rng.clone();
    Vec4::new(r.next_f32(), r.next_f32(), r.next_f32(), r.next_f32())
}

fn close(a: Vec3, b: Vec3, rel: f32) -> bool {
    (a - b).abs().max_element() <= rel * a.abs().max_element().max(b.abs().max_element()) + 1e-6
}

/// The CPU's power and q for a non-delta sample in direction `wi` (the BSDF's
/// f·cos/pdf and the roulette's formula, on the CPU's f32 `eval` and `pdf`).
fn cpu_at(case: &Case, wi: Vec3) -> (Vec3, f32) {
    let w = case.m.eval(case.wo, wi) * wi.z.abs() / case.m.pdf(case.wo, wi);
    let scattered = case.power * w;
    let q = (scattered.max_element() / case.power.max_element()).min(1.0);
    (scattered / q, q)
}

fn agrees(case: &Case, c: Option<&Scattered>, g: Option<&GpuScattered>) -> Result<bool, String> {
    match (c, g) {
        (None, None) => Ok(true),
        (Some(c), Some(g)) if c.lobe == g.lobe => {
            let dir = (c.wi - g.wi).abs().max_element() <= 2e-3;
            // Diffuse and glossy weights are compared at the GPU's direction: near the peak
            // of a sharp lobe (roughness 0.05) the sampled direction's f32 conditioning
            // (1 + (α² − 1)u for u near 1) moves it by ~1e-4, and the weight by percent.
            let (cp, cq) = match c.lobe {
                Lobe::Diffuse | Lobe::Glossy => cpu_at(case, g.wi),
                _ => (c.power, c.q),
            };
            let power = close(cp, g.power, 2e-3);
            let q = (cq - g.q).abs() <= 2e-3 * cq + 1e-6;
            if dir && power && q {
                Ok(true)
            } else {
                Err(format!(
                    "{:?}: wi {} vs {}, power {} vs {}, q {} vs {}",
                    c.lobe, c.wi, g.wi, c.power, g.power, c.q, g.q
                ))
            }
        }
        _ => Ok(false),
    }
}

#[test]
fn gpu_scatter_matches_the_cpu_on_the_same_random_numbers() {
    let ctx = gpu::context(None).expect("a GPU adapter (lavapipe in CI)");
    let cases = cases(4000);
    let us: Vec<Vec4> = cases.iter().map(|c| draws(&c.rng)).collect();
    let inputs: Vec<ScatterInput> = cases
        .iter()
        .zip(&us)
        .map(|(c, &u)| ScatterInput::new(&c.m, c.wo, c.ng, c.power, u))
        .collect();
    let gpu_out = scatter(&ctx, &inputs).expect("the scatter query runs");
    assert_eq!(gpu_out.len(), cases.len());
    let (mut grazes, mut alive, mut failures) = (0, 0, Vec::new());
    let mut lobes = std::collections::HashMap::new();
    for (i, ((c, &u), g)) in cases.iter().zip(&us).zip(&gpu_out).enumerate() {
        let mut rng = c.rng.clone();
        let cpu = scatter_local(&c.m, c.wo, c.ng, c.power, &mut rng);
        match agrees(c, cpu.as_ref(), g.as_ref()) {
            Ok(true) => {
                if let Some(s) = &cpu {
                    alive += 1;
                    *lobes.entry(format!("{:?}", s.lobe)).or_insert(0) += 1;
                }
            }
            Ok(false) => {
                grazes += 1;
                println!(
                    "case {i}: cpu {:?} gpu {:?}, u {u}",
                    cpu.map(|s| s.lobe),
                    g.map(|s| s.lobe)
                );
            }
            Err(e) => failures.push(format!("case {i}: {e}")),
        }
    }
    println!(
        "{} cases, {alive} scattered, {grazes} grazes, lobes {lobes:?}",
        cases.len()
    );
    assert!(
        failures.is_empty(),
        "{} mismatches: {:#?}",
        failures.len(),
        &failures[..failures.len().min(10)]
    );
    assert!(grazes * 1000 <= cases.len(), "{grazes} grazes");
    // Every lobe was exercised, and most samples survive (the test is not vacuous).
    assert_eq!(lobes.len(), 5, "{lobes:?}");
    assert!(alive * 3 > cases.len(), "{alive} of {}", cases.len());
}
