//! The table of render options: [`OPTIONS`], one row per option with its kind and range,
//! default, methods and doc, and the checks of values against it.

use super::values::Value;
use super::{
    BidirStrategy, Estimator, FirstBounce, Kernel, Method, PhotonTrace, SpecularSampling,
    VolumeShape, MAX_AREA_SAMPLES, MAX_BUNDLES, MAX_IMAGE_SIDE, MAX_K, MAX_LIGHT_PATHS,
    MAX_PHOTONS, MAX_SKY_SAMPLES, MAX_SPP, MAX_TEMPORAL_FRAMES, MAX_VPLS_PER_LIGHT,
};
use crate::error::{Error, Named, Result};

/// What values an option takes.
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    Bool,
    /// An integer in `min..=max`.
    Int {
        min: i128,
        max: i128,
    },
    /// A finite number between `min` and `max`, each bound included unless `open`.
    Float {
        min: f64,
        min_open: bool,
        max: f64,
        max_open: bool,
    },
    /// One of the names `choices()` lists.
    Choice(fn() -> Vec<&'static str>),
    /// Any text.
    Text,
}

/// The names of a [`Named`] choice (for [`Kind::Choice`]).
fn names<T: Named>() -> Vec<&'static str> {
    T::all().iter().map(|v| v.name()).collect()
}

/// An option's default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Default {
    /// "Automatic": the doc says what that means.
    None,
    Bool(bool),
    Int(i128),
    Float(f64),
    Str(&'static str),
}

impl Default {
    pub fn value(self) -> Value {
        match self {
            Default::None => Value::None,
            Default::Bool(b) => Value::Bool(b),
            Default::Int(i) => Value::Int(i),
            Default::Float(x) => Value::Float(x),
            Default::Str(s) => Value::Str(s.to_string()),
        }
    }
}

/// One row of [`OPTIONS`].
#[derive(Clone, Copy, Debug)]
pub struct OptionSpec {
    pub name: &'static str,
    pub kind: Kind,
    /// Whether `None` ("automatic") is allowed; the default then is `None`.
    pub optional: bool,
    pub default: Default,
    pub methods: &'static [Method],
    /// One line: what the option does, in what unit, and what `None` means where allowed.
    pub doc: &'static str,
}

use Method::{Bidir, Direct, Gather, Ispm, Path, Photon};
const ALL: &[Method] = Method::ALL;
const GPU: &[Method] = &[Direct, Ispm, Bidir];
const CPU_CAMERA: &[Method] = &[Path, Photon, Gather];
const PHOTONS: &[Method] = &[Photon, Gather, Ispm];
const DEPTH: &[Method] = &[Path, Photon, Gather, Ispm, Bidir];
const REFINED: &[Method] = &[Gather, Ispm];
const PROGRESSIVE: &[Method] = &[Path, Photon, Gather, Direct, Ispm, Bidir];

const fn int(min: i128, max: i128) -> Kind {
    Kind::Int { min, max }
}
const fn closed(min: f64, max: f64) -> Kind {
    Kind::Float {
        min,
        min_open: false,
        max,
        max_open: false,
    }
}
const fn open_closed(min: f64, max: f64) -> Kind {
    Kind::Float {
        min,
        min_open: true,
        max,
        max_open: false,
    }
}
const fn open(min: f64, max: f64) -> Kind {
    Kind::Float {
        min,
        min_open: true,
        max,
        max_open: true,
    }
}
const fn row(
    name: &'static str,
    kind: Kind,
    default: Default,
    methods: &'static [Method],
    doc: &'static str,
) -> OptionSpec {
    OptionSpec {
        name,
        kind,
        optional: matches!(default, Default::None),
        default,
        methods,
        doc,
    }
}

/// Every render option. A name may have two rows when it means different things to
/// different methods (`spp`: camera samples for the CPU methods, direct-light samples for
/// the GPU ones); a method sees at most one row of each name.
pub const OPTIONS: &[OptionSpec] = &[
    row(
        "width",
        int(1, MAX_IMAGE_SIDE as i128),
        Default::None,
        ALL,
        "image width in pixels (None: the scene camera's)",
    ),
    row(
        "height",
        int(1, MAX_IMAGE_SIDE as i128),
        Default::None,
        ALL,
        "image height in pixels (None: the scene camera's)",
    ),
    row(
        "seed",
        int(0, u64::MAX as i128),
        Default::Int(0),
        ALL,
        "random seed (frames of a Renderer with temporal reuse vary it per frame)",
    ),
    row(
        "spp",
        int(1, MAX_SPP as i128),
        Default::Int(64),
        CPU_CAMERA,
        "camera samples per pixel",
    ),
    row(
        "spp",
        int(1, MAX_SPP as i128),
        Default::Int(16),
        GPU,
        "direct-light samples per pixel, taken at silhouettes, creases and material edges \
         (16: within 0.5% of 64's error, docs/bench/defaults.md)",
    ),
    row(
        "max_depth",
        int(1, 1024),
        Default::Int(64),
        DEPTH,
        "most scattering events on a path (1: direct light only)",
    ),
    row(
        "light_paths",
        int(0, MAX_LIGHT_PATHS as i128),
        Default::None,
        &[Path],
        "light paths traced for caustics (None: one per camera sample)",
    ),
    row(
        "light_vertices",
        Kind::Bool,
        Default::Bool(true),
        &[Path],
        "also connect each camera path to one light vertex (where a ray from a point or spot \
         light or an emitter lands), by multiple importance sampling: 1.2-1.75x the \
         efficiency in closed rooms, 0.8-0.9x in open scenes whose noise is their caustics \
         (docs/bench/path-vs-mitsuba.md)",
    ),
    row(
        "photons",
        int(1, MAX_PHOTONS as i128),
        Default::Int(200_000),
        PHOTONS,
        "photons emitted from the lights (ispm: the first-bounce budget, split by power)",
    ),
    row(
        "k",
        int(1, MAX_K as i128),
        Default::Int(100),
        &[Photon, Ispm],
        "photons per k-nearest-neighbour estimate (ispm: the gather behind mirrors and glass)",
    ),
    row(
        "max_radius",
        open(0.0, f64::INFINITY),
        Default::None,
        PHOTONS,
        "largest photon kernel radius in metres (None: 5% of the scene's diagonal for the \
         k-NN gathers, 10% for footprints)",
    ),
    row(
        "kernel",
        Kind::Choice(names::<Kernel>),
        Default::Str("cone"),
        PHOTONS,
        "density estimation kernel of the photon gathers",
    ),
    row(
        "smoothing",
        open_closed(0.0, 100.0),
        Default::Float(1.0),
        REFINED,
        "footprint scale s of photon differentials (gather: each shading point gathers about \
         30·s² diffuse photons with the final gather, 240·s² without, whatever the scene and \
         photon count; ispm: the scale of footprint_volumes)",
    ),
    row(
        "leaf_size",
        int(1, 4096),
        Default::None,
        &[Gather],
        "footprints per photon-map BVH leaf (None: the automatic T_auto)",
    ),
    row(
        "final_gather",
        Kind::Bool,
        Default::Bool(true),
        &[Gather],
        "indirect light by one BSDF ray per camera sample into the photon map (a final \
         gather; False: the photon map read at the surface seen, blotchier and faster)",
    ),
    row(
        "adapter",
        Kind::Text,
        Default::None,
        GPU,
        "GPU adapter: \"cpu\" (lavapipe), \"gpu\" or part of its name (None: GI_ADAPTER, \
         else a real GPU when present, else lavapipe)",
    ),
    row(
        "shadow_map_size",
        int(16, 16384),
        Default::Int(1024),
        GPU,
        "shadow-map texels per side",
    ),
    row(
        "edge_supersampling",
        Kind::Bool,
        Default::Bool(true),
        GPU,
        "supersample the direct light only where the pixel's neighbourhood crosses an edge \
         (False: every pixel, a full-screen pass per sample, 6-9x slower, same image to ~1e-4)",
    ),
    row(
        "area_samples",
        int(1, MAX_AREA_SAMPLES as i128),
        Default::Int(16),
        GPU,
        "points drawn on the emitting surfaces by power for the direct light, each an \
         oriented point light with a cube shadow map of shadow_map_size/4 (new points per \
         progressive pass)",
    ),
    row(
        "sky_samples",
        int(1, MAX_SKY_SAMPLES as i128),
        Default::Int(64),
        &[Direct, Ispm],
        "directions drawn from the environment for the direct light, each a distant light with \
         an orthographic shadow map of shadow_map_size/4, softened over the cone it stands for \
         (new ones per progressive pass; 64: frame means of a sky through a window within 2% \
         across seeds, 16: 11%, docs/bench/sky-openings.md)",
    ),
    row(
        "kernel_scale",
        open_closed(0.0, 1000.0),
        Default::Float(1.0),
        &[Ispm],
        "scale of the photon-volume radii",
    ),
    row(
        "subsample",
        int(1, 8),
        Default::Int(2),
        &[Ispm],
        "splat the indirect light at 1/subsample resolution, joint-bilaterally upsampled",
    ),
    row(
        "footprint_volumes",
        Kind::Bool,
        Default::Bool(false),
        &[Ispm],
        "size photon volumes by photon-differential footprints instead of path density",
    ),
    row(
        "boundary_compensation",
        Kind::Bool,
        Default::Bool(true),
        REFINED,
        "divide each photon's power by the share of its kernel on surfaces (probe rays)",
    ),
    row(
        "caustic_density_bound",
        Kind::Bool,
        Default::Bool(true),
        REFINED,
        "keep caustic kernels within 0.75-1.5x the distance to the 16th nearest caustic photon",
    ),
    row(
        "photon_focus",
        closed(0.0, 0.95),
        Default::Float(0.25),
        REFINED,
        "share of each light's photons aimed at mirrors and glass (weighted, image unchanged)",
    ),
    row(
        "volume_shape",
        Kind::Choice(names::<VolumeShape>),
        Default::Str("auto"),
        &[Ispm],
        "shape drawn per photon volume (auto: quads under 16 px, else icosahedra); cost only",
    ),
    row(
        "estimator",
        Kind::Choice(names::<Estimator>),
        Default::Str("auto"),
        &[Ispm],
        "how photons are splatted (auto: per adapter, stats.estimator_reason says why)",
    ),
    row(
        "first_bounce",
        Kind::Choice(names::<FirstBounce>),
        Default::Str("auto"),
        &[Ispm],
        "where photons' first hits are found: bounce maps or the CPU BVH (auto: per adapter)",
    ),
    row(
        "photon_trace",
        Kind::Choice(names::<PhotonTrace>),
        Default::Str("auto"),
        &[Ispm],
        "where photons are traced after their first scatter: cpu or gpu (auto: CPU on CPU devices)",
    ),
    row(
        "temporal_frames",
        int(1, MAX_TEMPORAL_FRAMES as i128),
        Default::Int(1),
        &[Ispm],
        "splat the photons of the last N frames of a Renderer (1: no reuse, coherent noise)",
    ),
    row(
        "specular_sampling",
        Kind::Choice(names::<SpecularSampling>),
        Default::Str("adaptive"),
        &[Ispm, Bidir],
        "how mirrors and glass seen by the camera are traced: adaptively or spp paths a pixel",
    ),
    row(
        "progressive",
        Kind::Bool,
        Default::Bool(false),
        PROGRESSIVE,
        "each frame is a pass of progressive photon mapping, the image their running mean \
         (not method photon: its k-NN kernel does not shrink)",
    ),
    row(
        "progressive_alpha",
        open(0.0, 1.0),
        Default::Float(0.7),
        PROGRESSIVE,
        "progressive radius reduction: r²(i+1) = r²(i)·(i + α)/(i + 1) \
         (not method photon: it has no progressive mode)",
    ),
    row(
        "vpls_per_light",
        int(1, MAX_VPLS_PER_LIGHT as i128),
        Default::Int(64),
        &[Bidir],
        "virtual point lights drawn per light and frame from its reflective shadow map",
    ),
    row(
        "rsm_size",
        int(1, 4096),
        Default::Int(64),
        &[Bidir],
        "reflective-shadow-map texels a side per view for a light of average power",
    ),
    row(
        "vpl_shadow_map_size",
        int(16, 4096),
        Default::Int(128),
        &[Bidir],
        "cube shadow-map texels per face side of each VPL",
    ),
    row(
        "bundles",
        int(0, MAX_BUNDLES as i128),
        Default::Int(16),
        &[Bidir],
        "global ray bundles per frame (0: VPLs only)",
    ),
    row(
        "bundle_resolution",
        int(16, 4096),
        Default::Int(128),
        &[Bidir],
        "ray-bundle pixels a side",
    ),
    row(
        "bundle_memory_mb",
        int(1, 4096),
        Default::Int(64),
        &[Bidir],
        "MiB for the bundles' fragment lists (overflow is dropped and counted in stats)",
    ),
    row(
        "bidir_strategy",
        Kind::Choice(names::<BidirStrategy>),
        Default::Str("mis"),
        &[Bidir],
        "one-bounce light by MIS of VPLs and bundles, or one strategy alone",
    ),
    row(
        "roughness_clamping",
        Kind::Bool,
        Default::Bool(true),
        &[Bidir],
        "widen glossy lobes where samples are too sparse for their peak (Tokuyoshi & Ogaki §5)",
    ),
];

/// The row of option `name` that `method` sees, if any.
pub fn spec(name: &str, method: Method) -> Option<&'static OptionSpec> {
    OPTIONS
        .iter()
        .find(|s| s.name == name && s.methods.contains(&method))
}

/// A value checked against its row.
pub(super) fn check(spec: &OptionSpec, value: &Value) -> Result<Value> {
    let name = spec.name;
    let bad = |what: String| Error::setting(name, what);
    match (&spec.kind, value) {
        (_, Value::None) if spec.optional => Ok(Value::None),
        (_, Value::None) => Err(bad(format!(
            "must be {}, not None",
            describe_kind(&spec.kind)
        ))),
        (Kind::Bool, Value::Bool(b)) => Ok(Value::Bool(*b)),
        (Kind::Int { min, max }, Value::Int(i)) => {
            if (*min..=*max).contains(i) {
                Ok(Value::Int(*i))
            } else {
                Err(bad(format!("must be in {min}..={max}, got {i}")))
            }
        }
        (Kind::Int { .. }, Value::Float(x)) if x.fract() == 0.0 && x.is_finite() => {
            check(spec, &Value::Int(*x as i128))
        }
        (
            Kind::Float {
                min,
                min_open,
                max,
                max_open,
            },
            Value::Float(_) | Value::Int(_),
        ) => {
            let x = match value {
                Value::Int(i) => *i as f64,
                Value::Float(x) => *x,
                _ => unreachable!(),
            };
            let above = if *min_open { x > *min } else { x >= *min };
            let below = if *max_open { x < *max } else { x <= *max };
            if x.is_finite() && above && below {
                Ok(Value::Float(x))
            } else {
                Err(bad(format!(
                    "must be {}, got {x}",
                    describe_kind(&spec.kind)
                )))
            }
        }
        (Kind::Choice(choices), Value::Str(s)) => {
            let choices = choices();
            if choices.contains(&s.as_str()) {
                Ok(Value::Str(s.clone()))
            } else {
                Err(bad(format!(
                    "unknown {} `{s}` (available: {})",
                    name.replace('_', " "),
                    choices.join(", ")
                )))
            }
        }
        (Kind::Text, Value::Str(s)) => Ok(Value::Str(s.clone())),
        (kind, v) => Err(bad(format!("must be {}, got {v}", describe_kind(kind)))),
    }
}

/// The values an option of `kind` takes, in words.
pub fn describe_kind(kind: &Kind) -> String {
    match kind {
        Kind::Bool => "a bool".into(),
        Kind::Int { min, max } => format!("an integer in {min}..={max}"),
        Kind::Float {
            min,
            min_open,
            max,
            max_open,
        } => {
            let lo = if *min_open { '(' } else { '[' };
            let hi = if *max_open { ')' } else { ']' };
            let max = if max.is_infinite() {
                "inf".to_string()
            } else {
                max.to_string()
            };
            format!("a number in {lo}{min}, {max}{hi}")
        }
        Kind::Choice(choices) => format!("one of {}", choices().join(", ")),
        Kind::Text => "a string".into(),
    }
}
