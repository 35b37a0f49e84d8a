//! GPU-facing data: `#[repr(C)]` Pod mirrors of the structs in `shaders/common/types.wgsl`.

use crate::bsdf::{coated, Distribution, Material};
use crate::scene::light_views::LightView;
use crate::scene::Light;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

/// `Material` in WGSL: 64 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct MaterialRaw {
    pub diffuse: [f32; 3],
    pub roughness: f32,
    pub specular: [f32; 3],
    pub fresnel: u32,
    pub transmission: [f32; 3],
    pub ior: f32,
    /// Emitted radiance of the front face (W·sr⁻¹·m⁻²).
    pub emission: [f32; 3],
    /// Bit 0: the back face emits too; bit 1: the back face reflects and transmits nothing
    /// ([`Material::one_sided`]; `MATERIAL_*` in `types.wgsl`).
    pub two_sided: u32,
}

impl Material {
    /// The GPU's copy: the uber parameters of [`Material::uber_equivalent`] (the GPU
    /// passes shade the uber BSDF only).
    pub fn to_raw(&self) -> MaterialRaw {
        let m = self.uber_equivalent();
        m.uber_raw()
    }

    fn uber_raw(&self) -> MaterialRaw {
        MaterialRaw {
            diffuse: self.diffuse.into(),
            roughness: self.roughness,
            specular: self.specular.into(),
            fresnel: self.fresnel as u32,
            transmission: self.transmission.into(),
            ior: self.ior,
            emission: self.emission.into(),
            two_sided: self.two_sided as u32 | (self.one_sided as u32) << 1,
        }
    }
}

/// `ModelMaterial` of `shaders/common/models.wgsl`: a material as the CPU's
/// [`Material`] holds it (Mitsuba's coated plastics and conductors, Beckmann), for the
/// passes that shade the exact models; one per scene material, beside the uber stand-in
/// [`MaterialRaw`]. 240 bytes.
///
/// Layout (each row 16 bytes): `diffuse` + `flags`, `specular` + `roughness`,
/// `transmission` + `ior`, `conductor_eta` + `coat_eta`, `conductor_k` + `coat_internal`,
/// `conductor_average` + `coat_external_mean`, then the coating's transmittance table,
/// then `stand_in_diffuse` + a pad.
/// A new model (e.g. a rough dielectric) takes the next bit of [`model_flags`] and reuses
/// `roughness`, `ior` and the distribution bit; fields it needs beyond those are appended
/// as whole rows after the table (and `ModelMaterial` in WGSL gains the same).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ModelMaterialRaw {
    pub diffuse: [f32; 3],
    /// [`model_flags`].
    pub flags: u32,
    pub specular: [f32; 3],
    pub roughness: f32,
    pub transmission: [f32; 3],
    pub ior: f32,
    pub conductor_eta: [f32; 3],
    pub coat_eta: f32,
    pub conductor_k: [f32; 3],
    pub coat_internal: f32,
    pub conductor_average: [f32; 3],
    pub coat_external_mean: f32,
    /// The rough coating's T(μ) at μ = i/([`coated::TABLE`] − 1), 4 entries a row.
    pub coat_t: [[f32; 4]; coated::TABLE / 4],
    /// Where a texture varies the diffuse reflectance ([`model_flags::TEX_DIFFUSE`]): the
    /// untextured uber stand-in's diffuse albedo, whose textured value (the stand-in's times
    /// the texel: the G-buffer's, an RSM's, a VPL record's) it divides to give the texel
    /// back (`model_textured` in `models.wgsl`).
    pub stand_in_diffuse: [f32; 3],
    pub _pad: u32,
}

/// Bits of [`ModelMaterialRaw::flags`] (`MODEL_*` in `models.wgsl`).
pub mod model_flags {
    /// Schlick's Fresnel on the uber specular lobe.
    pub const FRESNEL: u32 = 1;
    /// Beckmann's distribution (else GGX).
    pub const BECKMANN: u32 = 2;
    /// A plastic: `diffuse` under a dielectric coating.
    pub const COATED: u32 = 4;
    /// A conductor's Fresnel term of complex index.
    pub const CONDUCTOR: u32 = 8;
    /// The coating's `nonlinear` option.
    pub const NONLINEAR: u32 = 16;
    /// A rough coating (its transmittance from the table).
    pub const ROUGH_COAT: u32 = 32;
    /// A texture varies `diffuse` (`stand_in_diffuse` recovers the texel per sample).
    pub const TEX_DIFFUSE: u32 = 64;
}

impl Material {
    /// The exact model's GPU record (`ModelMaterial` in WGSL).
    pub fn to_model_raw(&self) -> ModelMaterialRaw {
        use model_flags::*;
        let mut raw = ModelMaterialRaw::zeroed();
        raw.diffuse = self.diffuse.into();
        raw.specular = self.specular.into();
        raw.roughness = self.roughness;
        raw.transmission = self.transmission.into();
        raw.ior = self.ior;
        let mut flags = 0;
        if self.fresnel {
            flags |= FRESNEL;
        }
        if self.distribution == Distribution::Beckmann {
            flags |= BECKMANN;
        }
        if let Some(c) = &self.conductor {
            flags |= CONDUCTOR;
            raw.conductor_eta = c.eta.into();
            raw.conductor_k = c.k.into();
            raw.conductor_average = c.average.into();
        }
        if let Some(c) = &self.coating {
            flags |= COATED;
            if c.nonlinear {
                flags |= NONLINEAR;
            }
            if c.rough {
                flags |= ROUGH_COAT;
            }
            raw.coat_eta = c.eta;
            raw.coat_internal = c.internal;
            raw.coat_external_mean = c.external_mean;
            for (i, t) in c.transmittance.iter().enumerate() {
                raw.coat_t[i / 4][i % 4] = *t;
            }
        }
        raw.flags = flags;
        raw
    }
}

/// `Light` in WGSL: 64 bytes. Shadow fields are filled in by the shadow-map pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct LightRaw {
    pub position: [f32; 3],
    /// 0 = point, 1 = spot, 2 = directional.
    pub kind: u32,
    /// Point and spot lights: intensity (W/sr); directional: irradiance (W/m²).
    pub intensity: [f32; 3],
    /// Spot: the inner cone's cosine; directional: the cosine of its disc's half angle.
    pub cos_inner: f32,
    /// Spot: its axis; directional: the way its light travels (the shadow's direction).
    pub direction: [f32; 3],
    pub cos_outer: f32,
    pub first_layer: u32,
    pub layers: u32,
    /// World size of a shadow texel, at unit distance for the perspective views.
    pub texel_scale: f32,
    /// Directional: the world depth of its orthographic shadow view (0 for the others).
    pub depth_extent: f32,
}

impl Light {
    /// The light without its shadow-map fields.
    pub fn to_raw(&self) -> LightRaw {
        let mut raw = LightRaw::zeroed();
        match *self {
            Light::Point {
                position,
                intensity,
            } => {
                raw.position = position.into();
                raw.intensity = intensity.into();
                raw.cos_outer = -2.0;
                raw.cos_inner = -1.0;
            }
            Light::Spot {
                position,
                direction,
                intensity,
                cos_inner,
                cos_outer,
            } => {
                raw.kind = 1;
                raw.position = position.into();
                raw.direction = direction.into();
                raw.intensity = intensity.into();
                raw.cos_inner = cos_inner;
                raw.cos_outer = cos_outer;
            }
            Light::Directional {
                direction,
                irradiance,
                cos_half_angle,
            } => {
                raw.kind = 2;
                raw.direction = direction.into();
                raw.intensity = irradiance.into();
                raw.cos_inner = cos_half_angle;
                raw.cos_outer = cos_half_angle;
            }
        }
        raw
    }
}

/// `View` in WGSL, padded to 256 bytes so that views can be picked by dynamic offset.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ViewRaw {
    pub view_proj: [[f32; 4]; 4],
    pub eye: [f32; 3],
    /// Weight of this view's sample in the accumulated image.
    pub weight: f32,
    /// Clip -> world (the view rays of pixels that no surface covers).
    pub inv_view_proj: [[f32; 4]; 4],
    pub _pad: [f32; 28],
}

impl ViewRaw {
    pub fn new(view_proj: Mat4, eye: Vec3, weight: f32) -> Self {
        ViewRaw {
            view_proj: view_proj.to_cols_array_2d(),
            eye: eye.into(),
            weight,
            inv_view_proj: view_proj.inverse().to_cols_array_2d(),
            _pad: [0.0; 28],
        }
    }
}

/// One vertex of the non-indexed triangle list: position, shading normal, geometric normal
/// (from the winding, the same for the triangle's three vertices), material index, texture
/// coordinates and the triangle's tangent (w: handedness, 0 where the UVs are degenerate).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct VertexRaw {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub geometric_normal: [f32; 3],
    pub material: u32,
    pub uv: [f32; 2],
    pub tangent: [f32; 4],
}

/// One placed object (instance) of the instanced vertex buffer, read per instance by the
/// passes that rasterize the scene (`InstanceIn` of `scene_vertex.wgsl`): object -> world
/// (columns), the normal matrix (inverse transpose of its linear part, columns; `normal[0][3]`
/// is -1 for a mirroring transform, whose tangent handedness flips, else 1) and the material
/// added to the vertex's (its file's per-face offset, or 0).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct InstanceRaw {
    pub model: [[f32; 4]; 4],
    pub normal: [[f32; 4]; 3],
    pub material: u32,
    pub _pad: [u32; 3],
}

/// `BounceView` of `bounce.wgsl`, padded to 256 bytes for dynamic offsets.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct BounceViewRaw {
    pub view_proj: [[f32; 4]; 4],
    pub light_position: [f32; 3],
    pub texel_area: f32,
    pub forward: [f32; 3],
    pub kind: u32,
    pub intensity: [f32; 3],
    pub cos_inner: f32,
    pub spot_direction: [f32; 3],
    pub cos_outer: f32,
    /// Random seed of the frame (its low 32 bits, hashed with the high ones).
    pub seed: u32,
    /// Index of this layer among all bounce-map layers.
    pub layer: u32,
    pub _pad: [f32; 30],
}

impl BounceViewRaw {
    /// Light view number `layer` (among all light views of the frame) of `light`, with the
    /// frame's random seed.
    pub fn new(layer: u32, view: &LightView, light: &Light, seed: u64) -> Self {
        let raw = light.to_raw();
        BounceViewRaw {
            view_proj: view.view_proj.to_cols_array_2d(),
            light_position: view.position.into(),
            texel_area: view.texel_area,
            forward: view.forward.into(),
            kind: raw.kind,
            intensity: raw.intensity,
            cos_inner: raw.cos_inner,
            spot_direction: raw.direction,
            cos_outer: raw.cos_outer,
            seed: (seed ^ (seed >> 32)) as u32,
            layer,
            _pad: [0.0; 30],
        }
    }
}

/// `VolumeParams` of `volume.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct VolumeParamsRaw {
    pub view_proj: [[f32; 4]; 4],
    pub eye: [f32; 3],
    pub r_base: f32,
    pub r_max: f32,
    pub z_ratio: f32,
    pub subsample: u32,
    pub _pad: f32,
}

/// `UpsampleParams` of `upsample.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct UpsampleParamsRaw {
    pub eye: [f32; 3],
    pub subsample: u32,
}
