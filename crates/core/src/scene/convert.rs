//! The values of a scene description converted to the scene model's, each checked: the
//! camera, lights, materials, transforms and primitive shapes; errors name the field at
//! fault ([`FieldError`]).

use super::desc::{self, LightDesc, MaterialDesc, Scale, ShapeDesc, SmoothDesc, V3};
use super::{primitives, Camera, Light, Smoothing, TriMesh};
use super::{MAX_ANGULAR_DIAMETER, MAX_EXTENT, MAX_INTENSITY, MAX_RADIANCE, MAX_SCALE};
use crate::bsdf::{Coating, Conductor, Material};
use crate::error::{Error, Result};
use glam::{EulerRot, Mat3, Mat4, Quat, Vec3};

pub(super) fn finite3(v: V3) -> bool {
    v.iter().all(|x| x.is_finite())
}

pub(super) fn within_extent(v: V3) -> bool {
    v.iter().all(|x| x.is_finite() && x.abs() <= MAX_EXTENT)
}

pub(crate) type FieldError = (String, &'static str);

/// The texture fields of the materials in [`parse_materials`]'s format, in order.
pub fn parse_material_textures(json: &str, source_name: &str) -> Result<Vec<desc::TextureRefs>> {
    let descs = material_descs(json, source_name)?;
    Ok(descs.iter().map(|(_, d)| d.texture_refs()).collect())
}

/// The `[name, material]` pairs of [`parse_materials`]'s format; errors name the field.
fn material_descs(json: &str, source_name: &str) -> Result<Vec<(String, MaterialDesc)>> {
    let de = &mut serde_json::Deserializer::from_str(json);
    serde_path_to_error::deserialize(de).map_err(|e| {
        Error::scene(
            source_name,
            format!("materials{}", e.path()),
            e.inner().to_string(),
        )
    })
}

/// Parses the materials carried by a mesh file (e.g. OBJ + MTL), as turned into descriptions
/// by its loader: a JSON array of `[name, material]` pairs in the `materials` section's
/// format. The order is kept: per-face material indices refer to it.
pub fn parse_materials(json: &str, source_name: &str) -> Result<Vec<(String, Material)>> {
    let descs = material_descs(json, source_name)?;
    descs
        .iter()
        .map(|(name, d)| {
            material_from_desc(d)
                .map(|m| (name.clone(), m))
                .map_err(|(f, msg)| Error::scene(source_name, format!("materials.{name}.{f}"), msg))
        })
        .collect()
}

pub(crate) fn camera_from_desc(
    c: &desc::CameraDesc,
) -> std::result::Result<Camera, (String, &'static str)> {
    for (name, v) in [
        ("position", c.position),
        ("look_at", c.look_at),
        ("up", c.up),
    ] {
        if !finite3(v) {
            return Err((name.into(), "must be finite"));
        }
    }
    for (name, v) in [("position", c.position), ("look_at", c.look_at)] {
        if !within_extent(v) {
            return Err((name.into(), "must lie within ±100000 m"));
        }
    }
    let (pos, at, up) = (
        Vec3::from(c.position),
        Vec3::from(c.look_at),
        Vec3::from(c.up),
    );
    if (at - pos).length() < 1e-6 {
        return Err(("look_at".into(), "must differ from position"));
    }
    if up.length() < 1e-6 || (at - pos).normalize().cross(up.normalize()).length() < 1e-4 {
        return Err((
            "up".into(),
            "must be non-zero and not parallel to the viewing direction",
        ));
    }
    if !(c.fov > 0.0 && c.fov < 179.0) {
        return Err(("fov".into(), "must be in (0, 179) degrees"));
    }
    for (name, v) in [("width", c.width), ("height", c.height)] {
        if v == 0 || v > 16384 {
            return Err((name.into(), "must be in 1..=16384 pixels"));
        }
    }
    Ok(Camera::new(pos, at, up, c.fov, c.width, c.height))
}

pub(super) fn check_intensity(v: V3) -> std::result::Result<Vec3, FieldError> {
    if !finite3(v) || v.iter().any(|x| *x < 0.0) {
        return Err(("intensity".into(), "must be finite and non-negative"));
    }
    if v.iter().any(|x| *x > MAX_INTENSITY) {
        return Err(("intensity".into(), "must be at most 1e10 W/sr per channel"));
    }
    Ok(Vec3::from(v))
}

pub(super) fn check_light_position(v: V3) -> std::result::Result<Vec3, FieldError> {
    if !finite3(v) {
        return Err(("position".into(), "must be finite"));
    }
    if !within_extent(v) {
        return Err(("position".into(), "must lie within ±100000 m"));
    }
    Ok(Vec3::from(v))
}

pub(crate) fn light_from_desc(l: &LightDesc) -> std::result::Result<Light, FieldError> {
    match *l {
        LightDesc::Point {
            position,
            intensity,
        } => {
            let position = check_light_position(position)?;
            Ok(Light::Point {
                position,
                intensity: check_intensity(intensity)?,
            })
        }
        LightDesc::Spot {
            position,
            direction,
            intensity,
            inner_angle,
            outer_angle,
        } => {
            let position = check_light_position(position)?;
            let d = Vec3::from(direction);
            if !finite3(direction) || d.length() < 1e-6 {
                return Err(("direction".into(), "must be finite and non-zero"));
            }
            let (inner_angle, outer_angle) = desc::spot_angles(inner_angle, outer_angle);
            if !(outer_angle > 0.0 && outer_angle < 90.0) {
                return Err(("outer_angle".into(), "must be in (0, 90) degrees"));
            }
            if !(inner_angle >= 0.0 && inner_angle <= outer_angle) {
                return Err((
                    "inner_angle".into(),
                    "must be in [0, outer_angle] degrees (the angle of full intensity \
                     lies within the cone's outer angle)",
                ));
            }
            Ok(Light::Spot {
                position,
                direction: d.normalize(),
                intensity: check_intensity(intensity)?,
                cos_inner: inner_angle.to_radians().cos(),
                cos_outer: outer_angle.to_radians().cos(),
            })
        }
        LightDesc::Directional {
            direction,
            irradiance,
            angular_diameter,
        } => {
            let d = Vec3::from(direction);
            if !finite3(direction) || d.length() < 1e-6 {
                return Err(("direction".into(), "must be finite and non-zero"));
            }
            if !finite3(irradiance) || irradiance.iter().any(|x| *x < 0.0) {
                return Err(("irradiance".into(), "must be finite and non-negative"));
            }
            if irradiance.iter().any(|x| *x > MAX_RADIANCE) {
                return Err((
                    "irradiance".into(),
                    "must be at most 1e10 W/m² per channel (MAX_RADIANCE)",
                ));
            }
            if !(0.0..MAX_ANGULAR_DIAMETER).contains(&angular_diameter) {
                return Err((
                    "angular_diameter".into(),
                    "must be in [0, 90) degrees (MAX_ANGULAR_DIAMETER)",
                ));
            }
            Ok(Light::Directional {
                direction: d.normalize(),
                irradiance: Vec3::from(irradiance),
                cos_half_angle: (0.5 * angular_diameter).to_radians().cos(),
            })
        }
    }
}

pub(crate) fn material_from_desc(m: &MaterialDesc) -> std::result::Result<Material, FieldError> {
    for (name, v) in [
        ("diffuse", m.diffuse),
        ("specular", m.specular),
        ("transmission", m.transmission),
    ] {
        if !finite3(v) || v.iter().any(|x| !(0.0..=1.0).contains(x)) {
            return Err((name.into(), "each channel must be in [0, 1]"));
        }
    }
    if (0..3).any(|c| m.diffuse[c] + m.transmission[c] > 1.0 + 1e-6) {
        return Err((
            "transmission".into(),
            "diffuse + transmission must not exceed 1 (energy conservation)",
        ));
    }
    if !(0.0..=1.0).contains(&m.roughness) {
        return Err(("roughness".into(), "must be in [0, 1]"));
    }
    if !(m.ior >= 1.0 && m.ior <= 4.0) {
        return Err(("ior".into(), "must be in [1, 4]"));
    }
    if !finite3(m.emission) || m.emission.iter().any(|x| *x < 0.0) {
        return Err(("emission".into(), "must be finite and non-negative"));
    }
    if m.emission.iter().any(|x| *x > MAX_RADIANCE) {
        return Err((
            "emission".into(),
            "must be at most 1e10 W·sr⁻¹·m⁻² per channel (MAX_RADIANCE)",
        ));
    }
    let distribution = match m.distribution {
        desc::DistributionDesc::Ggx => crate::bsdf::Distribution::Ggx,
        desc::DistributionDesc::Beckmann => crate::bsdf::Distribution::Beckmann,
    };
    let coating = match m.coating_ior {
        None => None,
        Some(eta) if !(eta > 1.0 && eta <= 4.0) => {
            return Err(("coating_ior".into(), "must be in (1, 4]"));
        }
        Some(_) if m.transmission.iter().any(|t| *t > 0.0) => {
            return Err((
                "coating_ior".into(),
                "excludes transmission (a coated base is opaque)",
            ));
        }
        Some(eta) => Some(Coating::new(
            eta,
            m.coating_nonlinear,
            m.roughness * m.roughness,
            distribution,
        )),
    };
    if m.coating_nonlinear && coating.is_none() {
        return Err(("coating_nonlinear".into(), "needs coating_ior"));
    }
    let conductor = match (m.conductor_eta, m.conductor_k) {
        (None, None) => None,
        (Some(eta), Some(k)) => {
            for (name, v) in [("conductor_eta", eta), ("conductor_k", k)] {
                if !finite3(v) || v.iter().any(|x| !(0.0..=100.0).contains(x)) {
                    return Err((name.into(), "each channel must be in [0, 100]"));
                }
            }
            if coating.is_some() {
                return Err(("conductor_eta".into(), "excludes coating_ior"));
            }
            Some(Conductor::new(eta.into(), k.into()))
        }
        (Some(_), None) => return Err(("conductor_k".into(), "needed with conductor_eta")),
        (None, Some(_)) => return Err(("conductor_eta".into(), "needed with conductor_k")),
    };
    if m.rough_glass {
        rough_glass_valid(m, coating.is_some() || conductor.is_some())?;
    }
    if let Some(r) = m.thin_glass {
        thin_glass_valid(m, r, coating.is_some() || conductor.is_some())?;
    }
    Ok(Material {
        diffuse: m.diffuse.into(),
        specular: m.specular.into(),
        roughness: m.roughness,
        fresnel: m.fresnel,
        transmission: m.transmission.into(),
        ior: m.ior,
        emission: m.emission.into(),
        two_sided: m.two_sided,
        distribution,
        coating,
        conductor,
        rough_glass: m.rough_glass,
        thin: m.thin_glass.map(Into::into),
        one_sided: m.one_sided,
    })
}

/// A thin slab (Mitsuba's thindielectric) is smooth glass alone: no diffuse base, no other
/// model, no roughness, some transmission, reflection factors in [0, 1].
fn thin_glass_valid(
    m: &MaterialDesc,
    r: [f32; 3],
    other_model: bool,
) -> std::result::Result<(), FieldError> {
    if !finite3(r) || r.iter().any(|x| !(0.0..=1.0).contains(x)) {
        return Err(("thin_glass".into(), "each channel must be in [0, 1]"));
    }
    if other_model || m.rough_glass {
        return Err((
            "thin_glass".into(),
            "excludes coating_ior, conductor_* and rough_glass (one model a material)",
        ));
    }
    if m.diffuse.iter().any(|d| *d > 0.0) || m.specular.iter().any(|s| *s > 0.0) {
        return Err((
            "thin_glass".into(),
            "needs diffuse and specular 0 (a thin slab of glass alone)",
        ));
    }
    if m.transmission.iter().all(|t| *t <= 0.0) {
        return Err(("thin_glass".into(), "needs transmission > 0"));
    }
    Ok(())
}

/// Rough glass (Mitsuba's roughdielectric) has no diffuse base, no other Fresnel model and
/// a rough surface (Mitsuba clamps α to 1e-4: roughness ≥ 0.01).
fn rough_glass_valid(m: &MaterialDesc, other_model: bool) -> std::result::Result<(), FieldError> {
    if other_model {
        return Err((
            "rough_glass".into(),
            "excludes coating_ior and conductor_* (one model a material)",
        ));
    }
    if m.diffuse.iter().any(|d| *d > 0.0) {
        return Err((
            "rough_glass".into(),
            "needs diffuse 0 (glass has no diffuse base)",
        ));
    }
    if m.roughness < 0.01 {
        return Err((
            "roughness".into(),
            "must be at least 0.01 (α ≥ 1e-4) with rough_glass; smooth glass is roughness 0 without it",
        ));
    }
    if m.ior <= 1.0 {
        return Err(("ior".into(), "must exceed 1 with rough_glass"));
    }
    Ok(())
}

pub(crate) fn transform_matrix(t: &desc::TransformDesc) -> std::result::Result<Mat4, FieldError> {
    if let Some(rows) = &t.matrix {
        if !t.is_trs_default() {
            return Err((
                "matrix".into(),
                "excludes translate/rotate/scale (give one or the other)",
            ));
        }
        return matrix_from_rows(rows).map_err(|(f, m)| (format!("matrix{f}"), m));
    }
    if !finite3(t.translate) {
        return Err(("translate".into(), "must be finite"));
    }
    if !within_extent(t.translate) {
        return Err(("translate".into(), "must lie within ±100000 m"));
    }
    if !finite3(t.rotate) {
        return Err(("rotate".into(), "must be finite"));
    }
    let scale = match t.scale {
        Scale::Uniform(s) => Vec3::splat(s),
        Scale::PerAxis(s) => Vec3::from(s),
    };
    if !scale.is_finite() || scale.abs().min_element() < 1e-12 {
        return Err(("scale".into(), "must be finite and non-zero"));
    }
    if scale.abs().max_element() > MAX_SCALE || scale.abs().min_element() < 1.0 / MAX_SCALE {
        return Err((
            "scale".into(),
            "each factor's magnitude must be in [1e-6, 1e6]",
        ));
    }
    let [rx, ry, rz] = t.rotate.map(f32::to_radians);
    // Rotate about x first, then y, then z: R = Rz·Ry·Rx.
    let rot = Quat::from_euler(EulerRot::ZYX, rz, ry, rx);
    Ok(Mat4::from_scale_rotation_translation(
        scale,
        rot,
        t.translate.into(),
    ))
}

/// An affine transform from 3 or 4 rows of 4 numbers (row-major; the translation in the last
/// column; a 4th row must be `[0, 0, 0, 1]`): finite, its translation within
/// [`MAX_EXTENT`], each axis's image (column) of length in [1/`MAX_SCALE`, `MAX_SCALE`],
/// and invertible by a margin: |det| at least 1e-6 of the product of the columns' lengths
/// (1 for orthogonal axes; Hadamard's bound), so that no axis collapses onto the others.
/// Errors name the part at fault relative to the matrix (`""`, `"[3]"`).
pub(crate) fn matrix_from_rows(rows: &[Vec<f32>]) -> std::result::Result<Mat4, FieldError> {
    if rows.len() != 3 && rows.len() != 4 {
        return Err((String::new(), "must be 3 or 4 rows of 4 numbers"));
    }
    if let Some(r) = rows.iter().position(|row| row.len() != 4) {
        return Err((format!("[{r}]"), "must hold 4 numbers"));
    }
    if rows.iter().flatten().any(|v| !v.is_finite()) {
        return Err((String::new(), "must be finite"));
    }
    if rows.len() == 4 && rows[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err(("[3]".into(), "must be [0, 0, 0, 1] (transforms are affine)"));
    }
    let mut m = Mat4::IDENTITY;
    for (r, row) in rows.iter().take(3).enumerate() {
        for (c, &v) in row.iter().enumerate() {
            m.col_mut(c)[r] = v;
        }
    }
    if !within_extent([m.w_axis.x, m.w_axis.y, m.w_axis.z]) {
        return Err((String::new(), "its translation must lie within ±100000 m"));
    }
    let lin = Mat3::from_mat4(m);
    let lengths = [
        lin.x_axis.length(),
        lin.y_axis.length(),
        lin.z_axis.length(),
    ];
    if lengths
        .iter()
        .any(|&l| !(l.is_finite() && (1.0 / MAX_SCALE..=MAX_SCALE).contains(&l)))
    {
        return Err((
            String::new(),
            "each column's length (an axis's scale) must be in [1e-6, 1e6]",
        ));
    }
    let det = lin.determinant();
    if !(det.is_finite() && det.abs() >= 1e-6 * lengths.iter().product::<f32>()) {
        return Err((
            String::new(),
            "must be invertible (its columns are parallel or coplanar: singular)",
        ));
    }
    Ok(m)
}

pub(super) fn primitive(shape: &ShapeDesc) -> std::result::Result<TriMesh, FieldError> {
    let positive = |name: &str, v: f32| {
        if !(v.is_finite() && v > 0.0) {
            Err((name.to_string(), "must be positive and finite"))
        } else if v > MAX_EXTENT {
            Err((name.to_string(), "must be at most 100000 m"))
        } else {
            Ok(v)
        }
    };
    let segs = |s: u32| {
        if (3..=4096).contains(&s) {
            Ok(s)
        } else {
            Err(("segments".to_string(), "must be in 3..=4096"))
        }
    };
    Ok(match *shape {
        ShapeDesc::Mesh { .. } | ShapeDesc::Instance { .. } => {
            unreachable!("mesh files and instances are resolved by the caller")
        }
        ShapeDesc::Quad { size } => {
            primitives::quad([positive("size", size[0])?, positive("size", size[1])?])
        }
        ShapeDesc::Box { size } => primitives::cuboid(Vec3::new(
            positive("size", size[0])?,
            positive("size", size[1])?,
            positive("size", size[2])?,
        )),
        ShapeDesc::Sphere {
            radius,
            subdivisions,
        } => {
            if subdivisions > 7 {
                return Err((
                    "subdivisions".into(),
                    "must be at most 7 (327,680 triangles)",
                ));
            }
            primitives::sphere(positive("radius", radius)?, subdivisions)
        }
        ShapeDesc::Cylinder {
            radius,
            height,
            segments,
            caps,
        } => primitives::cylinder(
            positive("radius", radius)?,
            positive("height", height)?,
            segs(segments)?,
            caps,
        ),
        ShapeDesc::Ring {
            inner_radius,
            outer_radius,
            height,
            segments,
        } => {
            let inner = positive("inner_radius", inner_radius)?;
            if !(outer_radius.is_finite() && outer_radius > inner && outer_radius <= MAX_EXTENT) {
                return Err((
                    "outer_radius".into(),
                    "must be finite, larger than inner_radius and at most 100000 m",
                ));
            }
            primitives::ring(
                inner,
                outer_radius,
                positive("height", height)?,
                segs(segments)?,
            )
        }
    })
}

/// The box of a mesh's vertices (non-finite when a vertex is).
pub(super) fn mesh_bounds(m: &TriMesh) -> (Vec3, Vec3) {
    m.positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            if p.is_finite() {
                (lo.min(*p), hi.max(*p))
            } else {
                (Vec3::NAN, Vec3::NAN)
            }
        })
}

/// Whether every corner of the box (lo, hi), placed by `xf`, is finite and within
/// [`MAX_EXTENT`]: then so is every vertex inside it (an affine map keeps points inside
/// the corners' hull).
pub(super) fn box_within_extent(lo: Vec3, hi: Vec3, xf: Mat4) -> bool {
    if !(lo.is_finite() && hi.is_finite()) {
        return false;
    }
    (0..8).all(|i| {
        let c = Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        let p = xf.transform_point3(c);
        p.is_finite() && p.abs().max_element() <= MAX_EXTENT
    })
}

/// Checks that every vertex of `m` lies within [`MAX_EXTENT`] once placed by `xf`; blames
/// the shape when its own coordinates are out of range, else the transform.
pub(super) fn validate_placed(m: &TriMesh, xf: Mat4) -> std::result::Result<(), (String, String)> {
    let outside = |p: Vec3| !(p.is_finite() && p.abs().max_element() <= MAX_EXTENT);
    if let Some(i) = m.positions.iter().position(|p| outside(*p)) {
        return Err(("shape".into(), format!("vertex {i} lies outside ±100000 m")));
    }
    if let Some(i) = m
        .positions
        .iter()
        .position(|p| outside(xf.transform_point3(*p)))
    {
        return Err((
            "transform".into(),
            format!("places vertex {i} outside ±100000 m"),
        ));
    }
    Ok(())
}

pub(super) fn smoothing(s: Option<SmoothDesc>) -> std::result::Result<Smoothing, &'static str> {
    Ok(match s {
        None => Smoothing::Auto,
        Some(SmoothDesc::On(false)) => Smoothing::Flat,
        Some(SmoothDesc::On(true)) => Smoothing::Smooth,
        Some(SmoothDesc::CreaseAngle(deg)) if (0.0..=180.0).contains(&deg) => {
            Smoothing::from_angle_degrees(deg)
        }
        Some(SmoothDesc::CreaseAngle(_)) => {
            return Err("must be false, true or a crease angle in [0, 180] degrees")
        }
    })
}

pub(super) fn validate_mesh(m: &TriMesh) -> std::result::Result<(), String> {
    if m.indices.is_empty() {
        return Err("mesh has no triangles".into());
    }
    if let Some(i) = m.positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {i} is not finite (NaN or infinity)"));
    }
    let count_ok = m.normals.is_empty() || m.normals.len() == m.positions.len();
    if !count_ok || m.normals.iter().any(|n| !n.is_finite()) {
        return Err("normals must be finite, one per vertex (or none)".into());
    }
    let n = m.positions.len() as u32;
    if let Some(t) = m.indices.iter().position(|t| t.iter().any(|&i| i >= n)) {
        return Err(format!("triangle {t} indexes a vertex out of range"));
    }
    Ok(())
}
