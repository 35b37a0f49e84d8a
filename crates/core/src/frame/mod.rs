//! The frame engine. A [`Renderer`] is made once from a scene and options and owns what
//! lives from one frame to the next: the scene (updated in place by [`SceneUpdate`]s), its
//! CPU BVH, and for the GPU methods the device, the scene's GPU buffers, the render targets
//! of one size, the estimator's resources and the temporal photon ring. A frame re-uploads
//! only what changed and reads back only the images asked for ([`FrameDesc`]).
//!
//! One file per method runs its passes in order: `direct`, `ispm`, `bidir`; the CPU
//! methods (`path`, `photon`, `gather`) reuse the renderer's BVH.

mod bidir;
mod context;
mod direct;
pub mod gather;
mod glass_stand_in;
mod gpu;
mod ispm;
mod model_stand_in;
pub mod options;
pub mod output;
mod path;
mod photon;
mod progressive;
pub mod readout;

use crate::cancel::Progress;
use crate::error::{Error, Result};
use crate::gpu::GpuContext;
use crate::image::Image;
use crate::photon::lbvh::Aabb;
use crate::photon::ring::PhotonRing;
use crate::scene::{Changes, Scene, SceneUpdate};
use crate::trace::SceneBvh;
use context::FrameCtx;
pub use ispm::bounce_map;
use options::DirectLightOptions;
pub use options::{Method, MethodOptions, RenderOptions};
pub use output::{RenderOutput, RenderStats};
pub use progressive::progressive_radius_scale;
use std::sync::Arc;
use std::time::Instant;

/// Which images a frame reads back. The radiance always; the rest on request.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Images {
    /// `albedo`, `normal`, `position`, `depth` (and `caustics`).
    pub aovs: bool,
    /// The method's own images (`RenderOutput::aovs`; `ispm`: direct, specular, indirect,
    /// photons).
    pub extras: bool,
}

impl Images {
    /// Everything: what the one-shot [`crate::render`] returns.
    pub const ALL: Images = Images {
        aovs: true,
        extras: true,
    };
}

/// What to render in one frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameDesc {
    /// Random seed of the frame; `None`: the options' seed, varied per frame when temporal
    /// reuse is on (`temporal_frames` > 1) and kept otherwise (frame-coherent random
    /// numbers, ISPM section 4.1: a still scene does not flicker).
    pub seed: Option<u64>,
    pub images: Images,
    /// Wait for the GPU after each stage, so that the stages' wall-clock times
    /// (`RenderStats::stages`, named "… (wall)") add up to the frame: for benchmarks on
    /// devices whose timestamps cannot place compute passes (lavapipe). Slower: the CPU
    /// trace no longer overlaps the GPU's direct light. Method `ispm` only.
    pub serial: bool,
    /// In what form the radiance is handed back (32-bit floats by default; half floats, a
    /// tone-mapped 8-bit display image, or both; see [`readout`]). Methods `direct` and
    /// `ispm` encode on the GPU and read back only what is asked for.
    pub readout: readout::Readout,
}

/// What varies from frame to frame beyond the scene: the frame's seed, the kernel scale
/// of a progressive pass, and whether the first-hit images are wanted.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FrameParams {
    pub seed: u64,
    /// Scale of every photon kernel radius (ISPM volumes, gather footprints and their caps,
    /// k-NN gathers): shrinks per progressive pass, 1 otherwise.
    pub radius_scale: f32,
    /// The CPU methods trace one more camera ray per pixel for the first-hit images.
    pub first_hit_aovs: bool,
    /// The frame is a progressive pass.
    pub progressive: bool,
}

/// The GPU side of a renderer (methods `direct` and `ispm`).
struct GpuState {
    ctx: Arc<GpuContext>,
    scene: gpu::GpuScene,
    targets: gpu::Targets,
    timer: crate::gpu::timer::Timer,
    ispm: Option<ispm::IspmState>,
    bidir: Option<bidir::BidirState>,
    /// What `direct`'s specular texture holds of the light met through mirrors and glass.
    delta_light: direct::DeltaLightState,
    /// This frame waits after each stage ([`FrameDesc::serial`]).
    serial: bool,
}

/// A persistent renderer of one scene with one method.
pub struct Renderer {
    scene: Scene,
    options: RenderOptions,
    /// What the renderer leaves out of the scene's light (see [`Renderer::warnings`]).
    warnings: Vec<String>,
    bvh: Option<SceneBvh>,
    /// What changed since the last frame.
    changes: Changes,
    /// Objects moved since the last frame, with the bounds they had before.
    moved: Vec<(usize, Aabb)>,
    lights_changed: Vec<usize>,
    resized: bool,
    gpu: Option<GpuState>,
    ring: PhotonRing,
    frame_index: u64,
    bvh_cost: BvhCost,
    /// Progressive mode: the running sum of the passes since the last change.
    accum: Option<progressive::Accumulation>,
    /// The scene's own lights and environment before the first [`Renderer::set_lighting`],
    /// which each later call starts from.
    own_lighting: Option<(
        Vec<crate::scene::Light>,
        Option<Arc<crate::scene::Environment>>,
    )>,
    /// [`Renderer::set_lighting`] changed the environment since the last frame: the GPU
    /// state swaps its environment tables (and `bidir` its state) at the next one.
    environment_changed: bool,
    /// The number of lights the GPU scene's light buffer was made for.
    gpu_lights: usize,
    /// Materials of rough glass that a GPU method renders as smooth glass
    /// ([`glass_stand_in`]).
    glass_stand_ins: Vec<String>,
}

/// Light transport `options` ask for that their method does not compute, one message each
/// (they become `gi.RenderWarning`s).
fn transport_omissions(scene: &Scene, options: &RenderOptions) -> Vec<String> {
    // `bidir`'s caustics of parallel suns seen directly are its delta-chain light tracer's
    // (`bidir/specular_paths.rs`) since issue 44: nothing to name there.
    let method = options.method();
    model_stand_in::warning(scene, method)
        .into_iter()
        .chain(glass_stand_in::thin_warning(scene, method))
        .collect()
}

/// Most refits before the BVH is built anew (a refitted tree keeps its topology and slows
/// down as objects travel).
const MAX_REFITS: u32 = 16;

/// Measured costs of the two ways to update the CPU BVH after objects moved: the renderer
/// tries each once, then keeps the faster (reported as stage "bvh build" or "bvh refit").
#[derive(Clone, Copy, Debug, Default)]
struct BvhCost {
    build: Option<f64>,
    refit: Option<f64>,
    refits: u32,
}

impl Renderer {
    /// A renderer of `scene` (copied) with `options`; the image size is the options' or,
    /// failing that, the scene camera's.
    pub fn new(scene: &Scene, options: &RenderOptions) -> Result<Self> {
        options.validate()?;
        let method = options.method();
        let camera = scene.camera.with_size(
            options.common.width.unwrap_or(scene.camera.width),
            options.common.height.unwrap_or(scene.camera.height),
        );
        options::check_image_memory(&camera, method)?;
        let mut scene = Scene {
            camera,
            ..scene.clone()
        };
        let glass_stand_ins = glass_stand_in::replace(&mut scene, method);
        let mut warnings = transport_omissions(&scene, options);
        warnings.extend(glass_stand_in::warning(method.name(), &glass_stand_ins));
        Ok(Renderer {
            scene,
            glass_stand_ins,
            options: options.clone(),
            warnings,
            bvh: None,
            changes: Changes::default(),
            moved: Vec::new(),
            lights_changed: Vec::new(),
            resized: false,
            gpu: None,
            ring: PhotonRing::new(options.method.temporal_frames() as usize),
            frame_index: 0,
            bvh_cost: BvhCost::default(),
            accum: None,
            own_lighting: None,
            environment_changed: false,
            gpu_lights: 0,
        })
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    pub fn options(&self) -> &RenderOptions {
        &self.options
    }

    /// What the method leaves out of the scene's light, one message each (e.g. a kind of
    /// light it does not render yet).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    pub fn method(&self) -> Method {
        self.options.method()
    }

    /// Frames rendered so far.
    pub fn frame_index(&self) -> u64 {
        self.frame_index
    }

    /// Progressive mode: the passes in the current running mean (0 after a change).
    pub fn passes(&self) -> u64 {
        self.accum.as_ref().map_or(0, |a| a.passes)
    }

    /// Applies a change to the scene before the next frame.
    pub fn update(&mut self, update: &SceneUpdate) -> Result<()> {
        let before = match update {
            SceneUpdate::Transform { object, .. } => self
                .scene
                .objects
                .get(*object)
                .map(|o| object_bounds(&self.scene, o)),
            _ => None,
        };
        let c = self.scene.apply(update)?;
        let method = self.method();
        for name in glass_stand_in::replace(&mut self.scene, method) {
            if !self.glass_stand_ins.contains(&name) {
                self.glass_stand_ins.push(name);
                self.warnings = transport_omissions(&self.scene, &self.options);
                let method = self.method().name();
                self.warnings
                    .extend(glass_stand_in::warning(method, &self.glass_stand_ins));
            }
        }
        self.changes = self.changes.union(c);
        if c.any() {
            self.accum = None;
        }
        match update {
            SceneUpdate::Transform { object, .. } => {
                if let Some(b) = before {
                    self.moved.push((*object, b));
                }
            }
            SceneUpdate::Light { index, .. } => self.lights_changed.push(*index),
            _ => {}
        }
        Ok(())
    }

    /// Gives the scene `lighting` before the next frame, starting from its own lights and
    /// environment as they were before the first call (so that calls do not accumulate;
    /// light updates made since are dropped). Geometry, its BVH and the GPU scene stay: the
    /// next frame uploads the lights and the environment's tables (a GPU scene whose shadow
    /// maps or sampled lights no longer fit, e.g. a sun added, is built anew); the photons
    /// and the progressive sum start again.
    pub fn set_lighting(&mut self, lighting: &crate::scene::Lighting) -> Result<()> {
        let (lights, env) = self
            .own_lighting
            .get_or_insert_with(|| (self.scene.lights.clone(), self.scene.environment.clone()))
            .clone();
        let mut scene = self.scene.clone();
        scene.lights = lights;
        scene.environment = env;
        scene.set_lighting(lighting);
        self.scene = scene;
        self.warnings = transport_omissions(&self.scene, &self.options);
        let method = self.method().name();
        self.warnings
            .extend(glass_stand_in::warning(method, &self.glass_stand_ins));
        self.environment_changed = true;
        self.accum = None;
        self.ring = PhotonRing::new(self.options.method.temporal_frames() as usize);
        self.lights_changed = (0..self.scene.lights.len()).collect();
        self.changes = self.changes.union(Changes {
            lights: true,
            ..Default::default()
        });
        Ok(())
    }

    /// Changes the image size; targets are rebuilt at the next frame.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<()> {
        for (name, v) in [("width", width), ("height", height)] {
            if v == 0 || v > 16384 {
                return Err(Error::setting(
                    if name == "width" { "width" } else { "height" },
                    "must be in 1..=16384",
                ));
            }
        }
        if (width, height) != (self.scene.camera.width, self.scene.camera.height) {
            let camera = self.scene.camera.with_size(width, height);
            options::check_image_memory(&camera, self.method())?;
            self.scene.camera = camera;
            self.resized = true;
            self.accum = None;
        }
        Ok(())
    }

    /// The seed of the next frame (see [`FrameDesc::seed`]).
    fn frame_seed(&self) -> u64 {
        let seed = self.options.common.seed;
        if self.options.method.temporal_frames() <= 1 || self.frame_index == 0 {
            seed
        } else {
            seed ^ self.frame_index.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        }
    }

    /// Renders one frame.
    pub fn render(&mut self, desc: &FrameDesc, progress: &dyn Progress) -> Result<RenderOutput> {
        let t0 = Instant::now();
        let mut stages = Vec::new();
        crate::cancel::check(progress)?;
        // Only the methods that trace rays on the CPU build (and keep updating) the BVH:
        // `direct` where mirrors or glass are seen (`direct::one_bounce_light`).
        if !self.method().uses_cpu_bvh_in(&self.scene) {
            self.bvh = None;
        } else if self.bvh.is_none() || self.changes.geometry {
            stages.push(self.update_bvh()?);
        }
        if self.changes.materials {
            // Alpha masks may have changed with the materials.
            if let Some(bvh) = self.bvh.as_mut() {
                bvh.update_alpha(&self.scene);
            }
        }
        let pass = self.passes();
        let common = &self.options.common;
        let mut frame = if common.progressive {
            progressive::pass_params(common, desc.seed, pass)
        } else {
            FrameParams {
                seed: desc.seed.unwrap_or_else(|| self.frame_seed()),
                radius_scale: 1.0,
                first_hit_aovs: true,
                progressive: false,
            }
        };
        // Not asked for: the CPU methods skip their first-hit rays (`keep_requested` drops
        // the images anyway).
        frame.first_hit_aovs &= desc.images.aovs;
        if let Some(g) = self.gpu.as_mut() {
            g.targets
                .set_sample_offset(progressive::sample_offset(common, pass));
            g.serial = desc.serial;
        }
        let mut out = match &self.options.method {
            MethodOptions::Path(o) => {
                path::render(&self.scene, self.cpu_bvh()?, o, &frame, progress)?
            }
            MethodOptions::Photon(o) => {
                photon::render(&self.scene, self.cpu_bvh()?, o, &frame, progress)?
            }
            MethodOptions::Gather(o) => {
                gather::render(&self.scene, self.cpu_bvh()?, o, &frame, progress)?
            }
            _ => {
                // The composite is the final radiance of a frame of `direct` and `ispm`
                // (progressive passes are summed, and `bidir` spreads spikes, on the CPU).
                let last = matches!(self.method(), Method::Direct | Method::Ispm);
                let on_gpu = readout::on_gpu(desc.readout, last && !common.progressive);
                self.gpu_frame(&frame, desc.images, on_gpu, progress)?
            }
        };
        out.stats.method = self.method().name().to_string();
        stages.append(&mut out.stats.stages);
        out.stats.stages = stages;
        keep_requested(&mut out, desc.images);
        if self.options.common.progressive {
            let acc = self
                .accum
                .get_or_insert_with(|| progressive::Accumulation::new(&out.radiance));
            out.radiance = acc.add(&out.radiance);
            out.stats.passes = acc.passes;
        } else {
            out.stats.passes = 1;
        }
        readout::complete(&mut out, desc.readout);
        self.changes = Changes::default();
        self.moved.clear();
        self.lights_changed.clear();
        self.resized = false;
        self.frame_index += 1;
        out.stats.total_seconds = t0.elapsed().as_secs_f64();
        Ok(out)
    }

    /// Builds the BVH, or after objects moved rebuilds or refits it, whichever measured
    /// faster (each is tried once first).
    fn update_bvh(&mut self) -> Result<(String, f64)> {
        let t = Instant::now();
        let c = self.bvh_cost;
        let refit = match (&self.bvh, c.build, c.refit) {
            (None, ..) => false,
            _ if c.refits >= MAX_REFITS => false,
            (Some(_), _, None) => true,
            (Some(_), Some(build), Some(refit)) => refit < build,
            (Some(_), None, Some(_)) => false,
        };
        let (name, seconds) = if let (true, Some(bvh)) = (refit, self.bvh.take()) {
            let moved: Vec<std::ops::Range<usize>> = self
                .moved
                .iter()
                .map(|(o, _)| {
                    let r = &self.scene.objects[*o].triangles;
                    r.start as usize..r.end as usize
                })
                .collect();
            self.bvh = Some(bvh.refit(&self.scene, &moved));
            let s = t.elapsed().as_secs_f64();
            self.bvh_cost.refit = Some(s);
            self.bvh_cost.refits += 1;
            ("bvh refit", s)
        } else {
            self.bvh = Some(SceneBvh::try_build(&self.scene)?);
            let s = t.elapsed().as_secs_f64();
            self.bvh_cost.build = Some(s);
            self.bvh_cost.refits = 0;
            ("bvh build", s)
        };
        Ok((name.to_string(), seconds))
    }

    /// The CPU BVH (built or updated at the start of every frame of a method that uses it).
    fn cpu_bvh(&self) -> Result<&SceneBvh> {
        self.bvh.as_ref().ok_or_else(no_bvh)
    }

    fn gpu_frame(
        &mut self,
        frame: &FrameParams,
        images: Images,
        readout: readout::Readout,
        progress: &dyn Progress,
    ) -> Result<RenderOutput> {
        let Some(direct) = self.options.method.direct_light() else {
            return Err(Error::setting("method", "not a GPU method"));
        };
        let ctx = match &self.gpu {
            Some(g) => g.ctx.clone(),
            None => crate::gpu::context(direct.adapter.as_deref())?,
        };
        let direct = direct.clone();
        let ispm = self.method() == Method::Ispm;
        ctx.scoped("frame", || {
            self.sync_gpu(&ctx, &direct)?;
            if let Some(g) = self.gpu.as_mut() {
                g.targets.set_readout(readout);
            }
            let mut out = self.gpu_method_frame(frame, images, progress)?;
            let g = self.gpu.as_mut().ok_or_else(no_gpu_state)?;
            if g.targets.grow_edges(&ctx)? {
                if frame.progressive && ispm {
                    // Progressive `ispm` corrects the composite on the CPU (ray-traced
                    // direct light, per-pixel kernel coverage): the whole pass again.
                    out = self.gpu_method_frame(frame, images, progress)?;
                } else {
                    // More edge pixels than their buffers held: grown, and the direct light
                    // and the composite redone over the frame's indirect and specular light.
                    let fc = FrameCtx {
                        scene: &self.scene,
                        bvh: self.bvh.as_ref(),
                        params: frame,
                        progress,
                        serial: g.serial,
                        stats: RenderStats::default(),
                    };
                    direct::redo(g, fc, images, &mut out)?;
                }
            }
            Ok(out)
        })
    }

    /// One frame of a GPU method on the synchronized GPU state.
    fn gpu_method_frame(
        &mut self,
        frame: &FrameParams,
        images: Images,
        progress: &dyn Progress,
    ) -> Result<RenderOutput> {
        let gpu = self.gpu.as_mut().ok_or_else(no_gpu_state)?;
        let scene = &self.scene;
        let fc = FrameCtx {
            scene,
            // Built by `render` for the methods that use it (`direct` only with mirrors
            // or glass).
            bvh: self.bvh.as_ref(),
            params: frame,
            progress,
            serial: gpu.serial,
            stats: RenderStats {
                triangles: scene.triangle_count() as u64,
                samples_per_pixel: gpu.targets.spp(),
                ..Default::default()
            },
        };
        // The sampled lights: drawn once from the options' seed (a still view re-draws
        // nothing), anew per progressive pass.
        let draw = gpu::LightDraw {
            seed: if frame.progressive {
                frame.seed
            } else {
                self.options.common.seed
            },
            disc_scale: frame.radius_scale,
            progressive: frame.progressive,
        };
        match &self.options.method {
            MethodOptions::Ispm(options) => {
                let invalid = ispm::Invalidation {
                    all: self.changes.materials,
                    lights: &self.lights_changed,
                    moved: &self.moved,
                };
                ispm::frame(ispm::FrameInputs {
                    gpu,
                    fc,
                    ring: &mut self.ring,
                    invalid,
                    options,
                    frame: self.frame_index,
                    changes: self.changes,
                    draw,
                    images,
                })
            }
            MethodOptions::Bidir(options) => bidir::frame(gpu, fc, options, draw, images),
            _ => direct::frame(gpu, fc, draw, images),
        }
    }

    /// Creates the GPU state on the first frame, else uploads what changed and rebuilds
    /// the targets after a resize.
    fn sync_gpu(&mut self, ctx: &Arc<GpuContext>, direct: &DirectLightOptions) -> Result<()> {
        let scene = &self.scene;
        let counts = gpu::SampleCounts {
            area: direct.area_samples,
            sky: direct.sky_samples,
            size: direct.sample_map_size(),
            // `bidir` draws the environment (and lights with it) through its bundles.
            background: self.method() != Method::Bidir,
        };
        // A new lighting may hold more or fewer lights than the light buffer was made for.
        let fits = self
            .gpu
            .as_ref()
            .is_some_and(|g| g.scene.fits(scene, counts))
            && scene.lights.len() == self.gpu_lights;
        if !fits {
            crate::raster::check_scene_buffers(ctx, scene)?;
            let gs = gpu::GpuScene::new(ctx, scene, direct.shadow_map_size, counts)?;
            gpu::check_limits(ctx, scene, direct.shadow_map_size, gs.layers)?;
            let targets =
                gpu::Targets::new(ctx, &gs, scene, direct.spp, direct.edge_supersampling)?;
            self.gpu = Some(GpuState {
                ctx: ctx.clone(),
                scene: gs,
                targets,
                timer: gpu::frame_timer(ctx),
                ispm: None,
                bidir: None,
                delta_light: Default::default(),
                serial: false,
            });
            self.gpu_lights = scene.lights.len();
            self.environment_changed = false;
            return Ok(());
        }
        let Some(g) = self.gpu.as_mut() else {
            return Ok(());
        };
        if std::mem::take(&mut self.environment_changed) {
            g.scene
                .samples
                .set_environment(ctx, scene.environment.as_deref());
            g.targets.rebind_scene(ctx, &g.scene);
            // `bidir` binds the environment's tables in its own state.
            g.bidir = None;
            g.delta_light.invalidate();
        }
        let c = self.changes;
        if c.camera || c.geometry || c.materials {
            g.delta_light.invalidate();
            if let Some(b) = g.bidir.as_mut() {
                b.view_changed();
            }
        }
        if c.geometry {
            for (object, _) in &self.moved {
                g.scene.write_instance(ctx, scene, *object);
            }
            g.scene.geometry_moved(scene);
        }
        if c.materials {
            g.scene.write_materials(ctx, scene);
        }
        if c.lights || c.geometry {
            g.scene.write_lights(ctx, scene, None);
        }
        if self.resized {
            gpu::check_limits(ctx, scene, direct.shadow_map_size, g.scene.layers)?;
            g.targets =
                gpu::Targets::new(ctx, &g.scene, scene, direct.spp, direct.edge_supersampling)?;
            g.ispm = None;
            g.bidir = None;
            g.delta_light = Default::default();
        } else {
            g.targets.invalidate(gpu::Stale::of_changes(c));
        }
        Ok(())
    }
}

/// World bounds of an object's vertices.
fn object_bounds(scene: &Scene, o: &crate::scene::SceneObject) -> Aabb {
    scene.object_vertices(o).fold(Aabb::EMPTY, |b, p| Aabb {
        min: b.min.min(p),
        max: b.max.max(p),
    })
}

/// Drops the images the frame did not ask for (they may have been computed anyway by the
/// CPU methods).
fn keep_requested(out: &mut RenderOutput, images: Images) {
    if !images.aovs {
        for img in [
            &mut out.albedo,
            &mut out.normal,
            &mut out.position,
            &mut out.caustics,
        ] {
            *img = Image::new(0, 0);
        }
        out.depth = Vec::new();
    }
    if !images.extras {
        out.aovs.clear();
    }
}

/// Renders `scene` with `options`: one frame of a new [`Renderer`] with every image read
/// back.
pub fn render(
    scene: &Scene,
    options: &RenderOptions,
    progress: &dyn Progress,
) -> Result<RenderOutput> {
    let mut renderer = Renderer::new(scene, options)?;
    renderer.render(
        &FrameDesc {
            seed: None,
            images: Images::ALL,
            serial: false,
            readout: Default::default(),
        },
        progress,
    )
}

/// The error of a step that finds no CPU BVH (`render` builds it first for the methods
/// that use it).
fn no_bvh() -> Error {
    Error::internal("the CPU BVH is used before it is built")
}

/// The error of a GPU method's frame that finds no GPU state (`sync_gpu` makes it first).
fn no_gpu_state() -> Error {
    Error::internal("a GPU frame found no GPU state (made by `sync_gpu` first)")
}
