//! Changes to a scene between frames: the camera, a light, an object's transform, a
//! material. Each is validated like the scene description it replaces, and reports what it
//! invalidates ([`Changes`]) so that a renderer re-uploads and rebuilds only that.

use super::desc::{CameraDesc, LightDesc, MaterialDesc, Scale, TransformDesc};
use super::{camera_from_desc, light_from_desc, material_from_desc, Light, Scene, MAX_EXTENT};
use crate::error::{Error, Result};
use glam::{EulerRot, Mat3, Mat4, Vec3};
use std::ops::Range;

/// Where an update's errors say they come from.
const SOURCE: &str = "scene update";

/// One object of the description, an instance: the unique mesh it places
/// ([`Scene::meshes`]), its transform, and its slice of the scene's flat arrays (the derived
/// world-space view that consumers not yet ported to instances read).
#[derive(Clone, Debug)]
pub struct SceneObject {
    pub name: Option<String>,
    /// Range of `Scene::positions` / `Scene::normals`.
    pub vertices: Range<u32>,
    /// Range of `Scene::triangles` / `Scene::triangle_materials`.
    pub triangles: Range<u32>,
    /// Object -> world (changed by `SceneObject::set_transform`, which keeps
    /// `normal_matrix` with it).
    pub transform: Mat4,
    /// The inverse transpose of `transform`'s linear part (normals object -> world), kept
    /// so that every surface interaction need not invert it.
    pub(crate) normal_matrix: Mat3,
    /// Whether the triangles are stored with flipped winding (a mirroring transform).
    pub flipped: bool,
    /// Index of the object's mesh in [`Scene::meshes`] (shared by every object that names
    /// the same file or built-in shape with the same options, or refers to it as an
    /// instance).
    pub mesh: u32,
    /// The object's material; with `face_materials`, the first of the file's materials.
    pub material: u32,
    /// The mesh file's material per triangle (offsets from `material`), if the object
    /// takes its materials from the file.
    pub face_materials: Option<std::sync::Arc<Vec<u32>>>,
    /// The transform as the scene file described it (while `transform` is still its
    /// matrix): [`Scene::object_desc`] gives it back exactly.
    pub(crate) described: Option<TransformDesc>,
}

/// The matrix that takes object normals to world normals under `transform`.
pub(crate) fn normal_matrix_of(transform: Mat4) -> Mat3 {
    Mat3::from_mat4(transform).inverse().transpose()
}

impl SceneObject {
    /// Places the object by `transform` (object -> world).
    pub(crate) fn set_transform(&mut self, transform: Mat4) {
        self.transform = transform;
        self.normal_matrix = normal_matrix_of(transform);
    }

    /// Writes the object's mesh, transformed, into the scene's flat arrays.
    pub(crate) fn place(
        &self,
        mesh: &super::TriMesh,
        positions: &mut [Vec3],
        normals: &mut [Vec3],
    ) {
        let r = self.vertices.start as usize..self.vertices.end as usize;
        let xf = self.transform;
        let normal_xf = Mat3::from_mat4(xf).inverse().transpose();
        for (dst, p) in positions[r.clone()].iter_mut().zip(&mesh.positions) {
            *dst = xf.transform_point3(*p);
        }
        for (dst, n) in normals[r].iter_mut().zip(&mesh.normals) {
            *dst = (normal_xf * *n).normalize_or_zero();
        }
    }
}

/// A change to a scene between two frames.
#[derive(Clone, Debug)]
pub enum SceneUpdate {
    /// The camera's pose and field of view. Its `width`/`height` are ignored: the image size
    /// belongs to the renderer (`Renderer::resize`).
    Camera(CameraDesc),
    /// Light `index` replaced by `light`.
    Light { index: usize, light: LightDesc },
    /// Object `object` (index into `Scene::objects`) placed by a new object -> world
    /// transform; a mirroring transform flips its winding, as in the description.
    Transform { object: usize, transform: Mat4 },
    /// The material called `name` replaced by `material` (boxed: a description is several
    /// times larger than the other updates).
    Material {
        name: String,
        material: Box<MaterialDesc>,
    },
}

/// What a set of updates invalidated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Changes {
    pub camera: bool,
    pub lights: bool,
    /// Vertex positions or normals (object transforms): BVH, vertex buffer, shadow maps.
    pub geometry: bool,
    pub materials: bool,
}

impl Changes {
    pub fn any(self) -> bool {
        self.camera || self.lights || self.geometry || self.materials
    }

    /// Whether light transport (photons, shadows) changed, not only the view.
    pub fn lighting(self) -> bool {
        self.lights || self.geometry || self.materials
    }

    pub fn union(self, o: Changes) -> Changes {
        Changes {
            camera: self.camera || o.camera,
            lights: self.lights || o.lights,
            geometry: self.geometry || o.geometry,
            materials: self.materials || o.materials,
        }
    }
}

impl Scene {
    /// Applies `update` after validating it; on error the scene is unchanged.
    pub fn apply(&mut self, update: &SceneUpdate) -> Result<Changes> {
        let err = |field: String, msg: &str| Error::scene(SOURCE, field, msg);
        match update {
            SceneUpdate::Camera(desc) => {
                let desc = CameraDesc {
                    width: self.camera.width,
                    height: self.camera.height,
                    ..desc.clone()
                };
                self.camera =
                    camera_from_desc(&desc).map_err(|(f, m)| err(format!("camera.{f}"), m))?;
                self.camera_source = desc;
                Ok(Changes {
                    camera: true,
                    ..Default::default()
                })
            }
            SceneUpdate::Light { index, light } => {
                let n = self.lights.len();
                let slot = self.lights.get_mut(*index).ok_or_else(|| {
                    err(
                        format!("lights[{index}]"),
                        &format!("no such light (the scene has {n})"),
                    )
                })?;
                *slot = light_from_desc(light)
                    .map_err(|(f, m)| err(format!("lights[{index}].{f}"), m))?;
                Ok(Changes {
                    lights: true,
                    ..Default::default()
                })
            }
            SceneUpdate::Transform { object, transform } => {
                let field = format!("objects[{object}].transform");
                let n = self.objects.len();
                if *object >= n {
                    return Err(err(field, &format!("no such object (the scene has {n})")));
                }
                let det = Mat3::from_mat4(*transform).determinant();
                if !transform.is_finite() || !det.is_finite() || det.abs() <= 1e-30 {
                    return Err(err(field, "must be finite and invertible"));
                }
                let obj = &self.objects[*object];
                let mesh = self.meshes[obj.mesh as usize].clone();
                let placed: Vec<Vec3> = mesh
                    .positions
                    .iter()
                    .map(|p| transform.transform_point3(*p))
                    .collect();
                let outside = |p: &Vec3| !(p.is_finite() && p.abs().max_element() <= MAX_EXTENT);
                if placed.iter().any(outside) {
                    return Err(err(
                        field,
                        "moves vertices outside ±100000 m or to non-finite positions",
                    ));
                }
                let obj = &mut self.objects[*object];
                obj.set_transform(*transform);
                let flip = det < 0.0;
                let flipped = flip != obj.flipped;
                obj.flipped = flip;
                self.moved_in_flat(*object, flipped);
                Ok(Changes {
                    geometry: true,
                    ..Default::default()
                })
            }
            SceneUpdate::Material { name, material } => {
                let i = self
                    .material_names
                    .iter()
                    .position(|m| m == name)
                    .ok_or_else(|| err(format!("materials.{name}"), "no material of that name"))?;
                let m = material_from_desc(material)
                    .map_err(|(f, m)| err(format!("materials.{name}.{f}"), m))?;
                let maps =
                    super::MaterialMaps::resolve(&material.texture_refs(), &self.texture_index())
                        .map_err(|(f, m)| err(format!("materials.{name}.{f}"), &m))?;
                self.materials[i] = m;
                self.material_maps[i] = maps;
                Ok(Changes {
                    materials: true,
                    ..Default::default()
                })
            }
        }
    }

    /// Index of the object called `name`.
    pub fn object_index(&self, name: &str) -> Option<usize> {
        self.objects
            .iter()
            .position(|o| o.name.as_deref() == Some(name))
    }

    /// The camera as a description (what [`SceneUpdate::Camera`] takes): as last described
    /// (scene file or update), with the current image size.
    pub fn camera_desc(&self) -> CameraDesc {
        CameraDesc {
            width: self.camera.width,
            height: self.camera.height,
            ..self.camera_source.clone()
        }
    }

    /// Light `index` as a description (what [`SceneUpdate::Light`] takes).
    pub fn light_desc(&self, index: usize) -> Option<LightDesc> {
        let degrees = |c: f32| c.clamp(-1.0, 1.0).acos().to_degrees();
        Some(match *self.lights.get(index)? {
            Light::Point {
                position,
                intensity,
            } => LightDesc::Point {
                position: position.into(),
                intensity: intensity.into(),
            },
            Light::Spot {
                position,
                direction,
                intensity,
                cos_inner,
                cos_outer,
            } => LightDesc::Spot {
                position: position.into(),
                direction: direction.into(),
                intensity: intensity.into(),
                inner_angle: Some(degrees(cos_inner)),
                outer_angle: Some(degrees(cos_outer)),
            },
            Light::Directional {
                direction,
                irradiance,
                cos_half_angle,
            } => LightDesc::Directional {
                direction: direction.into(),
                irradiance: irradiance.into(),
                angular_diameter: 2.0 * degrees(cos_half_angle),
            },
        })
    }

    /// Object `index`'s transform as a description (what an object update takes): the scene
    /// file's `translate`/`rotate`/`scale` while the object has not moved, else the current
    /// matrix taken apart into them (rotation angles about x, then y, then z, which may
    /// differ from the ones given but rotate alike); `Err` with the matrix's rows for a
    /// matrix with shear, which no translate/rotate/scale describes.
    pub fn object_desc(
        &self,
        index: usize,
    ) -> Option<std::result::Result<TransformDesc, [[f32; 4]; 4]>> {
        let obj = self.objects.get(index)?;
        // A described `matrix` is given back taken apart like a moved object's, so that
        // partial updates (`translate` alone) apply to it.
        if let Some(d) = obj.described.as_ref().filter(|d| d.matrix.is_none()) {
            if super::transform_matrix(d).is_ok_and(|m| m == obj.transform) {
                return Some(Ok(d.clone()));
            }
        }
        let m = obj.transform;
        let (scale, rotation, translation) = m.to_scale_rotation_translation();
        let (rz, ry, rx) = rotation.to_euler(EulerRot::ZYX);
        let desc = TransformDesc {
            translate: translation.into(),
            rotate: [rx.to_degrees(), ry.to_degrees(), rz.to_degrees()],
            scale: if scale.x == scale.y && scale.y == scale.z {
                Scale::Uniform(scale.x)
            } else {
                Scale::PerAxis(scale.into())
            },
            matrix: None,
        };
        // A sheared matrix is not a scale, a rotation and a translation.
        let exact = super::transform_matrix(&desc).is_ok_and(|back| {
            let tolerance = 1e-4
                * m.abs()
                    .to_cols_array()
                    .iter()
                    .fold(1.0f32, |a, &b| a.max(b));
            back.abs_diff_eq(m, tolerance)
        });
        Some(if exact {
            Ok(desc)
        } else {
            Err(m.transpose().to_cols_array_2d())
        })
    }

    /// The material called `name` as a description (what [`SceneUpdate::Material`] takes).
    pub fn material_desc(&self, name: &str) -> Option<MaterialDesc> {
        let i = self.material_names.iter().position(|m| m == name)?;
        let m = &self.materials[i];
        let t = self.material_maps[i].refs(&self.texture_names);
        Some(MaterialDesc {
            diffuse: m.diffuse.into(),
            specular: m.specular.into(),
            roughness: m.roughness,
            fresnel: m.fresnel,
            transmission: m.transmission.into(),
            ior: m.ior,
            diffuse_texture: t.diffuse,
            specular_texture: t.specular,
            roughness_texture: t.roughness,
            normal_texture: t.normal,
            alpha_texture: t.alpha,
            alpha_cutoff: t.alpha_cutoff,
            emission: m.emission.into(),
            emission_texture: t.emission,
            two_sided: m.two_sided,
            distribution: match m.distribution {
                crate::bsdf::Distribution::Ggx => super::desc::DistributionDesc::Ggx,
                crate::bsdf::Distribution::Beckmann => super::desc::DistributionDesc::Beckmann,
            },
            coating_ior: m.coating.map(|c| c.eta),
            coating_nonlinear: m.coating.is_some_and(|c| c.nonlinear),
            conductor_eta: m.conductor.map(|c| c.eta.into()),
            conductor_k: m.conductor.map(|c| c.k.into()),
            rough_glass: m.rough_glass,
            thin_glass: m.thin.map(Into::into),
            one_sided: m.one_sided,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    /// Moving an object and moving it back restores its vertices (to float round-off), and
    /// its triangles keep their winding.
    #[test]
    fn transform_round_trip() {
        let mut scene = builtin::load("cornell").expect("scene");
        let before = scene.clone();
        let i = scene.objects.len() - 1;
        let original = scene.objects[i].transform;
        let moved = Mat4::from_translation(Vec3::new(0.1, 0.0, -0.2)) * original;
        let c = scene
            .apply(&SceneUpdate::Transform {
                object: i,
                transform: moved,
            })
            .expect("valid");
        assert!(c.geometry && !c.camera);
        let r = scene.objects[i].vertices.clone();
        let p = scene.flat().positions[r.start as usize];
        let q = before.flat().positions[r.start as usize];
        assert!((p - q - Vec3::new(0.1, 0.0, -0.2)).length() < 1e-5);
        scene
            .apply(&SceneUpdate::Transform {
                object: i,
                transform: original,
            })
            .expect("valid");
        for (a, b) in scene
            .flat()
            .positions
            .iter()
            .zip(before.flat().positions.iter())
        {
            assert!((*a - *b).length() < 1e-5);
        }
        assert_eq!(scene.flat().triangles, before.flat().triangles);
    }

    /// A mirroring transform flips the winding so the geometric normal keeps pointing out.
    #[test]
    fn mirroring_flips_winding() {
        let mut scene = builtin::load("cornell").expect("scene");
        let i = scene.objects.len() - 1;
        let t = scene.objects[i].triangles.start as usize;
        let normal = |s: &Scene| {
            let [a, b, c] = s.triangle(t);
            (b - a).cross(c - a).normalize()
        };
        let n0 = normal(&scene);
        let xf = scene.objects[i].transform;
        let mirrored = xf * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        scene
            .apply(&SceneUpdate::Transform {
                object: i,
                transform: mirrored,
            })
            .expect("valid");
        // The mirrored face's normal is the original one mirrored in the object's x axis,
        // still outward: its dot with the vertex normal is positive.
        let [a, _, _] = scene.flat().triangles[t];
        let n1 = normal(&scene);
        assert!(n1.dot(scene.flat().normals[a as usize]) > 0.0, "{n0} {n1}");
    }

    #[test]
    fn invalid_updates_leave_the_scene_unchanged() {
        let mut scene = builtin::load("cornell").expect("scene");
        let before = scene.flat().positions.clone();
        let bad = [
            SceneUpdate::Transform {
                object: 0,
                transform: Mat4::from_scale(Vec3::ZERO),
            },
            SceneUpdate::Transform {
                object: 999,
                transform: Mat4::IDENTITY,
            },
            SceneUpdate::Light {
                index: 0,
                light: LightDesc::Point {
                    position: [0.0, f32::NAN, 0.0],
                    intensity: [1.0; 3],
                },
            },
            SceneUpdate::Material {
                name: "no such".into(),
                material: Box::new(scene.material_desc(&scene.material_names[0]).expect("m")),
            },
        ];
        for u in &bad {
            let e = scene.apply(u).expect_err("must be rejected");
            assert!(matches!(e, Error::Scene { .. }), "{e}");
        }
        assert_eq!(scene.flat().positions, before);
    }

    /// JSON updates merge into the current description and name the field on error.
    #[test]
    fn json_updates() {
        let mut scene = builtin::load("cornell").expect("scene");
        let v = |s: &str| serde_json::from_str::<serde_json::Value>(s).expect("json");
        let u = scene
            .update_from_json(&UpdateTarget::Light(0), &v(r#"{"intensity": [1, 2, 3]}"#))
            .expect("valid");
        let p = scene.lights[0].position();
        scene.apply(&u).expect("valid");
        assert_eq!(scene.lights[0].position(), p);
        assert!(
            matches!(scene.lights[0], Light::Point { intensity, .. } if intensity == Vec3::new(1.0, 2.0, 3.0))
        );
        let name = scene.material_names[0].clone();
        let u = scene
            .update_from_json(
                &UpdateTarget::Material(name.clone()),
                &v(r#"{"roughness": 0.5}"#),
            )
            .expect("valid");
        scene.apply(&u).expect("valid");
        assert_eq!(scene.material_desc(&name).expect("m").roughness, 0.5);
        let u = scene
            .update_from_json(&UpdateTarget::Object(0), &v(r#"{"translate": [0, 1, 0]}"#))
            .expect("valid");
        assert!(matches!(u, SceneUpdate::Transform { transform, .. } if transform.w_axis.y == 1.0));
        let u = scene
            .update_from_json(
                &UpdateTarget::Object(0),
                &v(r#"{"matrix": [[1,0,0,2],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}"#),
            )
            .expect("valid");
        assert!(matches!(u, SceneUpdate::Transform { transform, .. } if transform.w_axis.x == 2.0));
        let e = scene
            .update_from_json(&UpdateTarget::Camera, &v(r#"{"fov": "wide"}"#))
            .expect_err("type error");
        assert!(e.to_string().contains("camera.fov"), "{e}");
        let e = scene
            .update_from_json(&UpdateTarget::Light(0), &v(r#"{"colour": [1, 1, 1]}"#))
            .expect_err("unknown field");
        assert!(e.to_string().contains("colour"), "{e}");
    }

    /// An update that gives a light another `type` replaces the whole light; one that
    /// gives the same type merges as any other.
    #[test]
    fn light_updates_change_the_type() {
        let mut scene = builtin::load("cornell").expect("scene");
        let v = |s: &str| serde_json::from_str::<serde_json::Value>(s).expect("json");
        let sun = r#"{"type": "directional", "direction": [0, -2, 0], "irradiance": [3, 3, 3]}"#;
        let u = scene
            .update_from_json(&UpdateTarget::Light(0), &v(sun))
            .expect("valid");
        scene.apply(&u).expect("valid");
        assert!(matches!(
            scene.lights[0],
            Light::Directional { direction, .. } if direction == Vec3::NEG_Y
        ));
        let u = scene
            .update_from_json(
                &UpdateTarget::Light(0),
                &v(r#"{"type": "directional", "angular_diameter": 2}"#),
            )
            .expect("valid");
        scene.apply(&u).expect("valid");
        let desc = serde_json::to_value(scene.light_desc(0).expect("light")).expect("json");
        assert_eq!(desc["irradiance"], v("[3.0, 3.0, 3.0]"));
        assert!((desc["angular_diameter"].as_f64().expect("f") - 2.0).abs() < 1e-3);
        let e = scene
            .update_from_json(&UpdateTarget::Light(0), &v(r#"{"type": "point"}"#))
            .expect_err("a point light needs its fields");
        assert!(e.to_string().contains("position"), "{e}");
    }

    /// Updating the camera's position keeps its look-at point and up vector exactly, however
    /// often: going back to the first position gives the first camera bit for bit.
    #[test]
    fn partial_camera_updates_do_not_drift() {
        let mut scene = builtin::load("cornell").expect("scene");
        let first = scene.camera;
        let p0 = scene.camera_desc().position;
        let v = |s: &str| serde_json::from_str::<serde_json::Value>(s).expect("json");
        for i in 0..50 {
            let json = v(&format!(
                r#"{{"position": [{}, 1.0, 3.0]}}"#,
                0.01 * i as f32
            ));
            let u = scene
                .update_from_json(&UpdateTarget::Camera, &json)
                .expect("valid");
            scene.apply(&u).expect("valid");
        }
        let json = serde_json::json!({ "position": p0 });
        let u = scene
            .update_from_json(&UpdateTarget::Camera, &json)
            .expect("valid");
        scene.apply(&u).expect("valid");
        assert_eq!(scene.camera, first);
    }

    /// An object update replaces the transform fields it gives and keeps the others; the
    /// transform reads back as the scene file gave it, then as the matrix taken apart.
    #[test]
    fn object_updates_merge_and_read_back() {
        let mut scene = builtin::load("cornell").expect("scene");
        let i = scene.objects.len() - 1; // the tall box: rotate [0, 20, 0], translate...
        let v = |s: &str| serde_json::from_str::<serde_json::Value>(s).expect("json");
        let file = scene.object_desc(i).expect("object").expect("no shear");
        let u = scene
            .update_from_json(&UpdateTarget::Object(i), &v(r#"{"rotate": [0, 45, 0]}"#))
            .expect("valid");
        scene.apply(&u).expect("valid");
        let moved = scene.object_desc(i).expect("object").expect("no shear");
        for (a, b) in moved.translate.iter().zip(file.translate) {
            assert!((a - b).abs() < 1e-5, "{moved:?} {file:?}");
        }
        assert!((moved.rotate[1] - 45.0).abs() < 1e-3 && moved.rotate[0].abs() < 1e-3);
        assert!(matches!(moved.scale, Scale::Uniform(s) if (s - 1.0).abs() < 1e-5));
        // A sheared matrix reads back as rows and takes only whole transforms.
        let sheared = v(r#"{"matrix": [[1,0.5,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}"#);
        let u = scene
            .update_from_json(&UpdateTarget::Object(i), &sheared)
            .expect("valid");
        scene.apply(&u).expect("valid");
        assert!(matches!(scene.object_desc(i), Some(Err(rows)) if rows[0][1] == 0.5));
        let e = scene
            .update_from_json(&UpdateTarget::Object(i), &v(r#"{"rotate": [0, 1, 0]}"#))
            .expect_err("partial update of a sheared matrix");
        assert!(e.to_string().contains("shear"), "{e}");
    }

    /// The camera's size is the renderer's; a light changing type keeps what both share;
    /// a spot angle given alone moves the other where it would leave the cone.
    #[test]
    fn update_checks() {
        let scene = builtin::load("cornell").expect("scene");
        let v = |s: &str| serde_json::from_str::<serde_json::Value>(s).expect("json");
        let (w, h) = (scene.camera.width, scene.camera.height);
        let same = format!(r#"{{"width": {w}, "height": {h}}}"#);
        assert!(scene
            .update_from_json(&UpdateTarget::Camera, &v(&same))
            .is_ok());
        let e = scene
            .update_from_json(&UpdateTarget::Camera, &v(r#"{"width": 48}"#))
            .expect_err("a size change");
        assert!(e.to_string().contains("camera.width") && e.to_string().contains("resize"));
        let spot = v(r#"{"type": "spot", "direction": [0, -1, 0], "outer_angle": 10}"#);
        let u = scene
            .update_from_json(&UpdateTarget::Light(0), &spot)
            .expect("point to spot");
        let SceneUpdate::Light { light, .. } = &u else {
            panic!("{u:?}")
        };
        let LightDesc::Spot {
            position,
            inner_angle,
            outer_angle,
            ..
        } = light
        else {
            panic!("{light:?}")
        };
        assert_eq!(*position, <[f32; 3]>::from(scene.lights[0].position()));
        assert_eq!((*inner_angle, *outer_angle), (None, Some(10.0)));
        let mut scene = scene;
        scene.apply(&u).expect("valid");
        let back = scene
            .update_from_json(&UpdateTarget::Light(0), &v(r#"{"type": "point"}"#))
            .expect("spot to point");
        assert!(matches!(
            back,
            SceneUpdate::Light {
                light: LightDesc::Point { .. },
                ..
            }
        ));
        // A spot becoming the sun keeps its direction; it needs an irradiance.
        let sun = v(r#"{"type": "directional", "irradiance": [2, 2, 2]}"#);
        let u = scene
            .update_from_json(&UpdateTarget::Light(0), &sun)
            .expect("spot to directional");
        assert!(matches!(
            u,
            SceneUpdate::Light { light: LightDesc::Directional { direction, .. }, .. }
                if direction == [0.0, -1.0, 0.0]
        ));
        let e = scene
            .update_from_json(&UpdateTarget::Light(0), &v(r#"{"type": "directional"}"#))
            .expect_err("no irradiance");
        assert!(e.to_string().contains("irradiance"), "{e}");
    }

    /// The descriptions read back from a scene rebuild the same lights and materials.
    #[test]
    fn descriptions_round_trip() {
        let mut scene = builtin::load("cornell-glass").expect("scene");
        let lights = scene.lights.clone();
        for i in 0..lights.len() {
            let light = scene.light_desc(i).expect("light");
            scene
                .apply(&SceneUpdate::Light { index: i, light })
                .expect("valid");
        }
        for (a, b) in scene.lights.iter().zip(&lights) {
            assert_eq!(a.position(), b.position());
            assert!(
                (a.power(scene.bounds()) - b.power(scene.bounds()))
                    .abs()
                    .max_element()
                    < 1e-3 * b.power(scene.bounds()).max_element()
            );
        }
        let camera = scene.camera;
        scene
            .apply(&SceneUpdate::Camera(scene.camera_desc()))
            .expect("valid");
        assert!((scene.camera.forward - camera.forward).length() < 1e-6);
    }
}

/// The fields of a light of type `kind` (as [`LightDesc`] names them; none for an unknown
/// type, which the description's parse then refuses).
fn light_fields(kind: &str) -> &'static [&'static str] {
    match kind {
        "point" => &["position", "intensity"],
        "spot" => &[
            "position",
            "direction",
            "intensity",
            "inner_angle",
            "outer_angle",
        ],
        "directional" => &["direction", "irradiance", "angular_diameter"],
        _ => &[],
    }
}

/// What a JSON update addresses (see [`Scene::update_from_json`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum UpdateTarget {
    Camera,
    /// A light by index.
    Light(usize),
    /// An object by index into `Scene::objects`.
    Object(usize),
    /// A material by name.
    Material(String),
}

impl Scene {
    /// An update from JSON, in the scene format's terms:
    /// - camera, lights, materials: the fields given replace the current ones (the rest
    ///   stay), e.g. `{"position": [0, 1, 3]}` or `{"intensity": [5, 5, 5]}`; a light of
    ///   another `type` keeps the fields both types have; the camera's `width` and
    ///   `height` may only repeat the current size (it is the renderer's);
    /// - objects: `{"translate", "rotate", "scale"}` as in the scene format, replacing
    ///   those of the current transform ([`Scene::object_desc`]), or `{"matrix": 4×4 rows}`
    ///   for a whole transform.
    ///
    /// Errors name the field (`SceneError` with source "scene update").
    pub fn update_from_json(
        &self,
        target: &UpdateTarget,
        json: &serde_json::Value,
    ) -> Result<SceneUpdate> {
        let obj = json
            .as_object()
            .ok_or_else(|| Error::scene(SOURCE, "(root)", "an update must be a JSON object"))?;
        // The fields given replace the current description's.
        let merged = |mut current: serde_json::Value| {
            if let Some(map) = current.as_object_mut() {
                for (k, v) in obj {
                    map.insert(k.clone(), v.clone());
                }
            }
            current
        };
        fn typed<T: serde::de::DeserializeOwned>(v: serde_json::Value, prefix: &str) -> Result<T> {
            serde_path_to_error::deserialize(v).map_err(|e| {
                let path = e.path().to_string();
                let field = if path == "." {
                    prefix.to_string()
                } else {
                    format!("{prefix}.{path}")
                };
                Error::scene(SOURCE, field, e.inner().to_string())
            })
        }
        let to_value = |v: std::result::Result<serde_json::Value, serde_json::Error>| {
            v.map_err(|e| Error::scene(SOURCE, "(root)", e.to_string()))
        };
        Ok(match target {
            UpdateTarget::Camera => {
                // The image size is the renderer's: an update may only repeat it (as a
                // description read back with `camera_desc` does).
                let (w, h) = (self.camera.width, self.camera.height);
                for (name, size) in [("width", w), ("height", h)] {
                    if obj
                        .get(name)
                        .is_some_and(|v| v.as_u64() != Some(size as u64))
                    {
                        return Err(Error::scene(
                            SOURCE,
                            format!("camera.{name}"),
                            format!(
                                "the image size ({w}x{h}) belongs to the renderer, not the \
                                 camera: change it with resize(width, height)"
                            ),
                        ));
                    }
                }
                let current = to_value(serde_json::to_value(self.camera_desc()))?;
                SceneUpdate::Camera(typed(merged(current), "camera")?)
            }
            UpdateTarget::Light(i) => {
                let prefix = format!("lights[{i}]");
                let desc = self.light_desc(*i).ok_or_else(|| {
                    let n = self.lights.len();
                    Error::scene(
                        SOURCE,
                        prefix.clone(),
                        format!("no such light (the scene has {n})"),
                    )
                })?;
                let mut current = to_value(serde_json::to_value(desc))?;
                let replaced = obj
                    .get("type")
                    .is_some_and(|t| Some(t) != current.get("type"));
                if let Some(map) = current.as_object_mut() {
                    // Another type of light keeps the fields the two types share.
                    if let Some(new) = obj.get("type").filter(|t| Some(*t) != map.get("type")) {
                        let shared = light_fields(new.as_str().unwrap_or_default());
                        map.retain(|k, _| shared.contains(&k.as_str()));
                    }
                    // A spot's angle given alone replaces the other (its default follows
                    // it) where the current one would no longer fit inside the cone.
                    let angle = |v: Option<&serde_json::Value>| v.and_then(|v| v.as_f64());
                    let (inner, outer) =
                        (angle(obj.get("inner_angle")), angle(obj.get("outer_angle")));
                    match (inner, outer) {
                        (None, Some(o)) if angle(map.get("inner_angle")).is_some_and(|i| i > o) => {
                            map.remove("inner_angle");
                        }
                        (Some(i), None) if angle(map.get("outer_angle")).is_some_and(|o| o < i) => {
                            map.remove("outer_angle");
                        }
                        _ => {}
                    }
                }
                // Lights are an internally tagged enum, whose errors carry no field path:
                // name the first field that fails on its own.
                let light = typed(merged(current.clone()), &prefix).map_err(|e| {
                    if replaced {
                        return e;
                    }
                    for (k, v) in obj {
                        let mut one = current.clone();
                        if let Some(map) = one.as_object_mut() {
                            map.insert(k.clone(), v.clone());
                        }
                        if let Err(Error::Scene { message, .. }) = typed::<LightDesc>(one, &prefix)
                        {
                            return Error::scene(SOURCE, format!("{prefix}.{k}"), message);
                        }
                    }
                    e
                })?;
                SceneUpdate::Light { index: *i, light }
            }
            UpdateTarget::Material(name) => {
                let prefix = format!("materials.{name}");
                let desc = self.material_desc(name).ok_or_else(|| {
                    Error::scene(SOURCE, prefix.clone(), "no material of that name")
                })?;
                let current = to_value(serde_json::to_value(desc))?;
                SceneUpdate::Material {
                    name: name.clone(),
                    material: Box::new(typed(merged(current), &prefix)?),
                }
            }
            UpdateTarget::Object(i) => {
                let prefix = format!("objects[{i}].transform");
                let transform = if let Some(m) = obj.get("matrix") {
                    if obj.len() != 1 {
                        return Err(Error::scene(
                            SOURCE,
                            prefix,
                            "`matrix` excludes translate/rotate/scale",
                        ));
                    }
                    let field = format!("{prefix}.matrix");
                    let rows: Vec<Vec<f32>> = typed(m.clone(), &field)?;
                    super::matrix_from_rows(&rows)
                        .map_err(|(f, m)| Error::scene(SOURCE, format!("{field}{f}"), m))?
                } else {
                    // The fields given replace those of the current transform.
                    let current = match self.object_desc(*i) {
                        None => {
                            let n = self.objects.len();
                            return Err(Error::scene(
                                SOURCE,
                                prefix,
                                format!("no such object (the scene has {n})"),
                            ));
                        }
                        Some(Ok(desc)) => to_value(serde_json::to_value(desc))?,
                        // A sheared matrix: only a whole transform replaces it.
                        Some(Err(_))
                            if ["translate", "rotate", "scale"]
                                .iter()
                                .all(|k| obj.contains_key(*k)) =>
                        {
                            serde_json::json!({})
                        }
                        Some(Err(_)) => {
                            return Err(Error::scene(
                                SOURCE,
                                prefix,
                                "the object's transform is a matrix with shear: give all of \
                                 translate, rotate and scale, or a matrix",
                            ))
                        }
                    };
                    let desc: TransformDesc = typed(merged(current), &prefix)?;
                    super::transform_matrix(&desc)
                        .map_err(|(f, m)| Error::scene(SOURCE, format!("{prefix}.{f}"), m))?
                };
                SceneUpdate::Transform {
                    object: *i,
                    transform,
                }
            }
        })
    }
}
