//! What a frame returns: its images and statistics.

use crate::image::Image;
use crate::scene::Scene;
use crate::trace::path::FirstHitImages;

/// Timings and counts of one render.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RenderStats {
    /// The method's name.
    pub method: String,
    /// (stage name, seconds), in execution order.
    pub stages: Vec<(String, f64)>,
    pub total_seconds: f64,
    pub samples_per_pixel: u32,
    /// Camera paths traced: `path`'s; `ispm`'s through mirrors and glass (0 in a frame that
    /// reused the last frame's, see [`crate::photon::specular::specular_paths`]).
    pub camera_paths: u64,
    pub light_paths: u64,
    pub triangles: u64,
    /// Method `ispm`: bounce-map texels that hit the scene and photons aimed at mirrors and
    /// glass (the `photon_focus` option, `RefineOptions::photon_focus`): the photons emitted from the lights.
    pub photons_emitted: u64,
    /// Method `ispm`: photons that survived the first (bounce-map) scatter.
    pub photons_first_bounce: u64,
    /// Method `ispm`: photons stored (and splatted as volumes), bounce 1 and later.
    pub photons_stored: u64,
    /// Method `ispm`: stored photons of caustic paths (light → mirrors/glass → here), traced
    /// this frame.
    pub caustic_photons: u64,
    /// Method `ispm`: stored photons whose volumes were drawn as quads (the rest as
    /// icosahedra; see the `volume_shape` option, `IspmOptions::volume_shape`).
    pub volume_quads: u64,
    /// Passes averaged into the radiance: 1, or in progressive mode the passes since the
    /// last change.
    pub passes: u64,
    /// Method `ispm`: the indirect estimator that ran, and why it was chosen.
    pub estimator: String,
    pub estimator_reason: String,
    /// Method `ispm`: where the first hits were found ("raster", "traced"), and why.
    pub first_bounce: String,
    pub first_bounce_reason: String,
    /// Method `ispm`: where the later bounces were traced ("cpu", "gpu"), and why.
    pub photon_trace: String,
    pub photon_trace_reason: String,
    /// Method `ispm`, GPU-traced photons: "gpu" when the estimator took the record buffer on
    /// the GPU (no photon readback), "readback: why" when a CPU step needed the photons;
    /// empty when traced on the CPU.
    pub photon_records: String,
    /// Method `ispm`: GPU memory of the estimator beyond its targets (bytes by part).
    pub estimator_memory: Vec<(String, u64)>,
    /// Method `ispm`, estimators `tiled` and `cluster`: photon-list entries written, and of
    /// them the cluster hierarchy's trivial accepts (a photon for a whole node).
    pub list_entries: u64,
    pub trivial_accepts: u64,
    /// Method `bidir`: virtual point lights of the frame (all lights).
    pub vpls: u64,
    /// Method `bidir`: ray bundles of the frame, the fragments they stored in their lists,
    /// and the fragments dropped because the list memory (`bundle_memory_mb`) was full.
    pub bundles: u64,
    pub bundle_fragments: u64,
    pub bundle_overflow: u64,
}

/// A rendered frame: radiance and auxiliary images, all `width × height`; an image not
/// asked for is empty (0 × 0, or no pixels).
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// Pixel radiance, W·sr⁻¹·m⁻² per channel (the box-filtered mean over each pixel); empty
    /// unless the frame's [`super::readout::Readout`] asks for 32-bit floats.
    pub radiance: Image,
    /// The radiance as half floats (RGB, 3 a pixel, rows top first), when asked for.
    pub radiance_half: Option<Vec<half::f16>>,
    /// The tone-mapped 8-bit sRGB display image (RGB, 3 bytes a pixel, rows top first),
    /// when asked for ([`super::readout::Display`]).
    pub display: Option<Vec<u8>>,
    /// First-hit scatter probability (reflectance) as seen from the camera.
    pub albedo: Image,
    /// First-hit shading normal, facing the camera; zero on a miss.
    pub normal: Image,
    /// First-hit world position; zero on a miss.
    pub position: Image,
    /// First-hit view-space depth (distance along the camera's axis), 0 on a miss.
    pub depth: Vec<f32>,
    /// The light-traced (caustic) part of `radiance`, already included in it.
    pub caustics: Image,
    /// Further method-specific images by name (method `ispm`: "direct", "indirect" and
    /// "photons", a visualization of where stored photons land).
    pub aovs: Vec<(String, Image)>,
    pub stats: RenderStats,
}

impl RenderStats {
    /// The statistics of a frame of `scene` before its first stage.
    pub fn of(scene: &Scene) -> RenderStats {
        RenderStats {
            triangles: scene.triangle_count() as u64,
            ..Default::default()
        }
    }
}

impl RenderOutput {
    /// A frame of a CPU method: its radiance (the light-traced `caustics` included) and
    /// first-hit images.
    pub fn of_cpu(
        radiance: Image,
        first: FirstHitImages,
        caustics: Image,
        stats: RenderStats,
    ) -> RenderOutput {
        RenderOutput {
            radiance,
            radiance_half: None,
            display: None,
            albedo: first.albedo,
            normal: first.normal,
            position: first.position,
            depth: first.depth,
            caustics,
            aovs: Vec::new(),
            stats,
        }
    }
}
