//! The light-traced part of the reference renderer, checked in absolute terms.

use gi_core::{render, scene::builtin, Image, Scene, Silent};
use glam::Vec3;
use std::collections::HashMap;

/// A diffuse floor (y = 0, albedo ρ) beside a large vertical mirror (plane x = 0,
/// reflectance R, no Fresnel) and a point light of intensity I at (a, h, 0).
/// The mirror acts as a second point light of intensity R·I at (−a, h, 0), so the floor's
/// radiance from mirror paths is L = ρ/π · R·I·h / d³, d the distance to the image light.
#[test]
fn planar_mirror_caustic_matches_image_light() {
    let (rho, refl, intensity, a, h) = (0.5f32, 0.9f32, 2.0f32, 1.0f32, 1.0f32);
    let json = format!(
        r#"{{
        "camera": {{"position": [2.0, 3.5, 0.0], "look_at": [2.0, 0.0, 0.0], "up": [0, 0, -1], "fov": 50,
                   "width": 48, "height": 48}},
        "lights": [{{"type": "point", "position": [{a}, {h}, 0], "intensity": [{intensity}, {intensity}, {intensity}]}}],
        "materials": {{"floor": {{"diffuse": [{rho}, {rho}, {rho}]}},
                      "mirror": {{"diffuse": [0, 0, 0], "specular": [{refl}, {refl}, {refl}]}}}},
        "objects": [
            {{"shape": {{"type": "quad", "size": [12, 12]}}, "material": "floor"}},
            {{"shape": {{"type": "quad", "size": [8, 12]}}, "transform": {{"rotate": [0, 0, -90], "translate": [0, 4, 0]}},
             "material": "mirror"}}
        ]}}"#
    );
    let scene = Scene::from_json(&json, "mirror-test", &HashMap::new()).unwrap();
    // max_depth 2: light → mirror → floor → eye only (no floor → mirror → floor chains).
    let settings = gi_core::options!(Path, spp: 1, max_depth: 2, light_paths: 6_000_000, seed: 3);
    let out = render(&scene, &settings, &Silent).unwrap();
    let image_light = Vec3::new(-a, h, 0.0);
    let (mut sum_mc, mut sum_exact, mut n) = (0.0f64, 0.0f64, 0);
    for (i, p) in out.position.pixels.iter().enumerate() {
        // Floor pixels away from the mirror's foot (where the camera sees the mirror itself).
        if p.y.abs() > 1e-3 || p.x < 0.3 {
            continue;
        }
        let d = (*p - image_light).length();
        let exact = rho / std::f32::consts::PI * refl * intensity * h / d.powi(3);
        sum_mc += out.caustics.pixels[i].x as f64;
        sum_exact += exact as f64;
        n += 1;
    }
    assert!(n > 1000, "the camera must see the floor ({n} pixels)");
    let rel = (sum_mc - sum_exact) / sum_exact;
    // 2% (the issue's bound); the Monte Carlo error of the region mean at 6M light paths is
    // about 0.3%.
    assert!(
        rel.abs() < 0.02,
        "mirror caustic {sum_mc:.4} vs analytic {sum_exact:.4} ({:+.2}%)",
        rel * 100.0
    );
}

fn box_blur(img: &Image, r: i32) -> Vec<f32> {
    let (w, h) = (img.width as i32, img.height as i32);
    let mut out = vec![0.0; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let (mut s, mut c) = (0.0, 0.0);
            for dy in -r..=r {
                for dx in -r..=r {
                    let (xx, yy) = (x + dx, y + dy);
                    if xx >= 0 && yy >= 0 && xx < w && yy < h {
                        s += img.pixels[(yy * w + xx) as usize].element_sum() / 3.0;
                        c += 1.0;
                    }
                }
            }
            out[(y * w + x) as usize] = s / c;
        }
    }
    out
}

/// The mirror ring focuses light into a cardioid on the floor inside it: the brightest part
/// of the light-traced image there is more than twice the median floor radiance around it
/// (the wall shadows most of the inner floor from direct light).
#[test]
fn caustic_ring_shows_the_cardioid() {
    let scene = builtin::load("caustic-ring").unwrap();
    let settings = gi_core::options!(Path, spp: 16, width: 96, height: 96, seed: 1);
    let out = render(&scene, &settings, &Silent).unwrap();
    let caustic = box_blur(&out.caustics, 1);
    let total = box_blur(&out.radiance, 1);
    let mut inside: Vec<(f32, f32)> = out
        .position
        .pixels
        .iter()
        .enumerate()
        .filter(|(_, p)| p.y.abs() < 1e-3 && (p.x * p.x + p.z * p.z).sqrt() < 0.95)
        .map(|(i, _)| (caustic[i], total[i]))
        .collect();
    assert!(
        inside.len() > 1000,
        "camera must see the floor inside the ring"
    );
    inside.sort_by(|a, b| a.0.total_cmp(&b.0));
    let peak = inside[inside.len() * 99 / 100].0;
    let mut totals: Vec<f32> = inside.iter().map(|v| v.1).collect();
    totals.sort_by(f32::total_cmp);
    let median = totals[totals.len() / 2];
    assert!(
        peak > 2.0 * median,
        "caustic peak {peak} vs median floor radiance {median}"
    );
    // And the caustic is a curve, not a uniform glow: most of the floor gets far less.
    let caustic_median = inside[inside.len() / 2].0;
    assert!(
        peak > 5.0 * caustic_median,
        "peak {peak} vs median caustic {caustic_median}"
    );
}
