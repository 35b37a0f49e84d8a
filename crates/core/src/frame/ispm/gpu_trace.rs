//! Step 4's choice of tracer (`photon_trace`): the CPU trace, or the GPU continuation pass
//! ([`crate::gpu::photon::trace`]) over the scene uploaded once and again after its
//! geometry or materials change.

use super::super::context::FrameCtx;
use super::super::options::IspmOptions;
use crate::error::Result;
use crate::gpu::photon::scene::GpuPhotonScene;
use crate::gpu::photon::PhotonTrace;
use crate::gpu::GpuContext;
use crate::scene::{Changes, Scene};

/// The resolved choice, why, and the GPU trace's scene.
pub(super) struct GpuTrace {
    pub choice: PhotonTrace,
    pub reason: String,
    scene: Option<GpuPhotonScene>,
}

impl GpuTrace {
    /// Resolves `o.photon_trace` for `scene` on `ctx`'s adapter (a setting error for `gpu`
    /// on a scene it cannot trace).
    pub fn new(ctx: &GpuContext, scene: &Scene, o: &IspmOptions) -> Result<Self> {
        let (choice, reason) = o
            .photon_trace
            .resolve(&ctx.info, scene, o.footprint_volumes)?;
        Ok(GpuTrace {
            choice,
            reason,
            scene: None,
        })
    }

    /// The scene to trace on the GPU with, `None` when tracing on the CPU: uploaded (stage
    /// "gpu trace upload") on first use and when `changes` moved geometry or materials.
    pub fn scene(
        &mut self,
        ctx: &GpuContext,
        fc: &mut FrameCtx,
        changes: Changes,
    ) -> Result<Option<&GpuPhotonScene>> {
        if self.choice != PhotonTrace::Gpu {
            return Ok(None);
        }
        if changes.geometry || changes.materials {
            self.scene = None;
        }
        if self.scene.is_none() {
            let (scene, bvh) = (fc.scene, fc.bvh()?);
            let uploaded = fc.timed("gpu trace upload", |_| {
                GpuPhotonScene::upload(ctx, scene, bvh)
            })?;
            self.scene = Some(uploaded);
        }
        Ok(self.scene.as_ref())
    }
}
