//! How to use the crate for real-time frames: one `Renderer` kept across frames, the scene
//! changed between them by `SceneUpdate`s, each frame re-doing only what the change needs.
//!
//! `cargo run -p gi-core --example renderer_frames` (method `ispm`: needs a GPU adapter or
//! Mesa lavapipe).

use gi_core::frame::{FrameDesc, Images, Renderer};
use gi_core::scene::desc::LightDesc;
use gi_core::scene::{builtin, SceneUpdate};
use gi_core::{options, Silent};

fn main() -> gi_core::Result<()> {
    let scene = builtin::load("cornell")?;
    let options = options!(Ispm, photons: 20_000, width: 64, height: 48);
    // Made once: the GPU state, the BVH and the photon ring live from frame to frame.
    let mut renderer = Renderer::new(&scene, &options)?;
    // What each frame reads back: the radiance only (`Images::ALL` for every image).
    let desc = FrameDesc {
        seed: None,
        images: Images {
            aovs: false,
            extras: false,
        },
        serial: false,
        readout: Default::default(),
    };
    for frame in 0..4 {
        // Move the first light a little (a point or spot light; a sun turns).
        let mut light = renderer.scene().light_desc(0).expect("cornell has a light");
        match &mut light {
            LightDesc::Point { position, .. } | LightDesc::Spot { position, .. } => {
                position[0] += 0.05
            }
            LightDesc::Directional { direction, .. } => direction[0] += 0.05,
        }
        renderer.update(&SceneUpdate::Light { index: 0, light })?;
        let out = renderer.render(&desc, &Silent)?;
        println!(
            "frame {frame}: mean radiance {:?}, {:.1} ms",
            out.radiance.mean(),
            out.stats.total_seconds * 1e3
        );
    }
    Ok(())
}
