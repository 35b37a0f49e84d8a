//! The methods and their options.

use crate::error::{Error, Result};
pub use crate::estimate::Estimator;
pub use crate::photon::bounce::FirstBounce;
pub use crate::photon::Kernel;
pub use crate::estimate::volume_shape::VolumeShape;
pub use crate::photon::delta_paths::SpecularSampling;
use std::str::FromStr;

/// A rendering technique.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// The CPU reference: path tracing with next-event estimation plus light tracing for
    /// caustic paths. Unbiased; the ground truth for every other method.
    Path,
    /// Classic photon mapping (Jensen): k-nearest-neighbour radiance estimates from a
    /// photon map of all bounces, direct light included. The baseline for ISPM.
    Photon,
    /// Photon differentials, a linear-BVH footprint photon map and a CPU gather estimate
    /// (Fabianowski & Dingliana 2009), with next-event estimation for direct light.
    Gather,
    /// GPU rasterization of direct light only: eye G-buffer, shadow maps (PCF) and deferred
    /// uber-BSDF shading, supersampled `spp` times per pixel.
    Direct,
    /// Image Space Photon Mapping (McGuire & Luebke 2009): GPU direct light as `direct`, plus
    /// indirect light from a GPU bounce map (the first scatter of `photons` light rays),
    /// CPU photon tracing of the later bounces, and photon volumes splatted on the GPU
    /// (optionally at 1/`subsample` resolution with joint bilateral upsampling).
    Ispm,
    /// Real-time bidirectional path tracing by rasterization (Tokuyoshi & Ogaki 2012): GPU
    /// direct light as `direct`, plus one-bounce indirect light from virtual point lights
    /// drawn from reflective shadow maps, each with its own cube shadow map.
    Bidir,
}

impl Method {
    pub const ALL: &'static [Method] = &[
        Method::Path,
        Method::Photon,
        Method::Gather,
        Method::Direct,
        Method::Ispm,
        Method::Bidir,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::Path => "path",
            Method::Photon => "photon",
            Method::Gather => "gather",
            Method::Direct => "direct",
            Method::Ispm => "ispm",
            Method::Bidir => "bidir",
        }
    }
}

impl FromStr for Method {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        crate::error::parse_named(s, Method::ALL, Method::name, "method", "method")
    }
}

/// Which strategies method `bidir` uses for the one-bounce light (Tokuyoshi & Ogaki 2012
/// §4.2): both combined by multiple importance sampling, or one alone (Figure 4: VPLs spike
/// where a VPL lies close to a receiver, bundles are noisy near bright spots).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BidirStrategy {
    #[default]
    Mis,
    Vpl,
    Bundle,
}

impl BidirStrategy {
    pub const ALL: &'static [BidirStrategy] = &[
        BidirStrategy::Mis,
        BidirStrategy::Vpl,
        BidirStrategy::Bundle,
    ];

    pub fn name(self) -> &'static str {
        match self {
            BidirStrategy::Mis => "mis",
            BidirStrategy::Vpl => "vpl",
            BidirStrategy::Bundle => "bundle",
        }
    }
}

impl FromStr for BidirStrategy {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        crate::error::parse_named(
            s,
            BidirStrategy::ALL,
            BidirStrategy::name,
            "bidir_strategy",
            "strategy",
        )
    }
}

/// Render settings. Sizes of `None` use the scene camera's.
#[derive(Clone, Debug)]
pub struct Settings {
    pub method: Method,
    /// Camera samples per pixel (method `path`); sub-pixel raster samples of the direct light
    /// (methods `direct` and `ispm`; the ISPM indirect light is shaded at pixel centres).
    pub spp: u32,
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub seed: u64,
    /// Maximum number of scattering events on a path (1 = direct light only); for method
    /// `ispm` photons are traced to bounce `max_depth − 1`.
    pub max_depth: u32,
    /// Light paths for caustics (method `path`); `None` = one per camera sample.
    pub light_paths: Option<u64>,
    /// Photons emitted from the lights (method `photon`); for method `ispm` the bounce-map
    /// texels of all lights together (the first-bounce photon budget, split by power).
    pub photons: u64,
    /// Photons per radiance estimate (method `photon`).
    pub k: u32,
    /// Maximum gather radius in metres (method `photon`); `None` = 5% of the scene's
    /// bounding-box diagonal.
    pub max_radius: Option<f32>,
    /// Density estimation kernel (methods `photon` and `gather`).
    pub kernel: Kernel,
    /// Footprint smoothing factor s of photon differentials (method `gather`).
    pub smoothing: f32,
    /// Footprints per photon-map BVH leaf (method `gather`); `None` = the automatic T_auto.
    pub leaf_size: Option<u32>,
    /// GPU adapter: "cpu", "gpu" or a case-insensitive part of its name; `None` uses the
    /// `GI_ADAPTER` environment variable, else a real GPU when present, else lavapipe.
    pub adapter: Option<String>,
    /// Shadow-map resolution in texels per side (GPU methods).
    pub shadow_map_size: u32,
    /// Scale of the photon-volume radii (method `ispm`); 1 = a photon of path density 1
    /// gets √(scene area / photons) and each diffuse bounce widens it about 4×.
    pub kernel_scale: f32,
    /// Indirect light is splatted at 1/`subsample` resolution and joint-bilaterally
    /// upsampled (method `ispm`); 1 = full resolution. 1..=8. Default 2: at equal error
    /// against the converged image it is 1.3–1.7× faster than 1 on lavapipe
    /// (docs/bench/ispm.md, equal-error table), with the same RMSE.
    pub subsample: u32,
    /// Size ISPM photon volumes by photon-differential footprints (as method `gather`,
    /// with `smoothing` and `max_radius`) instead of the path-density heuristic.
    pub footprint_volumes: bool,
    /// Divide each ISPM photon's power by the fraction of its kernel that lies on surfaces
    /// (probe rays, `photon::boundary`), so that photons near edges and corners don't lose
    /// the energy that falls off the surface; the same for the footprints of method
    /// `gather` (on `cornell`, progressive gather's error near edges fell from −4.7% to
    /// −0.8% on average, docs/bench/progressive.md).
    pub boundary_compensation: bool,
    /// GPU methods: supersample the direct light only at pixels whose neighbourhood of
    /// pixel-centre G-buffer samples crosses a silhouette, crease or material boundary
    /// (`raster::edges`), shading the others once at their centre; false supersamples
    /// every pixel `spp` times (a full-screen pass per sample). Measured on lavapipe
    /// (docs/bench/frame.md): the same image to a relative RMSE of ~1e-4 at 640×480 and
    /// 1280×720, and 6–9.5× less time for a frame whose lights moved.
    pub edge_supersampling: bool,
    /// Bounding shape of the ISPM photon volumes: icosahedra, screen-aligned quads, or per
    /// photon by projected size (`Auto`). Changes the cost only, not the image.
    pub volume_shape: VolumeShape,
    /// Indirect estimator of method `ispm` (`estimate::Estimator`): raster photon volumes,
    /// tiled compute splatting, or per adapter (`Auto`). Changes the cost, not the image
    /// (up to float summation order).
    pub estimator: Estimator,
    /// Where method `ispm` finds the photons' first hits (`photon::bounce::FirstBounce`):
    /// rasterized bounce maps, the same photons cast in the CPU BVH, or per adapter
    /// (`Auto`). The photons have the same distribution either way.
    pub first_bounce: FirstBounce,
    /// Temporal photon reuse (method `ispm`, Jozwowski 2002): a frame splats the photons
    /// of the last `temporal_frames` frames of a `Renderer`, each frame tracing `photons`
    /// new ones; 1 = no reuse (and frame-coherent random numbers).
    pub temporal_frames: u32,
    /// Progressive mode (methods `ispm`, `gather`, `path`, `direct`): each frame of a
    /// `Renderer` is one pass, an independent estimate with fresh random numbers (photons,
    /// pixel jitter, light samples) and kernels shrunk by [`Settings::radius_scale`], and
    /// the frame's radiance is the running mean of the passes since the last scene, camera
    /// or size change (probabilistic progressive photon mapping, Knaus & Zwicker 2011).
    pub progressive: bool,
    /// α of the progressive radius sequence r²ᵢ₊₁ = r²ᵢ (i + α)/(i + 1), in (0, 1).
    pub progressive_alpha: f32,
    /// Scale of every photon kernel radius (ISPM volumes, gather footprints and their
    /// caps), set per pass by the progressive mode; 1 otherwise.
    pub radius_scale: f32,
    /// Bound each caustic photon's kernel radius by the distance to its k-th nearest caustic
    /// neighbour (`photon::density`; methods `ispm` and `gather`): small where caustics
    /// focus, wide where they spread.
    pub caustic_density_bound: bool,
    /// Share of each light's photons aimed at the mirrors and glass through its projection
    /// map (`photon::focus`), weighted so that the estimate is unchanged. 0 = none. Method
    /// `gather`: that share of its photons is aimed. Method `ispm`: each light whose map holds
    /// every specular object also emits this share of its bounce-map photons from the CPU
    /// into the map, and those carry all its first hits on mirrors and glass (the bounce
    /// map's are dropped). Default 0.25: on gather at 200k photons (docs/bench/caustics.md) it keeps
    /// most of 0.5's gain where caustics dominate (mirror-shadow FLIP 0.290 → 0.156, 0.147
    /// at 0.5) and little of its cost elsewhere (cornell-glass 0.078 → 0.080, 0.085 at 0.5).
    pub photon_focus: f32,
    /// Compute the first-hit images (albedo, normal, position, depth) of the CPU methods:
    /// one extra camera ray per pixel through its centre. A `frame::Renderer` clears it for
    /// frames whose AOVs are not asked for (at one sample per pixel, as in a progressive
    /// pass of `gather`, that ray was about a tenth of the camera pass on `cornell`).
    pub first_hit_aovs: bool,
    /// Virtual point lights per light and frame (method `bidir`), drawn from the light's
    /// reflective shadow map with probability proportional to texel flux.
    pub vpls_per_light: u32,
    /// Reflective-shadow-map texels a side per view for a light of average power (method
    /// `bidir`); views of brighter lights get more (the split of the ISPM bounce map).
    pub rsm_size: u32,
    /// Cube shadow-map resolution of each VPL, texels per face side (method `bidir`).
    pub vpl_shadow_map_size: u32,
    /// Global ray bundles per frame (method `bidir`); 0 = VPLs only.
    pub bundles: u32,
    /// Ray-bundle resolution, pixels a side of the parallel projection (method `bidir`).
    pub bundle_resolution: u32,
    /// Memory for the ray bundles' fragment lists, MiB (method `bidir`); fragments beyond it
    /// are dropped and counted in `RenderStats::bundle_overflow`.
    pub bundle_memory_mb: u32,
    /// Strategies of `bidir`'s one-bounce light.
    pub bidir_strategy: BidirStrategy,
    /// Roughness clamping of glossy BSDFs at `bidir`'s path vertices (Tokuyoshi & Ogaki
    /// 2012 §5): the GGX α is raised where the samples are too sparse for its peak.
    pub roughness_clamping: bool,
    /// How the CPU specular paths of `ispm` and `bidir` (mirrors and glass seen by the
    /// camera) are sampled: adaptively (`render::delta_paths`) or `spp` paths through every
    /// pixel. Changes the cost and the noise, not the expectation.
    pub specular_sampling: SpecularSampling,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            method: Method::Path,
            spp: 64,
            width: None,
            height: None,
            seed: 0,
            max_depth: 64,
            light_paths: None,
            photons: 200_000,
            k: 100,
            max_radius: None,
            kernel: Kernel::default(),
            smoothing: 1.0,
            leaf_size: None,
            adapter: None,
            shadow_map_size: 1024,
            kernel_scale: 1.0,
            subsample: 2,
            footprint_volumes: false,
            boundary_compensation: true,
            edge_supersampling: true,
            volume_shape: VolumeShape::Auto,
            estimator: Estimator::Auto,
            first_bounce: FirstBounce::Auto,
            temporal_frames: 1,
            progressive: false,
            progressive_alpha: 0.7,
            radius_scale: 1.0,
            caustic_density_bound: true,
            photon_focus: 0.25,
            first_hit_aovs: true,
            vpls_per_light: 64,
            rsm_size: 64,
            vpl_shadow_map_size: 128,
            bundles: 16,
            bundle_resolution: 128,
            bundle_memory_mb: 64,
            bidir_strategy: BidirStrategy::Mis,
            roughness_clamping: true,
            specular_sampling: SpecularSampling::Adaptive,
        }
    }
}

impl Settings {
    /// The defaults of `method`: those of [`Settings::default`], with 16 direct-light samples
    /// per pixel for the GPU methods (`direct`, `ispm`), where 64 gave within 0.5% of
    /// the same image error against the converged path tracer at 4× the raster passes
    /// (`docs/bench/defaults.md`).
    pub fn for_method(method: Method) -> Settings {
        let spp = match method {
            Method::Direct | Method::Ispm | Method::Bidir => GPU_DEFAULT_SPP,
            _ => Settings::default().spp,
        };
        Settings {
            method,
            spp,
            ..Default::default()
        }
    }
}

/// Default direct-light samples per pixel of the GPU methods (see [`Settings::for_method`]).
pub const GPU_DEFAULT_SPP: u32 = 16;

/// Upper bounds that keep absurd requests from exhausting memory or running for days.
pub const MAX_SPP: u32 = 1 << 20;
pub const MAX_LIGHT_PATHS: u64 = 1 << 36;
pub const MAX_PHOTONS: u64 = 1_000_000_000;
pub const MAX_K: u32 = 1 << 16;
pub const MAX_TEMPORAL_FRAMES: u32 = 64;
/// VPLs per light (each takes six shadow-map layers).
pub const MAX_VPLS_PER_LIGHT: u32 = 1024;
/// Ray bundles per frame.
pub const MAX_BUNDLES: u32 = 4096;

impl Settings {
    pub fn validate(&self) -> Result<()> {
        if !(self.smoothing.is_finite() && self.smoothing > 0.0 && self.smoothing <= 100.0) {
            return Err(Error::setting("smoothing", "must be in (0, 100]"));
        }
        if let Some(n) = self.leaf_size {
            if n == 0 || n > 4096 {
                return Err(Error::setting("leaf_size", "must be in 1..=4096"));
            }
        }
        if self.spp == 0 || self.spp > MAX_SPP {
            return Err(Error::setting("spp", format!("must be in 1..={MAX_SPP}")));
        }
        for (name, v) in [("width", self.width), ("height", self.height)] {
            if let Some(v) = v {
                if v == 0 || v > 16384 {
                    return Err(Error::setting(
                        if name == "width" { "width" } else { "height" },
                        "must be in 1..=16384",
                    ));
                }
            }
        }
        if self.max_depth == 0 || self.max_depth > 1024 {
            return Err(Error::setting("max_depth", "must be in 1..=1024"));
        }
        if let Some(n) = self.light_paths {
            if n > MAX_LIGHT_PATHS {
                return Err(Error::setting(
                    "light_paths",
                    format!("must be at most {MAX_LIGHT_PATHS}"),
                ));
            }
        }
        if self.photons == 0 || self.photons > MAX_PHOTONS {
            return Err(Error::setting(
                "photons",
                format!("must be in 1..={MAX_PHOTONS}"),
            ));
        }
        if self.k == 0 || self.k > MAX_K {
            return Err(Error::setting("k", format!("must be in 1..={MAX_K}")));
        }
        if let Some(r) = self.max_radius {
            if !(r.is_finite() && r > 0.0) {
                return Err(Error::setting(
                    "max_radius",
                    "must be a positive finite distance",
                ));
            }
        }
        if !(16..=16384).contains(&self.shadow_map_size) {
            return Err(Error::setting("shadow_map_size", "must be in 16..=16384"));
        }
        if !(self.kernel_scale.is_finite() && self.kernel_scale > 0.0 && self.kernel_scale <= 1e3) {
            return Err(Error::setting(
                "kernel_scale",
                "must be a positive finite scale up to 1000",
            ));
        }
        if !(1..=8).contains(&self.subsample) {
            return Err(Error::setting("subsample", "must be in 1..=8"));
        }
        if !(1..=MAX_TEMPORAL_FRAMES).contains(&self.temporal_frames) {
            return Err(Error::setting(
                "temporal_frames",
                format!("must be in 1..={MAX_TEMPORAL_FRAMES}"),
            ));
        }
        if !(0.0..=0.95).contains(&self.photon_focus) {
            return Err(Error::setting("photon_focus", "must be in [0, 0.95]"));
        }
        if !(1..=MAX_VPLS_PER_LIGHT).contains(&self.vpls_per_light) {
            return Err(Error::setting(
                "vpls_per_light",
                format!("must be in 1..={MAX_VPLS_PER_LIGHT}"),
            ));
        }
        if !(1..=4096).contains(&self.rsm_size) {
            return Err(Error::setting("rsm_size", "must be in 1..=4096"));
        }
        if !(16..=4096).contains(&self.vpl_shadow_map_size) {
            return Err(Error::setting(
                "vpl_shadow_map_size",
                "must be in 16..=4096",
            ));
        }
        if self.bundles > MAX_BUNDLES {
            return Err(Error::setting(
                "bundles",
                format!("must be in 0..={MAX_BUNDLES}"),
            ));
        }
        if !(16..=4096).contains(&self.bundle_resolution) {
            return Err(Error::setting("bundle_resolution", "must be in 16..=4096"));
        }
        if !(1..=4096).contains(&self.bundle_memory_mb) {
            return Err(Error::setting("bundle_memory_mb", "must be in 1..=4096"));
        }
        if self.bundles == 0 && self.bidir_strategy == BidirStrategy::Bundle {
            return Err(Error::setting(
                "bidir_strategy",
                "strategy `bundle` needs bundles > 0",
            ));
        }
        if !(self.progressive_alpha > 0.0 && self.progressive_alpha < 1.0) {
            return Err(Error::setting("progressive_alpha", "must be in (0, 1)"));
        }
        if !(self.radius_scale.is_finite() && self.radius_scale > 0.0 && self.radius_scale <= 1.0) {
            return Err(Error::setting("radius_scale", "must be in (0, 1]"));
        }
        if self.progressive && self.method == Method::Photon {
            return Err(Error::setting(
                "progressive",
                "method `photon` (k nearest neighbours) has no shrinking kernel: use `gather` or `ispm`",
            ));
        }
        if self.progressive && self.temporal_frames > 1 {
            return Err(Error::setting(
                "progressive",
                "passes are independent estimates: use temporal_frames = 1",
            ));
        }
        Ok(())
    }
}

/// Checks that the images of a frame fit in memory: the outputs (six RGB images and the
/// depth, 76 bytes a pixel), the per-pixel intermediates of the CPU methods, and the render
/// targets and readbacks of the GPU methods (G-buffer, accumulation, copies).
pub(crate) fn check_image_memory(camera: &crate::scene::Camera, method: Method) -> Result<()> {
    let per_pixel: u64 = match method {
        Method::Direct | Method::Ispm | Method::Bidir => 400,
        _ => 160,
    };
    let pixels = camera.width as u64 * camera.height as u64;
    crate::memory::check(
        || format!("the images of a {}x{} frame", camera.width, camera.height),
        pixels * per_pixel,
    )
}
