//! What every step of a frame reads and adds to: the scene, its CPU BVH, the frame's
//! parameters, the progress to report to and check, whether the frame waits after each
//! stage, and the statistics it returns. A method's orchestrator makes one per frame and
//! hands it to its steps, instead of the same five arguments to each.

use super::{FrameParams, RenderStats};
use crate::cancel::Progress;
use crate::scene::Scene;
use crate::trace::SceneBvh;
use std::time::Instant;

/// One frame's context (see the module).
pub(crate) struct FrameCtx<'a> {
    pub scene: &'a Scene,
    pub bvh: &'a SceneBvh,
    pub params: &'a FrameParams,
    pub progress: &'a dyn Progress,
    /// Wait for the GPU after each stage and time it (`FrameDesc::serial`).
    pub serial: bool,
    /// The frame's statistics: each step adds its stages and counts.
    pub stats: RenderStats,
}

impl FrameCtx<'_> {
    /// Adds stage `name`, begun at `t`, to the frame's statistics.
    pub fn stage(&mut self, name: &str, t: Instant) {
        self.stats
            .stages
            .push((name.to_string(), t.elapsed().as_secs_f64()));
    }
}
