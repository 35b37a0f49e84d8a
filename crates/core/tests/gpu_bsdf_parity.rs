//! CPU/GPU parity of the BSDFs: a compute shader evaluates `bsdf.wgsl` (the uber BSDF) or
//! `models.wgsl` (Mitsuba's coated plastics, conductors, Beckmann) on a table of
//! (normal, wo, wi, material) cases and must match `Material::eval(wo, wi)·|cos θi|`: of the
//! uber stand-in (`Material::uber_equivalent`) for `bsdf.wgsl`, of the material itself for
//! `models.wgsl`.
//!
//! Tolerance per channel: |gpu − cpu| ≤ 1e-4·|cpu| + 1e-6 + 4·s, where the absolute floor
//! 1e-6 guards values near zero and `s` is the case's own f32 sensitivity: the largest change
//! of the CPU value when the normal, wo or wi moves by 1e-6 (about 8 ULPs: the rounding of the
//! world-to-local rotation, which the CPU does and the shader doesn't). Near the peak of a sharp GGX
//! lobe (roughness 0.05) one ULP in the half vector changes D by percent, so no two f32
//! implementations can agree there to 1e-4; everywhere else `s` is negligible.

mod common;

use bytemuck::Pod;
use gi_core::bsdf::{Coating, Conductor, Distribution, Material};
use gi_core::gpu::{self, shaders};
use gi_core::sampling::{uniform_sphere, Frame, Rng};
use glam::Vec3;

#[derive(Clone, Copy)]
struct Case {
    material: Material,
    normal: Vec3,
    wo: Vec3,
    wi: Vec3,
}

fn materials() -> Vec<Material> {
    let d = Vec3::new(0.73, 0.065, 0.05);
    let s = Vec3::new(0.04, 0.5, 0.9);
    let mut out = vec![
        Material {
            diffuse: d,
            ..Default::default()
        },
        Material {
            diffuse: Vec3::ZERO,
            specular: s,
            roughness: 0.0,
            ..Default::default()
        },
        Material {
            diffuse: d,
            specular: s,
            roughness: 0.0,
            fresnel: true,
            ..Default::default()
        },
        Material {
            diffuse: Vec3::splat(0.1),
            transmission: Vec3::splat(0.9),
            ior: 1.5,
            ..Default::default()
        },
    ];
    // Mitsuba's models: a rough coating, a rough conductor (gold), a Beckmann uber lobe.
    out.push(Material {
        diffuse: d,
        specular: Vec3::ONE,
        roughness: 0.3,
        distribution: Distribution::Beckmann,
        coating: Some(Coating::new(1.49, true, 0.09, Distribution::Beckmann)),
        ..Default::default()
    });
    out.push(Material {
        diffuse: Vec3::ZERO,
        specular: Vec3::ONE,
        roughness: 0.4,
        conductor: Some(Conductor::new(
            Vec3::new(0.143, 0.375, 1.442),
            Vec3::new(3.983, 2.386, 1.603),
        )),
        ..Default::default()
    });
    out.push(Material {
        diffuse: d,
        specular: s,
        roughness: 0.4,
        fresnel: true,
        distribution: Distribution::Beckmann,
        ..Default::default()
    });
    for roughness in [0.05, 0.2, 0.5, 1.0] {
        for fresnel in [false, true] {
            out.push(Material {
                diffuse: Vec3::ZERO,
                specular: s,
                roughness,
                fresnel,
                ..Default::default()
            });
            out.push(Material {
                diffuse: d,
                specular: Vec3::splat(0.04),
                roughness,
                fresnel,
                ..Default::default()
            });
        }
    }
    out
}

/// Mitsuba's models: smooth and rough plastics (GGX and Beckmann, linear and `nonlinear`,
/// white and coloured bases), conductors (gold and Mitsuba's "none") at several roughnesses,
/// the uber BSDF with Beckmann's distribution, and the uber materials above (which
/// `models.wgsl` must shade as `bsdf.wgsl` does).
fn models() -> Vec<Material> {
    let au = (
        Vec3::new(0.143036, 0.375307, 1.44205),
        Vec3::new(3.983, 2.38556, 1.60336),
    );
    let mut out = Vec::new();
    for dist in [Distribution::Ggx, Distribution::Beckmann] {
        for roughness in [0.0f32, 0.1, 0.3162, 0.7] {
            for (rho, nonlinear) in [
                (Vec3::new(0.8, 0.3, 0.05), false),
                (Vec3::new(0.8, 0.3, 0.05), true),
                (Vec3::ONE, false),
            ] {
                out.push(Material {
                    diffuse: rho,
                    specular: Vec3::new(1.0, 0.9, 0.7),
                    roughness,
                    distribution: dist,
                    coating: Some(Coating::new(1.49, nonlinear, roughness * roughness, dist)),
                    ..Default::default()
                });
            }
            for (eta, k) in [au, (Vec3::ZERO, Vec3::ONE)] {
                out.push(Material {
                    diffuse: Vec3::ZERO,
                    specular: Vec3::ONE,
                    roughness,
                    distribution: dist,
                    conductor: Some(Conductor::new(eta, k)),
                    ..Default::default()
                });
            }
            out.push(Material {
                diffuse: Vec3::splat(0.5),
                specular: Vec3::splat(0.04),
                fresnel: true,
                roughness,
                distribution: dist,
                ..Default::default()
            });
        }
    }
    out.extend(materials());
    out
}

/// Directions: random pairs, grazing ones (cos 1e-3 and 1e-2), pairs across the horizon,
/// and pairs near the mirror direction (the glossy peak), `per` per material.
fn cases(materials: &[Material], per: usize) -> Vec<Case> {
    let mut rng = Rng::new(11, 0, 0);
    let mut out = Vec::new();
    for &material in materials {
        for k in 0..per {
            let normal = uniform_sphere(rng.next_2d());
            let frame = Frame::new(normal);
            let mut wo_l = uniform_sphere(rng.next_2d());
            let mut wi_l = uniform_sphere(rng.next_2d());
            match k % 6 {
                0 => {
                    wo_l = Vec3::new(wo_l.x, wo_l.y, 0.0).normalize() * 0.999_999_5 + Vec3::Z * 1e-3
                }
                1 => wi_l = Vec3::new(wi_l.x, wi_l.y, 0.0).normalize() * 0.99995 + Vec3::Z * 1e-2,
                2 => {
                    // Near the mirror direction of wo.
                    wo_l.z = wo_l.z.abs();
                    wi_l = (Vec3::new(-wo_l.x, -wo_l.y, wo_l.z) + wi_l * 0.05).normalize();
                }
                _ => {}
            }
            if k % 2 == 0 {
                // Mostly the same hemisphere, so that most cases are non-zero.
                wi_l.z = wi_l.z.abs() * wo_l.z.signum();
            }
            let (wo, wi) = (
                frame.to_world(wo_l.normalize()),
                frame.to_world(wi_l.normalize()),
            );
            out.push(Case {
                material,
                normal,
                wo,
                wi,
            });
        }
    }
    out
}

/// `Material::eval(wo, wi)·|cos θi|` of `m` for the case's directions.
fn cpu_of(m: &Material, c: &Case) -> Vec3 {
    let frame = Frame::new(c.normal);
    let (wo, wi) = (frame.to_local(c.wo), frame.to_local(c.wi));
    m.eval(wo, wi) * wi.z.abs()
}

/// The CPU value `bsdf.wgsl` must give: the BSDF of the material's GPU copy (`to_raw`), the
/// uber stand-in of Mitsuba's models (`Material::uber_equivalent`; the material itself
/// for uber materials).
fn cpu_uber(c: &Case) -> Vec3 {
    cpu_of(&c.material.uber_equivalent(), c)
}

/// The CPU value `models.wgsl` must give: the material's own BSDF.
fn cpu_exact(c: &Case) -> Vec3 {
    cpu_of(&c.material, c)
}

/// The largest change of the CPU value when an input moves by about 8 ULPs.
fn sensitivity(c: &Case, cpu: fn(&Case) -> Vec3) -> Vec3 {
    let base = cpu(c);
    let mut s = Vec3::ZERO;
    for axis in 0..9 {
        for sign in [-1.0f32, 1.0] {
            let mut d = Vec3::ZERO;
            d[axis % 3] = 1e-6 * sign;
            let (n, wo, wi) = match axis / 3 {
                0 => (c.normal, c.wo + d, c.wi),
                1 => (c.normal, c.wo, c.wi + d),
                _ => (c.normal + d, c.wo, c.wi),
            };
            let p = Case {
                normal: n.normalize(),
                wo: wo.normalize(),
                wi: wi.normalize(),
                ..*c
            };
            s = s.max((cpu(&p) - base).abs());
        }
    }
    s
}

/// Runs the compute kernel `parts` (the shared sources, then the kernel) over `n` cases
/// packed in `input`, one vec4 result per case.
fn run_kernel(parts: &[&str], input: &[u8], n: usize) -> Vec<Vec3> {
    let ctx = gpu::context(None).expect("a GPU adapter (lavapipe in CI)");
    common::kernel::run(&ctx, parts, input, n, None)
        .iter()
        .map(|v| Vec3::new(v[0], v[1], v[2]))
        .collect()
}

fn dir4(v: Vec3) -> [f32; 4] {
    v.extend(0.0).into()
}

/// Checks `gpu` against `cpu` case by case (tolerance in the module's doc).
fn compare(cases: &[Case], gpu: &[Vec3], cpu: fn(&Case) -> Vec3) {
    let mut failures = Vec::new();
    let mut nonzero = 0;
    for (i, (c, g)) in cases.iter().zip(gpu).enumerate() {
        let r = cpu(c);
        if r.max_element() > 0.0 {
            nonzero += 1;
        }
        let tol = r.abs() * 1e-4 + Vec3::splat(1e-6) + 4.0 * sensitivity(c, cpu);
        if (*g - r).abs().cmpgt(tol).any() || !g.is_finite() {
            failures.push(format!(
                "case {i}: {:?} n={} wo={} wi={}: gpu {g} cpu {r}",
                c.material, c.normal, c.wo, c.wi
            ));
        }
    }
    assert!(
        nonzero > cases.len() / 3,
        "too few non-zero cases: {nonzero}"
    );
    assert!(
        failures.is_empty(),
        "{} of {} cases differ:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// The kernel's `Case` array: each case's GPU material record (`material`) followed by its
/// normal, wo and wi as vec4s (the WGSL struct's layout: the records are multiples of 16
/// bytes).
fn case_bytes<M: Pod>(cases: &[Case], material: impl Fn(&Material) -> M) -> Vec<u8> {
    let mut bytes = Vec::new();
    for c in cases {
        let m = material(&c.material);
        assert_eq!(std::mem::size_of::<M>() % 16, 0, "a record of whole vec4s");
        bytes.extend_from_slice(bytemuck::bytes_of(&m));
        for v in [c.normal, c.wo, c.wi] {
            bytes.extend_from_slice(bytemuck::bytes_of(&dir4(v)));
        }
    }
    bytes
}

/// The evaluation kernel for the material type `material` and its `eval` function.
fn eval_kernel(material: &str, eval: &str) -> String {
    include_str!("gpu_eval_parity.wgsl")
        .replace("MATERIAL_T", material)
        .replace("EVAL_FN", eval)
}

#[test]
fn wgsl_bsdf_matches_cpu() {
    let cases = cases(&materials(), 48);
    let raw = case_bytes(&cases, Material::to_raw);
    let kernel = eval_kernel("Material", "bsdf_eval");
    let parts = [shaders::COMMON, shaders::BSDF, kernel.as_str()];
    let gpu = run_kernel(&parts, &raw, cases.len());
    compare(&cases, &gpu, cpu_uber);
}

/// `models.wgsl` against the CPU's exact models (no stand-in).
#[test]
fn wgsl_models_match_cpu() {
    let cases = cases(&models(), 60);
    let raw = case_bytes(&cases, Material::to_model_raw);
    let kernel = eval_kernel("ModelMaterial", "model_eval");
    let parts = [
        shaders::COMMON,
        shaders::BSDF,
        shaders::MODELS,
        kernel.as_str(),
    ];
    let gpu = run_kernel(&parts, &raw, cases.len());
    compare(&cases, &gpu, cpu_exact);
}
