//! The options of each method, read from the table's values: the options every method has
//! ([`Common`]), the narrow groups several methods share, and one struct per method.

use super::values::Values;
use super::{
    BidirStrategy, Estimator, FirstBounce, Kernel, Method, PhotonTrace, SpecularSampling,
    VolumeShape,
};

/// The options of every method: the image, the seed and the progressive mode.
#[derive(Clone, Debug, PartialEq)]
pub struct Common {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub seed: u64,
    pub progressive: bool,
    pub progressive_alpha: f32,
}

impl Common {
    pub(super) fn read(v: &Values) -> Self {
        Common {
            width: v.opt_u32("width"),
            height: v.opt_u32("height"),
            seed: v.u64("seed"),
            progressive: v.bool("progressive"),
            progressive_alpha: v.f32("progressive_alpha"),
        }
    }
}

/// The GPU direct light (`direct`, `ispm`, `bidir`): adapter, samples and shadow maps.
#[derive(Clone, Debug, PartialEq)]
pub struct DirectLightOptions {
    pub adapter: Option<String>,
    /// Sub-pixel samples of the direct light.
    pub spp: u32,
    pub shadow_map_size: u32,
    pub edge_supersampling: bool,
    /// Points drawn on the emitters per frame.
    pub area_samples: u32,
    /// Directions drawn from the sky per frame (not read by `bidir`, whose bundles light
    /// the sky).
    pub sky_samples: u32,
}

impl DirectLightOptions {
    /// The options of `v`; `sky`: the method lights the sky by sampled directions.
    pub(super) fn read(v: &Values, sky: bool) -> Self {
        DirectLightOptions {
            adapter: v.text("adapter"),
            spp: v.u32("spp"),
            shadow_map_size: v.u32("shadow_map_size"),
            edge_supersampling: v.bool("edge_supersampling"),
            area_samples: v.u32("area_samples"),
            sky_samples: if sky { v.u32("sky_samples") } else { 0 },
        }
    }

    /// Side of the sampled lights' shadow maps: a quarter of the lights', at least 64.
    pub fn sample_map_size(&self) -> u32 {
        (self.shadow_map_size / 4).max(64)
    }
}

/// The photon gathers' kernel: its largest radius and its shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelOptions {
    /// `None`: a share of the scene's diagonal.
    pub max_radius: Option<f32>,
    pub kernel: Kernel,
}

impl KernelOptions {
    pub(super) fn read(v: &Values) -> Self {
        KernelOptions {
            max_radius: v.opt_f32("max_radius"),
            kernel: v.choice("kernel"),
        }
    }
}

/// The refinements of `gather`'s and `ispm`'s photons: boundary compensation, the caustic
/// density bound and photon focusing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineOptions {
    pub boundary_compensation: bool,
    pub caustic_density_bound: bool,
    pub photon_focus: f32,
    /// Footprint smoothing of photon differentials.
    pub smoothing: f32,
}

impl RefineOptions {
    pub(super) fn read(v: &Values) -> Self {
        RefineOptions {
            boundary_compensation: v.bool("boundary_compensation"),
            caustic_density_bound: v.bool("caustic_density_bound"),
            photon_focus: v.f32("photon_focus"),
            smoothing: v.f32("smoothing"),
        }
    }
}

/// Method `path`.
#[derive(Clone, Debug, PartialEq)]
pub struct PathOptions {
    pub spp: u32,
    pub max_depth: u32,
    /// `None`: one per camera sample.
    pub light_paths: Option<u64>,
    /// Camera paths also connect to a light vertex ([`crate::trace::light_vertex`]).
    pub light_vertices: bool,
}

/// Method `photon`.
#[derive(Clone, Debug, PartialEq)]
pub struct PhotonOptions {
    pub spp: u32,
    pub max_depth: u32,
    pub photons: u64,
    pub k: u32,
    pub kernel: KernelOptions,
}

/// Method `gather`.
#[derive(Clone, Debug, PartialEq)]
pub struct GatherOptions {
    pub spp: u32,
    pub max_depth: u32,
    pub photons: u64,
    pub kernel: KernelOptions,
    pub refine: RefineOptions,
    /// `None`: the automatic T_auto.
    pub leaf_size: Option<u32>,
    /// Indirect light by one final-gather ray per camera sample into the photon map
    /// ([`crate::photon::final_gather`]); `false`: the map read where the camera looks.
    pub final_gather: bool,
}

/// Method `direct`.
#[derive(Clone, Debug, PartialEq)]
pub struct DirectOptions {
    pub direct: DirectLightOptions,
}

/// Method `ispm`.
#[derive(Clone, Debug, PartialEq)]
pub struct IspmOptions {
    pub direct: DirectLightOptions,
    pub max_depth: u32,
    pub photons: u64,
    pub k: u32,
    pub kernel: KernelOptions,
    pub refine: RefineOptions,
    pub kernel_scale: f32,
    pub subsample: u32,
    pub footprint_volumes: bool,
    pub volume_shape: VolumeShape,
    pub estimator: Estimator,
    pub first_bounce: FirstBounce,
    pub photon_trace: PhotonTrace,
    pub temporal_frames: u32,
    pub specular_sampling: SpecularSampling,
}

/// Method `bidir`.
#[derive(Clone, Debug, PartialEq)]
pub struct BidirOptions {
    pub direct: DirectLightOptions,
    pub max_depth: u32,
    pub vpls_per_light: u32,
    pub rsm_size: u32,
    pub vpl_shadow_map_size: u32,
    pub bundles: u32,
    pub bundle_resolution: u32,
    pub bundle_memory_mb: u32,
    pub strategy: BidirStrategy,
    pub roughness_clamping: bool,
    pub specular_sampling: SpecularSampling,
}

/// The options of one method.
#[derive(Clone, Debug, PartialEq)]
pub enum MethodOptions {
    Path(PathOptions),
    Photon(PhotonOptions),
    Gather(GatherOptions),
    Direct(DirectOptions),
    Ispm(IspmOptions),
    Bidir(BidirOptions),
}

impl MethodOptions {
    /// The options of `method` from the table's values.
    pub fn read(method: Method, v: &Values) -> MethodOptions {
        match method {
            Method::Path => MethodOptions::Path(PathOptions {
                spp: v.u32("spp"),
                max_depth: v.u32("max_depth"),
                light_paths: v.opt_u64("light_paths"),
                light_vertices: v.bool("light_vertices"),
            }),
            Method::Photon => MethodOptions::Photon(PhotonOptions {
                spp: v.u32("spp"),
                max_depth: v.u32("max_depth"),
                photons: v.u64("photons"),
                k: v.u32("k"),
                kernel: KernelOptions::read(v),
            }),
            Method::Gather => MethodOptions::Gather(GatherOptions {
                spp: v.u32("spp"),
                max_depth: v.u32("max_depth"),
                photons: v.u64("photons"),
                kernel: KernelOptions::read(v),
                refine: RefineOptions::read(v),
                leaf_size: v.opt_u32("leaf_size"),
                final_gather: v.bool("final_gather"),
            }),
            Method::Direct => MethodOptions::Direct(DirectOptions {
                direct: DirectLightOptions::read(v, true),
            }),
            Method::Ispm => MethodOptions::Ispm(IspmOptions {
                direct: DirectLightOptions::read(v, true),
                max_depth: v.u32("max_depth"),
                photons: v.u64("photons"),
                k: v.u32("k"),
                kernel: KernelOptions::read(v),
                refine: RefineOptions::read(v),
                kernel_scale: v.f32("kernel_scale"),
                subsample: v.u32("subsample"),
                footprint_volumes: v.bool("footprint_volumes"),
                volume_shape: v.choice("volume_shape"),
                estimator: v.choice("estimator"),
                first_bounce: v.choice("first_bounce"),
                photon_trace: v.choice("photon_trace"),
                temporal_frames: v.u32("temporal_frames"),
                specular_sampling: v.choice("specular_sampling"),
            }),
            Method::Bidir => MethodOptions::Bidir(BidirOptions {
                direct: DirectLightOptions::read(v, false),
                max_depth: v.u32("max_depth"),
                vpls_per_light: v.u32("vpls_per_light"),
                rsm_size: v.u32("rsm_size"),
                vpl_shadow_map_size: v.u32("vpl_shadow_map_size"),
                bundles: v.u32("bundles"),
                bundle_resolution: v.u32("bundle_resolution"),
                bundle_memory_mb: v.u32("bundle_memory_mb"),
                strategy: v.choice("bidir_strategy"),
                roughness_clamping: v.bool("roughness_clamping"),
                specular_sampling: v.choice("specular_sampling"),
            }),
        }
    }

    pub fn method(&self) -> Method {
        match self {
            MethodOptions::Path(_) => Method::Path,
            MethodOptions::Photon(_) => Method::Photon,
            MethodOptions::Gather(_) => Method::Gather,
            MethodOptions::Direct(_) => Method::Direct,
            MethodOptions::Ispm(_) => Method::Ispm,
            MethodOptions::Bidir(_) => Method::Bidir,
        }
    }

    /// The GPU direct light's options (the GPU methods).
    pub fn direct_light(&self) -> Option<&DirectLightOptions> {
        match self {
            MethodOptions::Direct(o) => Some(&o.direct),
            MethodOptions::Ispm(o) => Some(&o.direct),
            MethodOptions::Bidir(o) => Some(&o.direct),
            _ => None,
        }
    }

    /// Temporal photon reuse: frames whose photons a frame splats (1: none).
    pub fn temporal_frames(&self) -> u32 {
        match self {
            MethodOptions::Ispm(o) => o.temporal_frames,
            _ => 1,
        }
    }
}

macro_rules! method_defaults {
    ($($t:ident => $m:ident),* $(,)?) => {$(
        /// The table's defaults.
        impl std::default::Default for $t {
            fn default() -> Self {
                match MethodOptions::read(Method::$m, &Values::defaults(Method::$m)) {
                    MethodOptions::$m(o) => o,
                    _ => unreachable!(),
                }
            }
        }
    )*};
}
method_defaults!(
    PathOptions => Path,
    PhotonOptions => Photon,
    GatherOptions => Gather,
    DirectOptions => Direct,
    IspmOptions => Ispm,
    BidirOptions => Bidir,
);
