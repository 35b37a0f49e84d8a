//! Step 5 of an `ispm` frame: mirrors and glass seen by the camera, traced backwards on the
//! CPU with a photon-map gather where the paths land (section 4), kept while nothing
//! changes and their landings kept while only the lights change.

use super::super::context::FrameCtx;
use super::super::gpu::GpuFrame;
use super::super::options::IspmOptions;
use crate::error::Result;
use crate::image::Image;
use crate::photon::delta_paths::Landings;
use crate::photon::specular::{specular_paths, SpecularPaths};
use crate::photon::Photon;
use crate::scene::{Changes, Scene};

/// The specular paths' state across frames.
pub(super) struct Specular {
    /// Whether the scene has mirrors or glass (the specular texture is written each frame).
    enabled: bool,
    /// The specular image of the last frame (reused while the camera and scene stand still).
    image: Option<Image>,
    /// The camera side of the specular paths (kept while only the lights change).
    landings: Option<Landings>,
}

impl Specular {
    pub fn new(scene: &Scene) -> Self {
        Specular {
            enabled: scene.has_specular_traced(),
            image: None,
            landings: None,
        }
    }

    /// Forgets what `changes` made stale: the image on any change; the landings, which
    /// depend on the view, the geometry and the materials, not on the lights.
    pub fn invalidate(&mut self, changes: Changes) {
        if changes.any() {
            self.image = None;
        }
        if changes.camera || changes.geometry || changes.materials {
            self.landings = None;
        }
    }

    /// The frame's specular image, traced (and uploaded) when the `photons` changed or no
    /// image is kept (else the kept one, not copied); `None` for a scene without mirrors or
    /// glass.
    pub fn render(
        &mut self,
        gpu: &GpuFrame,
        fc: &mut FrameCtx,
        options: &IspmOptions,
        photons: &[Photon],
        photons_changed: bool,
    ) -> Result<Option<&Image>> {
        let t = std::time::Instant::now();
        if self.enabled && (self.image.is_none() || photons_changed) {
            self.image = None;
            let (scene, bvh, params, progress) = (fc.scene, fc.bvh()?, fc.params, fc.progress);
            let paths = SpecularPaths {
                samples: super::super::options::derived::camera_samples(
                    options.direct.spp,
                    options.max_depth,
                    params,
                ),
                sampling: options.specular_sampling,
                gather: super::super::options::derived::knn_gather(
                    scene,
                    options.k,
                    &options.kernel,
                    params,
                ),
                precompute: !params.progressive,
            };
            let traced = specular_paths(scene, bvh, &paths, photons, &mut self.landings, progress);
            fc.add_stage("specular paths", t.elapsed().as_secs_f64());
            let (img, camera_paths) = traced?;
            fc.stats.camera_paths = camera_paths;
            gpu.targets.write_specular(&gpu.ctx, &img);
            self.image = Some(img);
        } else {
            fc.add_stage("specular paths", t.elapsed().as_secs_f64());
        }
        Ok(self.image.as_ref().filter(|_| self.enabled))
    }
}
