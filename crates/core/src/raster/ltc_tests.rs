//! The closed form against a numeric integral of the uber material's GGX lobe
//! (`Material::eval`·cos θi, Fresnel 1 and Schlick) over polygons.

use super::*;
use crate::bsdf::Material;

/// ∫ f·cos θi dω over the parallelogram (`corner`, edges `e1`, `e2`) or, with `triangle`,
/// the triangle (`corner`, `corner + e1`, `corner + e2`), by the midpoint rule on an
/// `n`×`n` grid of its area (f64 sums), seen from the origin with normal z and view `wo`.
fn numeric(m: &Material, wo: Vec3, corner: Vec3, e1: Vec3, e2: Vec3, triangle: bool) -> f64 {
    numeric_lobe(&|wi| m.eval(wo, wi).x, corner, e1, e2, triangle)
}

/// [`numeric`] of the lobe `f` (f of wi, without the cosine).
fn numeric_lobe(f: &dyn Fn(Vec3) -> f32, corner: Vec3, e1: Vec3, e2: Vec3, triangle: bool) -> f64 {
    let n = 600;
    let normal = e1.cross(e2);
    let area = normal.length() as f64;
    let nl = normal.normalize();
    let mut sum = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let (u, v) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            if triangle && u + v > 1.0 {
                continue;
            }
            let p = corner + e1 * u + e2 * v;
            let d2 = p.length_squared();
            let wi = p / d2.sqrt();
            if wi.z <= 0.0 {
                continue;
            }
            sum += (f(wi) * wi.z * wi.dot(nl).abs() / d2) as f64;
        }
    }
    sum * area / (n * n) as f64
}

struct Case {
    roughness: f32,
    theta: f32,
    corner: Vec3,
    e1: Vec3,
    e2: Vec3,
    triangle: bool,
}

/// Squares and triangles near the mirror direction of wo and off it, one crossing the
/// horizon, at roughnesses between the table's nodes (the interpolation is tested too).
fn cases() -> Vec<Case> {
    let mut out = Vec::new();
    for roughness in [0.2f32, 0.3, 0.5, 0.8] {
        for theta in [0.1f32, 0.5, 1.0] {
            let mirror_x = -2.0 * theta.tan();
            for (k, (dx, dy)) in [(0.0, 0.0), (1.0, 0.5), (0.3, -1.5)]
                .into_iter()
                .enumerate()
            {
                out.push(Case {
                    roughness,
                    theta,
                    corner: Vec3::new(mirror_x + dx - 0.5, dy - 0.5, 2.0),
                    e1: Vec3::X,
                    e2: Vec3::Y,
                    triangle: k == 1,
                });
            }
            // A vertical square standing across the horizon, in front of the view.
            out.push(Case {
                roughness,
                theta,
                corner: Vec3::new(-1.5, -1.0, -0.5),
                e1: Vec3::new(0.0, 2.0, 0.0),
                e2: Vec3::new(0.0, 0.0, 2.0),
                triangle: false,
            });
        }
    }
    out
}

fn corners(c: &Case) -> [Vec3; 4] {
    if c.triangle {
        [c.corner, c.corner + c.e1, c.corner + c.e2, c.corner]
    } else {
        [
            c.corner,
            c.corner + c.e1,
            c.corner + c.e1 + c.e2,
            c.corner + c.e2,
        ]
    }
}

/// The tolerance's floors as fractions of the lobe's albedo F0·n + (1 − F0)·s: without
/// Fresnel and with Schlick's.
const OF_LOBE: [f64; 2] = [0.015, 0.12];

/// Within 6% of the lobe's integral, or `OF_LOBE` of its albedo where the polygon sees a
/// part of it: the fit's error. Measured (committed 10×10 table, 600² midpoint grid):
/// without Fresnel, in the lobe 0.2–4.3% (the largest at roughness 0.2, θ 1), over its
/// edge or tail up to 21% of a small value but ≤ 1.3% of the albedo (≤ 2.9% where the
/// relative error is under 6%); with Schlick's F0 = 0.04 (the moment s carries almost all
/// of it, with the Fresnel-1 lobe's shape: the paper's approximation) up to 11.5% of the
/// albedo (at grazing view, θ 1 rad, on the polygon crossing the horizon).
#[test]
fn closed_form_matches_a_numeric_integral() {
    let mut worst = [0.0f64; 2];
    for c in cases() {
        let wo = Vec3::new(c.theta.sin(), 0.0, c.theta.cos());
        let [x, y] = glossy_integral(Vec3::Z, wo, c.roughness, &corners(&c));
        let cell = table().lookup(c.roughness, wo.z);
        for (f0, fresnel, got) in [
            (1.0f32, false, x as f64),
            (0.04, true, (0.04 * x + 0.96 * y) as f64),
        ] {
            let m = Material {
                diffuse: Vec3::ZERO,
                specular: Vec3::splat(f0),
                roughness: c.roughness,
                fresnel,
                ..Material::default()
            };
            let want = numeric(&m, wo, c.corner, c.e1, c.e2, c.triangle);
            let err = (got - want).abs();
            let lobe = f0 as f64 * cell.norm as f64 + (1.0 - f0 as f64) * cell.fresnel as f64;
            worst[fresnel as usize] = worst[fresnel as usize].max(err / lobe);
            assert!(
                err <= (0.06 * want).max(OF_LOBE[fresnel as usize] * lobe),
                "r {} θ {} corner {} tri {} F0 {f0}: LTC {got} numeric {want}",
                c.roughness,
                c.theta,
                c.corner,
                c.triangle
            );
        }
    }
    println!("worst error over the lobe's albedo: {worst:?}");
}

/// The test can fail: M⁻¹ = I (a cosine) times the albedo misses the glossy integral over
/// a square in the mirror direction by far more than the tolerance.
#[test]
fn a_cosine_in_place_of_the_fit_fails() {
    let theta = 0.5f32;
    let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
    let corner = Vec3::new(-2.0 * theta.tan() - 0.5, -0.5, 2.0);
    let quad = [
        corner,
        corner + Vec3::X,
        corner + Vec3::X + Vec3::Y,
        corner + Vec3::Y,
    ];
    let got = form_factor(&quad) as f64;
    let m = Material {
        diffuse: Vec3::ZERO,
        specular: Vec3::ONE,
        roughness: 0.3,
        ..Material::default()
    };
    let want = numeric(&m, wo, corner, Vec3::X, Vec3::Y, false);
    assert!((got - want).abs() > 0.18 * want, "{got} {want}");
}

/// Lambert's form factor of a unit square at height 1 centred above the point: four times
/// its quarter (x, y ∈ [0, ½]), F = (1/2π)(a/√(1+a²)·atan(b/√(1+a²)) + b/√(1+b²)·
/// atan(a/√(1+b²))) with a = b = ½; a polygon below the horizon gives 0.
#[test]
fn form_factor_of_a_square_and_of_one_below() {
    let q = |z: f32| {
        [
            Vec3::new(-0.5, -0.5, z),
            Vec3::new(0.5, -0.5, z),
            Vec3::new(0.5, 0.5, z),
            Vec3::new(-0.5, 0.5, z),
        ]
    };
    let a = 0.5f64;
    let s = (1.0 + a * a).sqrt();
    let quarter = 2.0 * a / s * (a / s).atan() / std::f64::consts::TAU;
    let got = form_factor(&q(1.0)) as f64;
    assert!(
        (got - 4.0 * quarter).abs() < 1e-6,
        "{got} {}",
        4.0 * quarter
    );
    assert_eq!(form_factor(&q(-1.0)), 0.0);
    // Orientation does not matter.
    let mut r = q(1.0);
    r.reverse();
    assert!((form_factor(&r) as f64 - 4.0 * quarter).abs() < 1e-6);
}

/// The tables are read with m00 ≥ 0 everywhere (interpolated entry by entry), and share
/// one grid size (the texture stacks them).
#[test]
fn cells_agree_in_sign() {
    for dist in [Distribution::Ggx, Distribution::Beckmann] {
        let t = table_of(dist);
        assert_eq!(t.cells.len(), t.size * t.size);
        assert_eq!(t.size, table().size);
        assert!(t.cells.iter().all(|c| c.minv[0] >= 0.0));
    }
}

/// Mitsuba's Beckmann lobe (separable Smith masking, Fresnel 1) f of wi, seen from `wo`.
fn beckmann_lobe(wo: Vec3, alpha: f32) -> impl Fn(Vec3) -> f32 {
    use crate::bsdf::microfacet::{d, g_separable};
    move |wi: Vec3| {
        if wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        let b = Distribution::Beckmann;
        d(h, alpha, b) * g_separable(wo, wi, alpha, b) / (4.0 * wo.z * wi.z)
    }
}

/// The Beckmann table against the numeric integral of Mitsuba's Beckmann lobe over the
/// squares and triangles of [`cases`] (no Fresnel), and against the GGX table at the same
/// α (the stand-in before it). LTC's clamped cosine has heavier tails than Beckmann's
/// Gaussian-like peak, so the fit is looser than GGX's (a polygon holding the whole narrow
/// lobe gets 0.82–0.95 of it at roughness 0.15–0.3: `scripts/data/ltc_fit.py`'s L³ fit,
/// measured with a numpy copy of this check), and its tail is heavier (the vertical square
/// across the horizon at roughness 0.3, θ 0.5: 0.058 for 0.012, 4.7% of the albedo; the
/// GGX table 0.062): every case within 20% of its value or 5% of the albedo; no case worse
/// than the GGX table's by more than 2% of the albedo, and the mean error over the albedo
/// at most 0.9 of the GGX table's (both printed).
#[test]
fn beckmann_table_matches_a_numeric_integral() {
    let (mut sum, mut ggx_sum, mut worst) = (0.0f64, 0.0f64, 0.0f64);
    let all = cases();
    for c in &all {
        let wo = Vec3::new(c.theta.sin(), 0.0, c.theta.cos());
        let alpha = c.roughness * c.roughness;
        let poly = corners(c);
        let got = glossy_integral_of(Distribution::Beckmann, Vec3::Z, wo, c.roughness, &poly)[0];
        let ggx = glossy_integral(Vec3::Z, wo, c.roughness, &poly)[0] as f64;
        let want = numeric_lobe(&beckmann_lobe(wo, alpha), c.corner, c.e1, c.e2, c.triangle);
        let lobe = table_of(Distribution::Beckmann)
            .lookup(c.roughness, wo.z)
            .norm as f64;
        let (err, ggx_err) = ((got as f64 - want).abs(), (ggx - want).abs());
        sum += err / lobe;
        ggx_sum += ggx_err / lobe;
        worst = worst.max(err / want.max(1e-9));
        let at = format!(
            "r {} θ {} corner {} tri {}: LTC {got} numeric {want} (GGX table {ggx})",
            c.roughness, c.theta, c.corner, c.triangle
        );
        assert!(err <= (0.2 * want).max(0.05 * lobe), "{at}");
        assert!(err <= ggx_err + 0.02 * lobe, "{at}");
    }
    let n = all.len() as f64;
    println!(
        "mean error over the albedo: Beckmann table {:.4}, GGX table {:.4}; worst relative {worst:.3}",
        sum / n,
        ggx_sum / n
    );
    assert!(sum <= 0.9 * ggx_sum, "{sum} {ggx_sum}");
}

/// The texture's texels are the table as `ltc.wgsl` reads them: the header texel, and
/// cell (i, j) at row i + 1, texels 2j and 2j + 1.
#[test]
fn texels_hold_the_cells_where_the_shader_reads_them() {
    let t = table();
    let texels = t.texels();
    let w = CELL_TEXELS as usize * t.size;
    assert_eq!(texels.len(), w * (t.size + 1));
    // The texture: GGX's rows, then Beckmann's from row size + 1 (`ltc_lookup`'s `base`).
    let all = all_texels();
    assert_eq!(all[..texels.len()], texels[..]);
    assert_eq!(
        all[texels.len()..],
        table_of(Distribution::Beckmann).texels()[..]
    );
    assert_eq!(texels[0], [t.r0, t.r1, t.theta_max, t.size as f32]);
    for (i, j) in [(0, 0), (1, 2), (t.size - 1, t.size - 1), (t.size / 2, 3)] {
        let c = t.cells[i * t.size + j];
        let row = (i + 1) * w;
        assert_eq!(texels[row + 2 * j], c.minv, "{i} {j}");
        assert_eq!(
            texels[row + 2 * j + 1],
            [c.norm, c.fresnel, 0.0, 0.0],
            "{i} {j}"
        );
    }
}

/// ∫ f·cos θi dω of `m` over the cone of directions to a sphere at `centre` (relative to
/// the origin; normal z, view `wo`) of `radius`, by the midpoint rule on a 400² grid of
/// (θ from the cone's axis, φ).
fn numeric_sphere(m: &Material, wo: Vec3, centre: Vec3, radius: f32) -> f64 {
    let n = 400;
    let axis = centre.normalize();
    let cone = (radius / centre.length()).asin();
    let u = Vec3::X.cross(axis).normalize();
    let v = axis.cross(u);
    let mut sum = 0.0f64;
    for i in 0..n {
        let t = (i as f32 + 0.5) / n as f32 * cone;
        for j in 0..n {
            let phi = (j as f32 + 0.5) / n as f32 * std::f32::consts::TAU;
            let wi = axis * t.cos() + (u * phi.cos() + v * phi.sin()) * t.sin();
            if wi.z <= 0.0 {
                continue;
            }
            sum += (m.eval(wo, wi).x * wi.z * t.sin()) as f64;
        }
    }
    sum * (cone * std::f32::consts::TAU) as f64 / (n * n) as f64
}

/// A sphere's glossy light as the polygon of its disc (`sphere_polygon`, the direct pass's
/// round emitters) against the numeric integral over its cone: spheres of angular radius
/// 0.02–0.3 rad in the mirror direction and beside it, roughness 0.1–0.5 (veach-mis's
/// plates: α 0.01–0.25), views 0.3–1.0 rad. Within 8% of the value or 2% of the lobe's
/// albedo (the fit's error, as `closed_form_matches_a_numeric_integral`, and the polygon's
/// corners).
#[test]
fn sphere_polygon_matches_a_numeric_integral() {
    let mut worst = 0.0f64;
    for roughness in [0.1f32, 0.22, 0.3, 0.5] {
        for theta in [0.3f32, 0.7, 1.0] {
            let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
            let mirror = Vec3::new(-wo.x, 0.0, wo.z);
            for (angle, off) in [(0.02f32, 0.0f32), (0.08, 0.0), (0.3, 0.0), (0.08, 0.1)] {
                let dir = (mirror + Vec3::Y * off).normalize();
                let centre = dir * 5.0;
                let radius = 5.0 * angle.sin();
                let m = Material {
                    diffuse: Vec3::ZERO,
                    specular: Vec3::ONE,
                    roughness,
                    fresnel: false,
                    ..Material::default()
                };
                let want = numeric_sphere(&m, wo, centre, radius);
                let got = glossy_integral(Vec3::Z, wo, roughness, &sphere_polygon(centre, radius))
                    [0] as f64;
                let lobe = table().lookup(roughness, wo.z).norm as f64;
                let err = (got - want).abs();
                worst = worst.max(err / want.max(1e-9));
                assert!(
                    err <= (0.08 * want).max(0.02 * lobe),
                    "r {roughness} θ {theta} angle {angle} off {off}: LTC {got} numeric {want}"
                );
            }
        }
    }
    println!("worst relative error: {worst}");
    // From inside the sphere: nothing.
    assert!(sphere_polygon(Vec3::new(0.0, 0.0, 0.5), 1.0).is_empty());
}
