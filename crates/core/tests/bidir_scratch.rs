use gi_core::render::{BidirStrategy, Silent};
use gi_core::{render, scene::builtin, Method, Settings};
use glam::{DVec3, Vec3};
#[test]
fn scratch() {
    let mut scene = builtin::load("cornell").unwrap();
    let rough: f32 = std::env::var("ROUGH")
        .map(|v| v.parse().unwrap())
        .unwrap_or(0.3);
    for m in scene.materials.iter_mut() {
        m.specular = Vec3::splat(0.3);
        m.roughness = rough;
        m.diffuse *= 0.6;
    }
    let base = Settings {
        method: Method::Bidir,
        spp: 4,
        width: Some(48),
        height: Some(48),
        seed: 3,
        max_depth: 2,
        bundles: 32,
        ..Default::default()
    };
    let path = render(
        &scene,
        &Settings {
            method: Method::Path,
            spp: 1024,
            ..base.clone()
        },
        &Silent,
    )
    .unwrap();
    let mean = |i: &gi_core::image::Image| {
        i.pixels.iter().map(|p| p.as_dvec3()).sum::<DVec3>() / i.pixels.len() as f64
    };
    let b = mean(&path.radiance);
    let d1 = mean(
        &render(
            &scene,
            &Settings {
                method: Method::Path,
                spp: 1024,
                max_depth: 1,
                ..base.clone()
            },
            &Silent,
        )
        .unwrap()
        .radiance,
    );
    let g1 = mean(
        &render(
            &scene,
            &Settings {
                method: Method::Direct,
                ..base.clone()
            },
            &Silent,
        )
        .unwrap()
        .radiance,
    );
    eprintln!(
        "direct: path {d1:.4?} gpu {g1:.4?}; path indirect {:.4?}",
        b - d1
    );
    for (s, c) in [(BidirStrategy::Mis, false), (BidirStrategy::Mis, true)] {
        let o = render(
            &scene,
            &Settings {
                bidir_strategy: s,
                roughness_clamping: c,
                ..base.clone()
            },
            &Silent,
        )
        .unwrap();
        let a = mean(&o.radiance);
        let mut ratios: Vec<f32> = o
            .radiance
            .pixels
            .iter()
            .zip(&path.radiance.pixels)
            .map(|(x, y)| (x.element_sum() / y.element_sum().max(1e-3)))
            .collect();
        ratios.sort_by(|x, y| y.partial_cmp(x).unwrap());
        eprintln!(
            "{s:?} clamp {c} overflow {}: mean {a:.4?} vs {b:.4?} rel {:.4?}; top ratios {:?}",
            o.stats.bundle_overflow,
            a / b - DVec3::ONE,
            &ratios[..4]
        );
        write_pfm(&format!("/tmp/bidir/g-{s:?}-{c}.pfm"), &o.radiance);
    }
    write_pfm("/tmp/bidir/g-path.pfm", &path.radiance);
}
fn write_pfm(p: &str, img: &gi_core::image::Image) {
    let mut out = format!("PF\n{} {}\n-1\n", img.width, img.height).into_bytes();
    for y in (0..img.height).rev() {
        for x in 0..img.width {
            for c in img.get(x, y).to_array() {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    std::fs::write(p, out).unwrap();
}
