//! The CPU methods as frames of the engine: `path` (the reference), `photon` (kNN photon
//! mapping) and `gather` (photon differentials + LBVH), each over the renderer's BVH.

use crate::error::Result;
use crate::render::{gather, photon_map, reference, Method, Progress, RenderOutput, Settings};
use crate::scene::Scene;
use crate::trace::SceneBvh;

pub(super) fn frame(
    scene: &Scene,
    bvh: &SceneBvh,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<RenderOutput> {
    match settings.method {
        Method::Photon => photon_map::render(scene, bvh, settings, progress),
        Method::Gather => gather::render(scene, bvh, settings, progress),
        _ => reference::render(scene, bvh, settings, progress),
    }
}
