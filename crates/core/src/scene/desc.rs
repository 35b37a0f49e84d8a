//! The JSON scene description (serde). Every field has a unit and a default; unknown fields
//! are errors. See `docs/scene-format.md` for the documented schema.

use serde::{Deserialize, Serialize};

pub type V3 = [f32; 3];

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    pub camera: CameraDesc,
    #[serde(default)]
    pub lights: Vec<LightDesc>,
    #[serde(default)]
    pub materials: std::collections::BTreeMap<String, MaterialDesc>,
    #[serde(default)]
    pub objects: Vec<ObjectDesc>,
    /// Keyframed tracks (see `scene::animation`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub animation: Option<AnimationDesc>,
    /// Light from infinitely far away: an HDR image or a constant (see `scene::environment`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub environment: Option<super::environment::EnvironmentDesc>,
}

/// Pinhole camera.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// Eye position, metres.
    pub position: V3,
    /// Point looked at, metres.
    pub look_at: V3,
    #[serde(default = "default_up")]
    pub up: V3,
    /// Vertical field of view, degrees.
    #[serde(default = "default_fov")]
    pub fov: f32,
    #[serde(default = "default_size")]
    pub width: u32,
    #[serde(default = "default_size")]
    pub height: u32,
}

fn default_up() -> V3 {
    [0.0, 1.0, 0.0]
}
fn default_fov() -> f32 {
    40.0
}
fn default_size() -> u32 {
    512
}

/// A light: intensity in W/sr per RGB channel.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum LightDesc {
    Point {
        position: V3,
        intensity: V3,
    },
    Spot {
        position: V3,
        direction: V3,
        intensity: V3,
        /// Half-angle (degrees) inside which the intensity is full; default 25, or 5/6 of
        /// `outer_angle` where that is less ([`spot_angles`]).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        inner_angle: Option<f32>,
        /// Half-angle (degrees) beyond which there is no light; default 30, or 6/5 of
        /// `inner_angle` (at most 89) where that is more.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        outer_angle: Option<f32>,
    },
    /// A distant light (the sun): light travelling along `direction` with `irradiance`
    /// (W·m⁻² per channel) on a surface facing it, from a disc of `angular_diameter`
    /// degrees (0: parallel light, hard shadows).
    Directional {
        direction: V3,
        irradiance: V3,
        #[serde(default)]
        angular_diameter: f32,
    },
}

/// A spot's half-angles (inner, outer) in degrees, each given or defaulted: 25 and 30 when
/// neither is given, and a default that fits the other one's value where 25 or 30 would
/// not (an `outer_angle` below 30 alone gets 5/6 of it as `inner_angle`, an `inner_angle`
/// above 30 alone gets 6/5 of it, at most 89, as `outer_angle`).
pub fn spot_angles(inner: Option<f32>, outer: Option<f32>) -> (f32, f32) {
    const INNER: f32 = 25.0;
    const OUTER: f32 = 30.0;
    match (inner, outer) {
        (Some(i), Some(o)) => (i, o),
        (None, Some(o)) => (INNER.min(o * INNER / OUTER), o),
        (Some(i), None) if i > OUTER => (i, (i * OUTER / INNER).min(89.0)),
        (Some(i), None) => (i, OUTER),
        (None, None) => (INNER, OUTER),
    }
}

/// The uber BSDF's parameters (see `bsdf`).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    #[serde(default = "default_diffuse")]
    pub diffuse: V3,
    #[serde(default)]
    pub specular: V3,
    #[serde(default)]
    pub roughness: f32,
    #[serde(default)]
    pub fresnel: bool,
    #[serde(default)]
    pub transmission: V3,
    #[serde(default = "default_ior")]
    pub ior: f32,
    /// Textures (names of the scene's textures, see `docs/scene-format.md`): RGB multiplies
    /// `diffuse` and `transmission`; its alpha is the coverage when `alpha_cutoff` is set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diffuse_texture: Option<String>,
    /// RGB multiplies `specular`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub specular_texture: Option<String>,
    /// Green channel multiplies `roughness` (glTF's metallic-roughness layout).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub roughness_texture: Option<String>,
    /// Tangent-space normal map (RGB = (n + 1) / 2, +z out of the surface, +y towards -v).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal_texture: Option<String>,
    /// Coverage in the alpha channel: surfaces are cut out where it is below `alpha_cutoff`.
    /// Defaults to `diffuse_texture` when only `alpha_cutoff` is given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha_texture: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha_cutoff: Option<f32>,
    /// Emitted radiance, W·sr⁻¹·m⁻² per channel, from the front face (the side the
    /// triangles' winding faces): the surface is an area light.
    #[serde(default, skip_serializing_if = "is_zero3")]
    pub emission: V3,
    /// RGB multiplies `emission`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emission_texture: Option<String>,
    /// The back face emits too.
    #[serde(default, skip_serializing_if = "is_false")]
    pub two_sided: bool,
    /// Microfacet distribution of the rough lobes (`roughness` stays √α).
    #[serde(default, skip_serializing_if = "is_ggx")]
    pub distribution: DistributionDesc,
    /// Mitsuba's plastic/roughplastic: `diffuse` under a dielectric coating of this relative
    /// index (> 1), whose Fresnel reflectance `specular` multiplies.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coating_ior: Option<f32>,
    /// Mitsuba's `nonlinear`: the base's internal scattering darkens its colour.
    #[serde(default, skip_serializing_if = "is_false")]
    pub coating_nonlinear: bool,
    /// Mitsuba's conductors: the specular Fresnel term is the exact conductor Fresnel of
    /// the complex index `conductor_eta + i·conductor_k` (per channel, relative to the
    /// outside); `specular` multiplies it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub conductor_eta: Option<V3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub conductor_k: Option<V3>,
    /// Mitsuba's roughdielectric: the glass lobe (`transmission`, `ior`) is rough with
    /// `roughness` (√α) and `distribution`, and `specular` multiplies its reflection.
    #[serde(default, skip_serializing_if = "is_false")]
    pub rough_glass: bool,
    /// Mitsuba's thindielectric: the smooth glass lobe (`transmission`, `ior`) is a thin
    /// slab, reflecting R' = 2R/(1 + R) (R the Fresnel reflectance of `ior`, with the
    /// slab's inner reflections) and passing the rest straight through; these per-channel
    /// factors (Mitsuba's `specular_reflectance`) multiply its reflection.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thin_glass: Option<V3>,
    /// Only the front face (the side the triangles' winding faces) reflects and transmits
    /// light; the back is black (Mitsuba's BSDFs without `twosided`). Default: both faces.
    #[serde(default, skip_serializing_if = "is_false")]
    pub one_sided: bool,
}

/// `"ggx"` or `"beckmann"`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DistributionDesc {
    #[default]
    Ggx,
    Beckmann,
}

fn is_ggx(d: &DistributionDesc) -> bool {
    *d == DistributionDesc::Ggx
}

fn is_zero3(v: &V3) -> bool {
    *v == [0.0; 3]
}

fn is_false(b: &bool) -> bool {
    !*b
}

impl MaterialDesc {
    /// The texture fields alone.
    pub fn texture_refs(&self) -> TextureRefs {
        TextureRefs {
            diffuse: self.diffuse_texture.clone(),
            specular: self.specular_texture.clone(),
            roughness: self.roughness_texture.clone(),
            normal: self.normal_texture.clone(),
            alpha: self.alpha_texture.clone(),
            alpha_cutoff: self.alpha_cutoff,
            emission: self.emission_texture.clone(),
        }
    }
}

/// The texture names of a material description.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TextureRefs {
    pub diffuse: Option<String>,
    pub specular: Option<String>,
    pub roughness: Option<String>,
    pub normal: Option<String>,
    pub alpha: Option<String>,
    pub alpha_cutoff: Option<f32>,
    pub emission: Option<String>,
}

fn default_diffuse() -> V3 {
    [0.8; 3]
}
fn default_ior() -> f32 {
    1.5
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    /// Optional name by which scene updates and animation tracks address the object.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub shape: ShapeDesc,
    #[serde(default)]
    pub transform: TransformDesc,
    /// Name of an entry of `materials`; may be omitted for mesh files that carry materials.
    #[serde(default)]
    pub material: Option<String>,
    /// Shading normals: `false` flat, `true` smooth, or a crease angle in degrees (smooth
    /// across edges flatter than it). Absent: the shape's own normals, flat where it has none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smooth: Option<SmoothDesc>,
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize)]
#[serde(untagged)]
pub enum SmoothDesc {
    On(bool),
    CreaseAngle(f32),
}

/// Geometry of an object, in its local frame (metres).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum ShapeDesc {
    /// A triangle mesh file (OBJ/MTL, PLY, glTF/GLB, STL), relative to the scene file.
    Mesh { file: String },
    /// Another instance of the object called `object` (its mesh, stored once; its smoothing
    /// and material unless this object gives its own).
    Instance { object: String },
    /// A rectangle in the xz plane centred on the origin, normal +y.
    Quad { size: [f32; 2] },
    /// An axis-aligned box centred on the origin.
    Box { size: V3 },
    /// A geodesic sphere centred on the origin.
    Sphere {
        radius: f32,
        #[serde(default = "default_subdivisions")]
        subdivisions: u32,
    },
    /// An open or capped cylinder along +y from y = 0 to `height`.
    Cylinder {
        radius: f32,
        height: f32,
        #[serde(default = "default_segments")]
        segments: u32,
        #[serde(default)]
        caps: bool,
    },
    /// A thick-walled tube (a ring) along +y from y = 0 to `height`.
    Ring {
        inner_radius: f32,
        outer_radius: f32,
        height: f32,
        #[serde(default = "default_segments")]
        segments: u32,
    },
}

fn default_subdivisions() -> u32 {
    4
}
fn default_segments() -> u32 {
    128
}

/// Scale, then rotate (degrees about x, then y, then z), then translate; or a general
/// affine `matrix` (which excludes the other three).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TransformDesc {
    #[serde(default)]
    pub translate: V3,
    #[serde(default)]
    pub rotate: V3,
    #[serde(default = "default_scale")]
    pub scale: Scale,
    /// Object -> world as 3 or 4 rows of 4 numbers (row-major, the translation in the last
    /// column; a 4th row must be `[0, 0, 0, 1]`), checked by `scene::matrix_from_rows`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub matrix: Option<Vec<Vec<f32>>>,
}

impl Default for TransformDesc {
    fn default() -> Self {
        TransformDesc {
            translate: [0.0; 3],
            rotate: [0.0; 3],
            scale: default_scale(),
            matrix: None,
        }
    }
}

impl TransformDesc {
    /// Whether translate, rotate and scale all hold their defaults (no move).
    pub fn is_trs_default(&self) -> bool {
        self.translate == [0.0; 3]
            && self.rotate == [0.0; 3]
            && match self.scale {
                Scale::Uniform(s) => s == 1.0,
                Scale::PerAxis(s) => s == [1.0; 3],
            }
    }
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize)]
#[serde(untagged)]
pub enum Scale {
    Uniform(f32),
    PerAxis(V3),
}

fn default_scale() -> Scale {
    Scale::Uniform(1.0)
}

/// Keyframed tracks over time (seconds): see `docs/scene-format.md`, `animation`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AnimationDesc {
    /// Length, seconds; default: the time of the last key of any track.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration: Option<f64>,
    #[serde(default)]
    pub tracks: Vec<TrackDesc>,
}

/// What a track animates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TrackTarget {
    Camera,
    Light,
    Object,
    Material,
}

/// How values between two keys are found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Interpolation {
    /// Numbers and vectors linearly; booleans and strings hold the earlier key's value.
    #[default]
    Linear,
    /// Every field holds the earlier key's value until the next key.
    Step,
}

/// One keyframed track: the fields of one camera, light, object transform or material.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TrackDesc {
    pub target: TrackTarget,
    /// Light (or object) index.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub index: Option<usize>,
    /// Object or material name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub keys: Vec<KeyDesc>,
    #[serde(default)]
    pub interpolation: Interpolation,
}

/// A key: at `time` (seconds) the animated fields have `value` (fields as in the section
/// the track targets; an object's are its transform's).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct KeyDesc {
    pub time: f64,
    pub value: serde_json::Map<String, serde_json::Value>,
}

#[cfg(test)]
mod tests {
    use super::spot_angles;

    /// An angle given alone gets a default that fits it; defaults that were valid stay.
    #[test]
    fn spot_angle_defaults_fit_the_angle_given() {
        assert_eq!(spot_angles(None, None), (25.0, 30.0));
        assert_eq!(spot_angles(None, Some(45.0)), (25.0, 45.0));
        assert_eq!(spot_angles(Some(10.0), None), (10.0, 30.0));
        let (i, o) = spot_angles(None, Some(20.0));
        assert!((i - 20.0 * 5.0 / 6.0).abs() < 1e-5 && o == 20.0);
        let (i, o) = spot_angles(Some(40.0), None);
        assert!(i == 40.0 && (o - 48.0).abs() < 1e-5);
        assert_eq!(spot_angles(Some(85.0), None), (85.0, 89.0));
    }
}
