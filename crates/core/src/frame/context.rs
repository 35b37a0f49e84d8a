//! What every step of a frame reads and adds to: the scene, its CPU BVH, the frame's
//! parameters, the progress to report to and check, whether the frame waits after each
//! stage, and the statistics it returns. The renderer makes one per frame and hands it to
//! the method, which hands it to its steps, instead of the same five arguments to each.

use super::{FrameParams, RenderStats};
use crate::cancel::Progress;
use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::trace::SceneBvh;
use std::time::Instant;

/// One frame's context (see the module).
pub(crate) struct FrameCtx<'a> {
    pub scene: &'a Scene,
    /// The CPU BVH, built for the methods that trace rays on the CPU (not `direct`).
    pub bvh: Option<&'a SceneBvh>,
    pub params: &'a FrameParams,
    pub progress: &'a dyn Progress,
    /// Wait for the GPU after each stage and time it (`FrameDesc::serial`).
    pub serial: bool,
    /// The frame's statistics: each step adds its stages and counts.
    pub stats: RenderStats,
}

impl<'a> FrameCtx<'a> {
    /// The CPU BVH of a method that uses one (the renderer builds it before the frame).
    pub fn bvh(&self) -> Result<&'a SceneBvh> {
        self.bvh
            .ok_or_else(|| Error::internal("a frame that traces rays found no CPU BVH"))
    }

    /// Runs `f` and adds its wall-clock seconds to stage `name` (the one way a step times a
    /// stage; a stage timed in parts, such as `bidir`'s uploads, adds up).
    pub fn timed<T>(&mut self, name: &str, f: impl FnOnce(&mut Self) -> T) -> T {
        let t = Instant::now();
        let out = f(self);
        self.add_stage(name, t.elapsed().as_secs_f64());
        out
    }

    /// Adds `seconds` to stage `name` (a new stage unless the frame has one of that name).
    pub fn add_stage(&mut self, name: &str, seconds: f64) {
        let stages = &mut self.stats.stages;
        match stages.iter_mut().find(|(n, _)| n == name) {
            Some((_, s)) => *s += seconds,
            None => stages.push((name.to_string(), seconds)),
        }
    }
}
