//! Method `bidir` (Tokuyoshi & Ogaki 2012) on lavapipe: reflective shadow maps, VPLs with
//! cube shadow maps, one-bounce VPL lighting of the G-buffer.
//!
//! - furnace: the one-bounce light (bidir − direct) against the analytic value;
//! - Cornell box against the path tracer limited to the same depth (direct + one bounce);
//! - settings are validated.

mod common;

use gi_core::render::Silent;
use gi_core::{render, scene::builtin, Method, RenderOutput, Scene, Settings};
use glam::DVec3;
use std::f64::consts::PI;

fn load(name: &str) -> Scene {
    builtin::load(name).expect("built-in scene")
}

fn mean(img: &gi_core::image::Image) -> DVec3 {
    img.pixels.iter().map(|p| p.as_dvec3()).sum::<DVec3>() / img.pixels.len() as f64
}

fn run(scene: &Scene, s: &Settings) -> RenderOutput {
    render(scene, s, &Silent).expect("render")
}

fn bidir_settings(size: u32) -> Settings {
    Settings {
        method: Method::Bidir,
        spp: 1,
        width: Some(size),
        height: Some(size),
        seed: 3,
        ..Default::default()
    }
}

/// Means of the `block`×`block` pixel blocks.
fn block_means(img: &gi_core::image::Image, block: u32) -> Vec<DVec3> {
    let (bw, bh) = (img.width / block, img.height / block);
    let mut out = vec![DVec3::ZERO; (bw * bh) as usize];
    for y in 0..bh * block {
        for x in 0..bw * block {
            out[((y / block) * bw + x / block) as usize] +=
                img.get(x, y).as_dvec3() / (block * block) as f64;
        }
    }
    out
}

/// Furnace (closed sphere R = 1, ρ = 0.5, point light I = 1 at the centre): direct radiance
/// L0 = ρI/(πR²); one bounce off a uniformly lit enclosure adds ρ·L0 = 0.25/π everywhere.
/// Between two points of a sphere cos θ1 = cos θ3 = d/2R, so the VPL term is the constant
/// 1/(4R²) (no spikes): with 64 VPLs the estimate is exact up to the RSM's covered flux
/// (all of 4π) and the shadow-map PCF at the VPL's own surface. Tolerance 3%, the issue's.
#[test]
fn furnace_one_bounce_matches_analytic() {
    let scene = load("furnace");
    let s = bidir_settings(32);
    let bidir = run(&scene, &s);
    let direct = run(
        &scene,
        &Settings {
            method: Method::Direct,
            ..s.clone()
        },
    );
    let indirect = mean(&bidir.radiance) - mean(&direct.radiance);
    let expected = 0.25 / PI;
    eprintln!(
        "furnace one-bounce {indirect:?} expected {expected:.5}; stats {:?}",
        bidir.stats
    );
    assert_eq!(bidir.stats.vpls, 64);
    for c in indirect.to_array() {
        assert!(
            (c / expected - 1.0).abs() < 0.03,
            "{indirect:?} vs {expected}"
        );
    }
    let aov = bidir
        .aovs
        .iter()
        .find(|(n, _)| n == "indirect")
        .expect("indirect AOV");
    let m = mean(&aov.1);
    assert!((m - indirect).abs().max_element() < 1e-4, "{m:?}");
}

/// Cornell box, 48×48: `bidir` (direct light + VPL one-bounce) against the path tracer with
/// `max_depth` 2 (direct + one bounce), 1024 spp. Criteria (those of `ispm`'s test):
/// - the image mean per channel within 3%;
/// - mean relative error per channel over the 36 blocks of 8×8 pixels ≤ 7%: the VPL-only
///   estimate is all but exact on open surfaces (blocks within 1–4%) and spikes where a VPL
///   lies close to a receiver (the 1/d² of the corner under the short box: measured +78% in
///   its darkest block, reference 0.019; Figure 4 (a) of the paper, what §4.2's MIS is for);
///   measured 4.4–5.7%; the reference's own block noise is ~1% at 1024 spp.
#[test]
fn cornell_matches_path_tracer_one_bounce() {
    let scene = load("cornell");
    let size = 48;
    let bidir = run(
        &scene,
        &Settings {
            vpls_per_light: 256,
            spp: 4,
            ..bidir_settings(size)
        },
    );
    let path = run(
        &scene,
        &Settings {
            method: Method::Path,
            spp: 1024,
            max_depth: 2,
            ..bidir_settings(size)
        },
    );
    let (a, b) = (mean(&bidir.radiance), mean(&path.radiance));
    let rel = (a / b - DVec3::ONE).abs();
    let (ba, bb) = (
        block_means(&bidir.radiance, 8),
        block_means(&path.radiance, 8),
    );
    let block_err = ba
        .iter()
        .zip(&bb)
        .map(|(x, y)| (*x - *y).abs() / y.max(DVec3::splat(1e-3)))
        .sum::<DVec3>()
        / ba.len() as f64;
    eprintln!(
        "cornell bidir {a:?} path(depth 2) {b:?} rel {rel:?}; 8x8-block error {block_err:?}; {:?}",
        bidir.stats
    );
    if rel.max_element() >= 0.03 || block_err.max_element() >= 0.07 {
        let dir = common::output_dir();
        for (name, img) in [
            ("bidir-cornell.pfm", &bidir.radiance),
            ("bidir-cornell-path.pfm", &path.radiance),
        ] {
            let _ = common::write_pfm(&dir.join(name), img);
        }
    }
    assert!(rel.max_element() < 0.03, "image mean {a:?} vs {b:?}");
    assert!(block_err.max_element() < 0.07, "block error {block_err:?}");
}

#[test]
fn bad_settings_are_setting_errors() {
    let scene = load("cornell");
    for s in [
        Settings {
            vpls_per_light: 0,
            ..bidir_settings(16)
        },
        Settings {
            vpl_shadow_map_size: 8,
            ..bidir_settings(16)
        },
        Settings {
            rsm_size: 0,
            ..bidir_settings(16)
        },
    ] {
        let e = render(&scene, &s, &Silent).err();
        assert!(matches!(e, Some(gi_core::Error::Setting { .. })), "{e:?}");
    }
    assert_eq!("bidir".parse::<Method>().ok(), Some(Method::Bidir));
}
