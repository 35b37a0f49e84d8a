//! The methods and their options.
//!
//! [`OPTIONS`] is the one table of render options: each row names an option, its kind and
//! range, its default, the methods it applies to and a one-line doc. Everything else is
//! made from it: the per-method option structs ([`RenderOptions::new`] reads them from the
//! table's values, and their `Default`s are the table's defaults), the Python keywords of
//! `gi.render`/`gi.Renderer`, the `gi render` arguments with their `--help`, and the batch
//! job format (`gi._gi.options()` hands the table to Python).
//!
//! Options that vary per frame are not here: the frame's seed, the progressive pass's
//! kernel scale and whether the first-hit images are wanted live in `FrameParams`.

pub mod derived;
mod methods;
mod table;
mod values;

pub use methods::*;
use table::check;
pub use table::{describe_kind, spec, Default, Kind, OptionSpec, OPTIONS};
pub use values::{Value, Values};

use crate::error::{named, Error, Result};
pub use crate::estimate::volume_shape::VolumeShape;
pub use crate::estimate::Estimator;
pub use crate::gpu::photon::PhotonTrace;
pub use crate::photon::bounce::FirstBounce;
pub use crate::photon::delta_paths::SpecularSampling;
pub use crate::photon::Kernel;
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

    /// Whether the method renders on the GPU.
    pub fn uses_gpu(self) -> bool {
        matches!(self, Method::Direct | Method::Ispm | Method::Bidir)
    }

    /// Whether the method traces rays on the CPU (and so needs the CPU BVH): all but
    /// `direct`, which rasterizes everything on the GPU.
    pub fn uses_cpu_bvh(self) -> bool {
        self != Method::Direct
    }

    /// Whether the method traces rays on the CPU in `scene`: `direct` only where mirrors
    /// or glass may be seen and light met one delta scattering from the camera (emitters,
    /// the environment, a sun's disc: `crate::photon::delta_light::can_meet_light`).
    pub fn uses_cpu_bvh_in(self, scene: &crate::scene::Scene) -> bool {
        self.uses_cpu_bvh()
            || (scene.has_specular_traced() && crate::photon::delta_light::can_meet_light(scene))
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

named!(
    Method,
    BidirStrategy,
    Kernel,
    VolumeShape,
    Estimator,
    FirstBounce,
    PhotonTrace,
    SpecularSampling
);

/// Upper bounds that keep absurd requests from exhausting memory or running for days.
pub const MAX_SPP: u32 = 1 << 20;
pub const MAX_LIGHT_PATHS: u64 = 1 << 36;
pub const MAX_PHOTONS: u64 = 1_000_000_000;
pub const MAX_K: u32 = 1 << 16;
pub const MAX_TEMPORAL_FRAMES: u32 = 64;
/// VPLs per light (each takes six shadow-map faces, four a layer).
pub const MAX_VPLS_PER_LIGHT: u32 = 1024;
/// Most points drawn on the emitters per frame (six shadow layers each).
pub const MAX_AREA_SAMPLES: u32 = 128;
/// Most directions drawn from the sky per frame (one shadow layer each).
pub const MAX_SKY_SAMPLES: u32 = 256;
/// Ray bundles per frame.
pub const MAX_BUNDLES: u32 = 4096;
/// Largest image side (pixels).
pub const MAX_IMAGE_SIDE: u32 = 16384;
/// Everything a [`super::Renderer`] is made with: the options every method has and the
/// method's own.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    pub common: Common,
    pub method: MethodOptions,
}

impl RenderOptions {
    /// The options of `method` from `given` (name, value) pairs, checked against
    /// [`OPTIONS`] and validated; also the warnings for options that don't apply to it.
    pub fn new(method: Method, given: &[(String, Value)]) -> Result<(RenderOptions, Vec<String>)> {
        let (values, warnings) = Values::new(method, given)?;
        let options = RenderOptions::read(method, &values);
        options.validate()?;
        Ok((options, warnings))
    }

    /// These options with option `name` set to `value`, checked like [`RenderOptions::new`]
    /// (an option the method doesn't take is an error here).
    pub fn set(&self, name: &str, value: impl Into<Value>) -> Result<RenderOptions> {
        let method = self.method();
        if spec(name, method).is_none() {
            return Err(Error::setting(
                "settings",
                format!("method `{}` takes no option `{name}`", method.name()),
            ));
        }
        let mut given: Vec<(String, Value)> = self
            .values()
            .into_iter()
            .map(|(n, v)| (n.to_string(), v))
            .collect();
        if let Some(slot) = given.iter_mut().find(|(n, _)| n == name) {
            slot.1 = value.into();
        }
        Ok(RenderOptions::new(method, &given)?.0)
    }

    /// [`RenderOptions::set`] for tests, examples and benchmarks: an option the method
    /// doesn't take is ignored (as a sweep over methods sharing options wants), and an
    /// invalid value or an unknown name panics.
    #[track_caller]
    pub fn with(&self, name: &str, value: impl Into<Value>) -> RenderOptions {
        if spec(name, self.method()).is_none() && OPTIONS.iter().any(|s| s.name == name) {
            return self.clone();
        }
        match self.set(name, value) {
            Ok(o) => o,
            Err(e) => panic!("{e}"),
        }
    }

    /// The options of `method` with the values of these where it takes the same option
    /// (the rest its defaults). Panics where they are invalid for `method`: for tests,
    /// examples and benchmarks.
    #[track_caller]
    pub fn with_method(&self, method: Method) -> RenderOptions {
        let given: Vec<(String, Value)> = self
            .values()
            .into_iter()
            .filter(|(n, _)| spec(n, method).is_some())
            .map(|(n, v)| (n.to_string(), v))
            .collect();
        match RenderOptions::new(method, &given) {
            Ok((o, _)) => o,
            Err(e) => panic!("{e}"),
        }
    }

    /// The value of option `name` (`None` where the method doesn't take it).
    pub fn get(&self, name: &str) -> Option<Value> {
        self.values()
            .into_iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| v)
    }

    /// The options of `values`.
    pub fn read(method: Method, values: &Values) -> RenderOptions {
        RenderOptions {
            common: Common::read(values),
            method: MethodOptions::read(method, values),
        }
    }

    /// The table's defaults for `method`.
    pub fn defaults(method: Method) -> RenderOptions {
        RenderOptions::read(method, &Values::defaults(method))
    }

    /// These options with the method's own replaced by `method` (the common ones kept).
    pub fn of(method: MethodOptions) -> RenderOptions {
        RenderOptions {
            common: RenderOptions::defaults(method.method()).common,
            method,
        }
    }

    /// These options at an image size of `width × height`.
    pub fn with_size(mut self, width: u32, height: u32) -> RenderOptions {
        self.common.width = Some(width);
        self.common.height = Some(height);
        self
    }

    /// These options with seed `seed`.
    pub fn with_seed(mut self, seed: u64) -> RenderOptions {
        self.common.seed = seed;
        self
    }

    /// These options in progressive mode.
    pub fn progressive(mut self) -> RenderOptions {
        self.common.progressive = true;
        self
    }

    pub fn method(&self) -> Method {
        self.method.method()
    }

    /// The checks that span several options (each option's own range is the table's, for
    /// options built from it; options built in Rust are checked here too).
    pub fn validate(&self) -> Result<()> {
        let values = self.values();
        for (name, value) in &values {
            if let Some(spec) = spec(name, self.method()) {
                check(spec, value)?;
            }
        }
        let c = &self.common;
        if c.progressive && self.method() == Method::Photon {
            return Err(Error::setting(
                "progressive",
                "method `photon` (k nearest neighbours) has no shrinking kernel: use `gather` \
                 or `ispm`",
            ));
        }
        match &self.method {
            MethodOptions::Ispm(o) if c.progressive && o.temporal_frames > 1 => {
                Err(Error::setting(
                    "progressive",
                    "passes are independent estimates: use temporal_frames = 1",
                ))
            }
            MethodOptions::Bidir(o) if o.bundles == 0 && o.strategy == BidirStrategy::Bundle => {
                Err(Error::setting(
                    "bidir_strategy",
                    "strategy `bundle` needs bundles > 0",
                ))
            }
            _ => Ok(()),
        }
    }

    /// Every option's current value, by name (the inverse of [`RenderOptions::new`]).
    pub fn values(&self) -> Vec<(&'static str, Value)> {
        let int = |i: u64| Value::Int(i as i128);
        let opt_int = |i: Option<u64>| i.map_or(Value::None, int);
        let float = |x: f32| Value::Float(x as f64);
        let name = |s: &'static str| Value::Str(s.to_string());
        let c = &self.common;
        let mut out = vec![
            ("width", opt_int(c.width.map(u64::from))),
            ("height", opt_int(c.height.map(u64::from))),
            ("seed", int(c.seed)),
            ("progressive", Value::Bool(c.progressive)),
            ("progressive_alpha", float(c.progressive_alpha)),
        ];
        let direct = |d: &DirectLightOptions, out: &mut Vec<(&'static str, Value)>| {
            out.push(("adapter", d.adapter.clone().map_or(Value::None, Value::Str)));
            out.push(("spp", int(d.spp as u64)));
            out.push(("shadow_map_size", int(d.shadow_map_size as u64)));
            out.push(("edge_supersampling", Value::Bool(d.edge_supersampling)));
            out.push(("area_samples", int(d.area_samples as u64)));
        };
        // `bidir` lights the sky through its bundles.
        let sky = |d: &DirectLightOptions, out: &mut Vec<(&'static str, Value)>| {
            out.push(("sky_samples", int(d.sky_samples as u64)));
        };
        let kernel = |k: &KernelOptions, out: &mut Vec<(&'static str, Value)>| {
            out.push(("max_radius", k.max_radius.map_or(Value::None, float)));
            out.push(("kernel", name(k.kernel.name())));
        };
        let refine = |r: &RefineOptions, out: &mut Vec<(&'static str, Value)>| {
            out.push((
                "boundary_compensation",
                Value::Bool(r.boundary_compensation),
            ));
            out.push((
                "caustic_density_bound",
                Value::Bool(r.caustic_density_bound),
            ));
            out.push(("photon_focus", float(r.photon_focus)));
            out.push(("smoothing", float(r.smoothing)));
        };
        match &self.method {
            MethodOptions::Path(o) => {
                out.push(("spp", int(o.spp as u64)));
                out.push(("max_depth", int(o.max_depth as u64)));
                out.push(("light_paths", opt_int(o.light_paths)));
                out.push(("light_vertices", Value::Bool(o.light_vertices)));
            }
            MethodOptions::Photon(o) => {
                out.push(("spp", int(o.spp as u64)));
                out.push(("max_depth", int(o.max_depth as u64)));
                out.push(("photons", int(o.photons)));
                out.push(("k", int(o.k as u64)));
                kernel(&o.kernel, &mut out);
            }
            MethodOptions::Gather(o) => {
                out.push(("spp", int(o.spp as u64)));
                out.push(("max_depth", int(o.max_depth as u64)));
                out.push(("photons", int(o.photons)));
                kernel(&o.kernel, &mut out);
                refine(&o.refine, &mut out);
                out.push(("leaf_size", opt_int(o.leaf_size.map(u64::from))));
                out.push(("final_gather", Value::Bool(o.final_gather)));
            }
            MethodOptions::Direct(o) => {
                direct(&o.direct, &mut out);
                sky(&o.direct, &mut out);
            }
            MethodOptions::Ispm(o) => {
                direct(&o.direct, &mut out);
                sky(&o.direct, &mut out);
                out.push(("max_depth", int(o.max_depth as u64)));
                out.push(("photons", int(o.photons)));
                out.push(("k", int(o.k as u64)));
                kernel(&o.kernel, &mut out);
                refine(&o.refine, &mut out);
                out.push(("kernel_scale", float(o.kernel_scale)));
                out.push(("subsample", int(o.subsample as u64)));
                out.push(("footprint_volumes", Value::Bool(o.footprint_volumes)));
                out.push(("volume_shape", name(o.volume_shape.name())));
                out.push(("estimator", name(o.estimator.name())));
                out.push(("first_bounce", name(o.first_bounce.name())));
                out.push(("photon_trace", name(o.photon_trace.name())));
                out.push(("temporal_frames", int(o.temporal_frames as u64)));
                out.push(("specular_sampling", name(o.specular_sampling.name())));
            }
            MethodOptions::Bidir(o) => {
                direct(&o.direct, &mut out);
                out.push(("max_depth", int(o.max_depth as u64)));
                out.push(("vpls_per_light", int(o.vpls_per_light as u64)));
                out.push(("rsm_size", int(o.rsm_size as u64)));
                out.push(("vpl_shadow_map_size", int(o.vpl_shadow_map_size as u64)));
                out.push(("bundles", int(o.bundles as u64)));
                out.push(("bundle_resolution", int(o.bundle_resolution as u64)));
                out.push(("bundle_memory_mb", int(o.bundle_memory_mb as u64)));
                out.push(("bidir_strategy", name(o.strategy.name())));
                out.push(("roughness_clamping", Value::Bool(o.roughness_clamping)));
                out.push(("specular_sampling", name(o.specular_sampling.name())));
            }
        }
        out
    }
}

/// The options of a method from `name: value` pairs, as the Python keywords:
/// `options!(Ispm, photons: 20_000, spp: 4, width: 64, height: 64)`. Panics on an invalid
/// option: for tests, examples and benchmarks.
#[macro_export]
macro_rules! options {
    ($method:ident $(, $name:ident : $value:expr)* $(,)?) => {
        $crate::frame::options::RenderOptions::new(
            $crate::frame::options::Method::$method,
            &[$((stringify!($name).to_string(), $crate::frame::options::Value::from($value))),*],
        )
        .map(|(options, _)| options)
        .expect("valid render options")
    };
}

/// Checks that the images of a frame fit in memory: the outputs (six RGB images and the
/// depth, 76 bytes a pixel), the per-pixel intermediates of the CPU methods, and the render
/// targets and readbacks of the GPU methods (G-buffer, accumulation, copies).
pub(crate) fn check_image_memory(camera: &crate::scene::Camera, method: Method) -> Result<()> {
    let per_pixel: u64 = if method.uses_gpu() { 400 } else { 160 };
    let pixels = camera.width as u64 * camera.height as u64;
    crate::memory::check(
        || format!("the images of a {}x{} frame", camera.width, camera.height),
        pixels * per_pixel,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each method reads exactly the options the table lists for it, and `values()` gives
    /// back every one of them: the table's `methods` column is what the code does.
    #[test]
    fn each_method_reads_exactly_its_options() {
        for &m in Method::ALL {
            let v = Values::defaults(m);
            let o = RenderOptions::read(m, &v);
            let mut read = v.read();
            read.sort();
            read.dedup();
            let mut listed: Vec<&str> = OPTIONS
                .iter()
                .filter(|s| s.methods.contains(&m))
                .map(|s| s.name)
                .collect();
            listed.sort();
            assert_eq!(read, listed, "{}", m.name());
            let mut back: Vec<&str> = o.values().iter().map(|(n, _)| *n).collect();
            back.sort();
            assert_eq!(back, listed, "{}", m.name());
        }
    }

    /// A method sees at most one row of a name; the table's defaults pass their own checks
    /// and round-trip through the typed structs; choice defaults are the enums' defaults.
    #[test]
    fn table_is_consistent() {
        for &m in Method::ALL {
            let mut names: Vec<&str> = OPTIONS
                .iter()
                .filter(|s| s.methods.contains(&m))
                .map(|s| s.name)
                .collect();
            let n = names.len();
            names.sort();
            names.dedup();
            assert_eq!(names.len(), n, "{}: a name twice", m.name());
            let o = RenderOptions::defaults(m);
            o.validate().unwrap();
            for (name, value) in o.values() {
                let default = spec(name, m).unwrap().default.value();
                match (value, default) {
                    // Floats went through f32.
                    (Value::Float(a), Value::Float(b)) => assert_eq!(a as f32, b as f32),
                    (a, b) => assert_eq!(a, b, "{name}"),
                }
            }
        }
        assert_eq!(IspmOptions::default().estimator, Estimator::default());
        assert_eq!(IspmOptions::default().volume_shape, VolumeShape::default());
        assert_eq!(IspmOptions::default().first_bounce, FirstBounce::default());
        assert_eq!(IspmOptions::default().photon_trace, PhotonTrace::default());
        assert_eq!(IspmOptions::default().kernel.kernel, Kernel::default());
        assert_eq!(BidirOptions::default().strategy, BidirStrategy::default());
    }

    #[test]
    fn values_are_checked_and_foreign_options_warned() {
        let given = |pairs: &[(&str, Value)]| -> Vec<(String, Value)> {
            pairs
                .iter()
                .map(|(n, v)| (n.to_string(), v.clone()))
                .collect()
        };
        let (o, w) = RenderOptions::new(
            Method::Ispm,
            &given(&[
                ("photons", Value::Int(1000)),
                ("kernel_scale", Value::Int(2)),
            ]),
        )
        .unwrap();
        assert!(w.is_empty());
        let MethodOptions::Ispm(i) = &o.method else {
            panic!()
        };
        assert_eq!((i.photons, i.kernel_scale), (1000, 2.0));
        let (_, w) =
            RenderOptions::new(Method::Path, &given(&[("subsample", Value::Int(4))])).unwrap();
        assert!(w[0].contains("subsample") && w[0].contains("ispm"), "{w:?}");
        for (name, bad) in [
            ("spp", Value::Int(0)),
            ("spp", Value::Str("4".into())),
            ("spp", Value::Float(2.5)),
            ("kernel", Value::Str("gauss".into())),
            ("seed", Value::Int(-1)),
            ("smoothing", Value::Float(f64::NAN)),
            ("photons", Value::None),
        ] {
            let e = RenderOptions::new(Method::Ispm, &given(&[(name, bad.clone())]))
                .expect_err(name)
                .to_string();
            assert!(e.contains(name), "{e}");
        }
        let e = RenderOptions::new(Method::Ispm, &given(&[("sp", Value::Int(4))]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("spp"), "{e}");
    }
}
