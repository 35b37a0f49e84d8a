//! Cost of the ISPM photon volumes by bounding shape (icosahedron, quad, auto) and volume
//! size, as a markdown table.
//!
//! `cargo run -p gi-core --profile test --example volume_shape_bench [-- --runs N] [--px R]…`
//!
//! Built-in `cornell` at 640×480, one direct sample per pixel. Rows: `kernel_scale` chosen
//! so that the median projected volume radius (pixels, as `VolumeShape::Auto` computes it)
//! is about 2, 4, … 64 px (the largest are capped by the maximum radius), with fewer photons
//! for the larger volumes to keep the frame times bounded; then the defaults (200k photons,
//! `kernel_scale` 1). Per row the three shapes are rendered in turn, N times after one
//! warm-up frame each; the "photon volumes" stage (eye G-buffer + photon upload + volume
//! pass; only the pass differs between shapes) is reported as the median, with the ratios
//! to the icosahedron measured in the same interleaved runs.

mod common;

use gi_core::estimate::volume_shape::projected_radius;
use gi_core::frame::options::VolumeShape;
use gi_core::photon::radius::VolumeRadius;
use gi_core::photon::{continue_paths, PhotonTraceSettings};
use gi_core::trace::SceneBvh;
use gi_core::Silent;
use gi_core::{render, scene::builtin, Scene};

const SHAPES: [VolumeShape; 3] = [
    VolumeShape::Icosahedron,
    VolumeShape::Quad,
    VolumeShape::Auto,
];

/// Projected radii (px) of the stored photons' volumes at `kernel_scale`, sorted.
fn projected_radii(scene: &Scene, s: &gi_core::RenderOptions) -> Result<Vec<f32>, gi_core::Error> {
    let bm = gi_core::frame::bounce_map(scene, s)?;
    let gi_core::MethodOptions::Ispm(o) = &s.method else {
        unreachable!("ispm options")
    };
    let bvh = SceneBvh::build(scene);
    let pts = PhotonTraceSettings {
        max_bounces: o.max_depth - 1,
        store_direct: false,
        differentials: None,
    };
    let photons = continue_paths(scene, &bvh, &bm.rays, &pts, s.common.seed).photons;
    let radius = VolumeRadius::of_scene(scene, o.photons, o.kernel_scale);
    let camera = scene.camera.with_size(640, 480);
    let mut px: Vec<f32> = photons
        .iter()
        .map(|p| projected_radius(&camera, o.subsample, p.position(), radius.of(p)))
        .collect();
    px.sort_by(f32::total_cmp);
    Ok(px)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::get();
    let runs = args.runs(3)?;
    common::print_adapter()?;
    let scene = builtin::load("cornell")?;
    let base = gi_core::options!(Ispm, spp: 1, width: 640, height: 480);
    // (target median radius in px, photons); `None` = the defaults.
    let rows: [(Option<f32>, u64); 7] = [
        (Some(2.0), 200_000),
        (Some(4.0), 200_000),
        (Some(8.0), 100_000),
        (Some(16.0), 50_000),
        (Some(32.0), 20_000),
        (Some(64.0), 10_000),
        (None, 200_000),
    ];
    println!(
        "| photons | kernel_scale | median radius (px) | stored | quads in auto | \
         icosahedron (ms) | quad (ms) | auto (ms) | quad / ico | auto / ico |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    // `--px R` (repeatable) keeps only the rows of those target radii.
    let only: Vec<f32> = args
        .values("--px")
        .into_iter()
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    for (target, photons) in rows {
        if !only.is_empty() && !target.is_some_and(|t| only.contains(&t)) {
            continue;
        }
        let unit = base.clone().with("photons", photons);
        let kernel_scale = match target {
            Some(t) => {
                let px = projected_radii(&scene, &unit)?;
                (t / px[px.len() / 2]).clamp(1e-3, 1e3)
            }
            None => 1.0,
        };
        let settings = unit.with("kernel_scale", kernel_scale);
        let px = projected_radii(&scene, &settings)?;
        let med_px = px[px.len() / 2];
        let with = |shape| {
            settings
                .clone()
                .with("volume_shape", shape)
                .with("estimator", gi_core::estimate::Estimator::Volumes)
        };
        for shape in SHAPES {
            render(&scene, &with(shape), &Silent)?;
        }
        // Per shape: stage times; per run the ratios to the icosahedron.
        let mut times: Vec<Vec<f64>> = vec![Vec::new(); SHAPES.len()];
        let mut ratios: Vec<Vec<f64>> = vec![Vec::new(); SHAPES.len()];
        let (mut stored, mut quads) = (0, 0);
        for _ in 0..runs {
            let mut this = [0.0; SHAPES.len()];
            for (i, shape) in SHAPES.into_iter().enumerate() {
                let out = render(&scene, &with(shape), &Silent)?;
                this[i] = out
                    .stats
                    .stages
                    .iter()
                    .filter(|(n, _)| n == "photon volumes")
                    .map(|(_, t)| t * 1e3)
                    .sum();
                times[i].push(this[i]);
                ratios[i].push(this[i] / this[0]);
                if shape == VolumeShape::Auto {
                    (stored, quads) = (out.stats.photons_stored, out.stats.volume_quads);
                }
            }
        }
        let t: Vec<f64> = times.iter_mut().map(|v| median(v)).collect();
        let r: Vec<f64> = ratios.iter_mut().map(|v| median(v)).collect();
        let label = if target.is_some() { "" } else { " (defaults)" };
        println!(
            "| {photons}{label} | {kernel_scale:.3} | {med_px:.1} | {stored} | {:.0}% | {:.1} | {:.1} | {:.1} | {:.2} | {:.2} |",
            100.0 * quads as f64 / stored.max(1) as f64,
            t[0],
            t[1],
            t[2],
            r[1],
            r[2]
        );
    }
    Ok(())
}
