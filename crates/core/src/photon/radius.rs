//! The kernel radii of ISPM's photon volumes: a base radius from the scene's area and the
//! photon count, widened by each photon's path density (McGuire & Luebke 2009, section 5.1),
//! and the volumes' flattening along the surface normal.

use crate::photon::Photon;
use crate::scene::Scene;

/// r_z / r_xy of the photon volumes.
pub const Z_RATIO: f32 = 0.5;

/// Radius (m) of a photon volume of path density 1: `kernel_scale`·√(scene area / photons).
pub fn base_radius(scene: &Scene, photons: u64, kernel_scale: f32) -> f32 {
    let area = scene.surface_area();
    (kernel_scale as f64 * (area / photons.max(1) as f64).sqrt()) as f32
}

/// Photon-volume radius ∝ ρp^(−α) ([`VolumeRadius::of`]).
pub(crate) const DENSITY_EXPONENT: f32 = 0.35;
/// Largest widening of a photon volume over the base radius ([`VolumeRadius::of`]).
pub(crate) const MAX_WIDENING: f32 = 12.0;

/// The radii of the photon volumes. Method `ispm` stores each photon's radius in
/// `Photon::footprint_radius` before the splat, so `volume.wgsl` reads it from there.
#[derive(Clone, Copy, Debug)]
pub struct VolumeRadius {
    /// Radius (m) of a photon of path density 1.
    pub r_base: f32,
    /// Largest radius (m).
    pub r_max: f32,
}

/// What the volume radii read from a scene, in one pass over its meshes: its surface area
/// and bounding-box diagonal. A frame makes it once ([`SceneExtent::of`]) and derives every
/// radius it needs from it ([`VolumeRadius::of_extent`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneExtent {
    /// Total surface area (m²).
    pub area: f64,
    /// Length of the bounding box's diagonal (m).
    pub diagonal: f32,
}

thread_local! {
    static EXTENT_PASSES: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

impl SceneExtent {
    /// The extent of `scene` (a pass over its meshes; counted per thread, [`Self::passes`]).
    pub fn of(scene: &Scene) -> SceneExtent {
        EXTENT_PASSES.with(|n| n.set(n.get() + 1));
        let (lo, hi) = crate::scene::light_views::bounds(scene);
        SceneExtent {
            area: scene.surface_area(),
            diagonal: (hi - lo).length(),
        }
    }

    /// How many extents this thread has made: the tests read it around a frame (a frame of
    /// method `ispm` makes one).
    pub fn passes() -> u64 {
        EXTENT_PASSES.with(|n| n.get())
    }
}

impl VolumeRadius {
    /// The radii of method `ispm` for `scene`: `r_base` from [`base_radius`],
    /// `r_max` a tenth of the scene's bounding-box diagonal.
    pub fn of_scene(scene: &Scene, photons: u64, kernel_scale: f32) -> Self {
        Self::of_extent(SceneExtent::of(scene), photons, kernel_scale)
    }

    /// [`Self::of_scene`] from the scene's `extent`, made once.
    pub fn of_extent(extent: SceneExtent, photons: u64, kernel_scale: f32) -> Self {
        let r_base = (kernel_scale as f64 * (extent.area / photons.max(1) as f64).sqrt()) as f32;
        VolumeRadius {
            r_base,
            r_max: (0.1 * extent.diagonal).max(r_base),
        }
    }

    /// Every radius times `s` (the progressive mode's shrinking kernels).
    pub fn scaled(self, s: f32) -> Self {
        VolumeRadius {
            r_base: self.r_base * s,
            r_max: self.r_max * s,
        }
    }

    /// The radius of a photon after a Lambertian bounce without footprint (the widest,
    /// r_base·G capped at r_max): that of most of the indirect light's kernels.
    pub fn diffuse(&self) -> f32 {
        (self.r_base * MAX_WIDENING).min(self.r_max)
    }

    /// The ellipsoid's radius in the surface plane (m), also the radius of a sphere around it
    /// (the normal axis is shorter): the footprint when traced with differentials, else
    /// from the path density (section 5.1), r_base·clamp(ρp^(−α), 1, G). Dense (caustic)
    /// paths get the base radius; one Lambertian bounce (ρp = ρL/1000 ≈ 7·10⁻⁴) widens it
    /// to the cap G, glossy ones less. α and G come from `benches/measure/ispm_kernel_sweep.rs` on
    /// cornell with boundary compensation: RMSE against the converged image at 200k photons
    /// falls from 0.0430 at 4× (the earlier α = 0.2, G = 4) to 0.0249 at 12× and flattens
    /// beyond (0.0244 at 16×), the 8×8-block error from 3.15% to 2.67%.
    pub fn of(&self, p: &Photon) -> f32 {
        if p.footprint_radius > 0.0 {
            return p.footprint_radius.min(self.r_max);
        }
        let g = p
            .path_density
            .max(1e-30)
            .powf(-DENSITY_EXPONENT)
            .clamp(1.0, MAX_WIDENING);
        (self.r_base * g).min(self.r_max)
    }
}
