//! GPU-facing data: `#[repr(C)]` Pod mirrors of the structs in `shaders/common/types.wgsl`.

use crate::bsdf::Material;
use crate::scene::light_views::LightView;
use crate::scene::Light;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

/// `Material` in WGSL: 48 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct MaterialRaw {
    pub diffuse: [f32; 3],
    pub roughness: f32,
    pub specular: [f32; 3],
    pub fresnel: u32,
    pub transmission: [f32; 3],
    pub ior: f32,
}

impl Material {
    pub fn to_raw(&self) -> MaterialRaw {
        MaterialRaw {
            diffuse: self.diffuse.into(),
            roughness: self.roughness,
            specular: self.specular.into(),
            fresnel: self.fresnel as u32,
            transmission: self.transmission.into(),
            ior: self.ior,
        }
    }
}

/// `Light` in WGSL: 64 bytes. Shadow fields are filled in by the shadow-map pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct LightRaw {
    pub position: [f32; 3],
    /// 0 = point, 1 = spot.
    pub kind: u32,
    pub intensity: [f32; 3],
    pub cos_inner: f32,
    pub direction: [f32; 3],
    pub cos_outer: f32,
    pub first_layer: u32,
    pub layers: u32,
    pub texel_scale: f32,
    pub _pad: f32,
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
            // Kind 2: not shaded by the GPU passes yet (they warn).
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
    pub _pad: [f32; 44],
}

impl ViewRaw {
    pub fn new(view_proj: Mat4, eye: Vec3, weight: f32) -> Self {
        ViewRaw {
            view_proj: view_proj.to_cols_array_2d(),
            eye: eye.into(),
            weight,
            _pad: [0.0; 44],
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
