//! Time of the indirect estimators (the `estimator` option) over the same photons, as a
//! markdown table: photon count × kernel scale × image size, one `Renderer` per row and
//! estimator. After the frame that traces the photons, the camera moves by a hair every
//! frame, so every frame splats the same photons again (the trace is reused); the time is the
//! estimator's GPU passes from timestamp queries (volumes: "photon volumes"; tiled: "tiled
//! binning" + "tiled shading"; the upsampling, the same for all, is left out), median of N.
//!
//! `cargo run -p gi-core --profile test --example estimator_bench [-- --runs N --quick]`
//!
//! Cornell box, 640×480 and 1280×720 (subsample 2), 10k / 50k / 200k / 1M photons at
//! kernel scale 1, and kernel scales 0.5 and 2 at 200k and 640×480.

mod common;

use common::median;
use gi_core::estimate::Estimator;
use gi_core::frame::{FrameDesc, Renderer};
use gi_core::scene::{builtin, SceneUpdate};
use gi_core::Silent;
use gi_core::{RenderOutput, Scene};

const ESTIMATORS: [Estimator; 4] = [
    Estimator::Volumes,
    Estimator::Tiled,
    Estimator::Cluster,
    Estimator::Directional,
];

fn stage(out: &RenderOutput, names: &[&str]) -> f64 {
    out.stats
        .stages
        .iter()
        .filter(|(n, _)| names.contains(&n.as_str()))
        .map(|(_, s)| s)
        .sum()
}

fn estimate_seconds(out: &RenderOutput) -> f64 {
    stage(
        out,
        &[
            "photon volumes",
            "tiled binning",
            "tiled shading",
            "cluster hierarchy",
            "cluster binning",
            "cluster shading",
            "directional shading",
        ],
    )
}

struct Measured {
    estimate: f64,
    /// Tiled: binning and shading separately.
    binning: f64,
    shading: f64,
    /// Cluster: share of list entries that are trivial accepts.
    accepts: f64,
    photons: u64,
    memory: u64,
}

fn measure(
    scene: &Scene,
    settings: &gi_core::RenderOptions,
    runs: usize,
) -> Result<Measured, Box<dyn std::error::Error>> {
    let mut r = Renderer::new(scene, settings)?;
    let first = r.render(&FrameDesc::default(), &Silent)?;
    let mut camera = r.scene().camera_desc();
    let (mut est, mut bin, mut shade) = (Vec::new(), Vec::new(), Vec::new());
    let mut accepts = Vec::new();
    for i in 0..runs {
        camera.fov += if i % 2 == 0 { 1e-3 } else { -1e-3 };
        r.update(&SceneUpdate::Camera(camera.clone()))?;
        let out = r.render(&FrameDesc::default(), &Silent)?;
        est.push(estimate_seconds(&out));
        bin.push(stage(
            &out,
            &["tiled binning", "cluster hierarchy", "cluster binning"],
        ));
        if std::env::var("GI_BENCH_STAGES").is_ok() {
            eprintln!("{:?}", out.stats.stages);
        }
        shade.push(stage(
            &out,
            &["tiled shading", "cluster shading", "directional shading"],
        ));
        let s = &out.stats;
        accepts.push(s.trivial_accepts as f64 / s.list_entries.max(1) as f64);
    }
    Ok(Measured {
        estimate: median(est),
        binning: median(bin),
        shading: median(shade),
        accepts: median(accepts),
        photons: first.stats.photons_stored,
        memory: first.stats.estimator_memory.iter().map(|(_, b)| b).sum(),
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::get();
    let runs = args.runs(3)?;
    let quick = args.quick();
    common::print_adapter()?;
    let scene = builtin::load("cornell")?;
    let sizes: &[(u32, u32)] = if quick {
        &[(640, 480)]
    } else {
        &[(640, 480), (1280, 720)]
    };
    let budgets: &[u64] = if quick {
        &[20_000, 200_000]
    } else {
        &[10_000, 50_000, 200_000, 1_000_000]
    };
    // Kernel radius swept at the default photon count and the smaller size.
    let scales_at = |photons: u64, w: u32| -> &'static [f32] {
        if quick || photons != 200_000 || w > 640 {
            &[1.0]
        } else {
            &[0.5, 1.0, 2.0]
        }
    };
    println!(
        "| size | photons | kernel scale | stored | volumes (ms) | tiled (ms) | cluster (ms) \
         | directional (ms) | tiled / volumes | cluster / volumes | directional / volumes \
         | fastest exact | tiled binning + shading (ms) | cluster binning + shading (ms) \
         | cluster trivial accepts | memory volumes / tiled / cluster / directional (MiB) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    for &(w, h) in sizes {
        for &photons in budgets {
            for &kernel_scale in scales_at(photons, w) {
                let mut m = Vec::new();
                for estimator in ESTIMATORS {
                    let settings = gi_core::options!(Ispm, width: w, height: h, spp: 16, photons: photons, kernel_scale: kernel_scale, estimator: estimator);
                    m.push(measure(&scene, &settings, runs)?);
                }
                let (v, t, c, d) = (&m[0], &m[1], &m[2], &m[3]);
                // The fastest of those that give the volumes' image (directional does not).
                let fastest = ESTIMATORS[..3]
                    .iter()
                    .zip(&m)
                    .min_by(|a, b| a.1.estimate.total_cmp(&b.1.estimate))
                    .map(|(e, _)| e.name())
                    .unwrap_or("");
                println!(
                    "| {w}×{h} | {photons} | {kernel_scale} | {} | {:.1} | {:.1} | {:.1} | {:.1} \
                     | {:.2} | {:.2} | {:.2} | {fastest} | {:.1} + {:.1} | {:.1} + {:.1} \
                     | {:.0}% | {:.1} / {:.1} / {:.1} / {:.1} |",
                    v.photons,
                    v.estimate * 1e3,
                    t.estimate * 1e3,
                    c.estimate * 1e3,
                    d.estimate * 1e3,
                    t.estimate / v.estimate,
                    c.estimate / v.estimate,
                    d.estimate / v.estimate,
                    t.binning * 1e3,
                    t.shading * 1e3,
                    c.binning * 1e3,
                    c.shading * 1e3,
                    100.0 * c.accepts,
                    mib(v.memory),
                    mib(t.memory),
                    mib(c.memory),
                    mib(d.memory),
                );
            }
        }
    }
    Ok(())
}
