//! Lighting given to a scene after loading: an environment (an image or a constant) and
//! lights (e.g. a sky's sun), added to the scene's own light or replacing it. What `gi
//! render --env`, `gi.render(..., environment=)` and `Renderer.update(environment=)` give
//! the core, validated as the description's `environment` and `lights` sections are.

use super::desc::LightDesc;
use super::environment::{EnvImage, EnvironmentDesc};
use super::{light_from_desc, Environment, Light, Scene};
use crate::error::{Error, Result};
use std::collections::HashMap;
use std::sync::Arc;

/// New lighting for a scene.
#[derive(Clone, Debug)]
pub struct Lighting {
    /// The environment light (`None`: none).
    pub environment: Option<Arc<Environment>>,
    /// Lights (e.g. a sky's sun).
    pub lights: Vec<Light>,
    /// `true`: added to the scene's light (its lights kept, its environment summed with
    /// this one, [`Environment::sum`]); `false`: the scene's lights and environment
    /// replaced (emitting surfaces, which are materials, stay).
    pub add: bool,
}

impl Lighting {
    /// Parses an `environment` section (JSON, `None`: no environment) with the images its
    /// `file` names, and a `lights` list (JSON, `None`: none); errors name `source` and the
    /// field (`environment.intensity`, `lights[0].direction`).
    pub fn from_json(
        environment: Option<&str>,
        images: &HashMap<String, EnvImage>,
        lights: Option<&str>,
        add: bool,
        source: &str,
    ) -> Result<Lighting> {
        let parse_err = |section: &str, e: serde_path_to_error::Error<serde_json::Error>| {
            let path = e.path().to_string();
            let field = if path == "." {
                section.to_string()
            } else if path.starts_with('[') {
                format!("{section}{path}")
            } else {
                format!("{section}.{path}")
            };
            Error::scene(source, field, e.inner().to_string())
        };
        let environment = match environment {
            None => None,
            Some(text) => {
                let de = &mut serde_json::Deserializer::from_str(text);
                let desc: EnvironmentDesc = serde_path_to_error::deserialize(de)
                    .map_err(|e| parse_err("environment", e))?;
                let env = Environment::from_desc(&desc, images).map_err(|(f, m)| {
                    let field = if f == "(section)" {
                        "environment".to_string()
                    } else {
                        format!("environment.{f}")
                    };
                    Error::scene(source, field, m)
                })?;
                Some(Arc::new(env))
            }
        };
        let lights =
            match lights {
                None => Vec::new(),
                Some(text) => {
                    let de = &mut serde_json::Deserializer::from_str(text);
                    let descs: Vec<LightDesc> =
                        serde_path_to_error::deserialize(de).map_err(|e| parse_err("lights", e))?;
                    let mut out = Vec::with_capacity(descs.len());
                    for (i, l) in descs.iter().enumerate() {
                        out.push(light_from_desc(l).map_err(|(f, m)| {
                            Error::scene(source, format!("lights[{i}].{f}"), m)
                        })?);
                    }
                    out
                }
            };
        Ok(Lighting {
            environment,
            lights,
            add,
        })
    }
}

impl Scene {
    /// The scene with `lighting` applied (its geometry, materials and textures shared).
    pub fn with_lighting(&self, lighting: &Lighting) -> Scene {
        let mut s = self.clone();
        s.set_lighting(lighting);
        s
    }

    /// Applies `lighting` in place.
    pub fn set_lighting(&mut self, lighting: &Lighting) {
        if !lighting.add {
            self.lights.clear();
            self.environment = None;
        }
        self.lights.extend(lighting.lights.iter().cloned());
        self.environment = match (&self.environment, &lighting.environment) {
            (Some(own), Some(new)) => Some(Arc::new(new.sum(own))),
            (own, new) => new.clone().or_else(|| own.clone()),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use std::f32::consts::PI;

    fn scene(environment: &str) -> Scene {
        let text = format!(
            r#"{{"camera": {{"position": [0, 0, 3], "look_at": [0, 0, 0]}},
                "lights": [{{"type": "point", "position": [0, 2, 0], "intensity": [1, 1, 1]}}],
                "materials": {{"m": {{"diffuse": [0.5, 0.5, 0.5]}}}},
                "objects": [{{"shape": {{"type": "sphere", "radius": 1}}, "material": "m"}}]{environment}}}"#
        );
        Scene::from_json(&text, "test", &HashMap::new()).unwrap()
    }

    fn lighting(env: Option<&str>, lights: Option<&str>, add: bool) -> Result<Lighting> {
        Lighting::from_json(env, &HashMap::new(), lights, add, "cli")
    }

    #[test]
    fn added_lighting_keeps_the_lights_and_sums_the_environments() {
        let sun = r#"[{"type": "directional", "direction": [0, -1, 0], "irradiance": [2, 2, 2]}]"#;
        let env = r#"{"radiance": [0.5, 0.5, 0.5], "intensity": 2}"#;
        let l = lighting(Some(env), Some(sun), true).unwrap();
        let lit = scene("").with_lighting(&l);
        assert_eq!(lit.lights.len(), 2);
        assert_eq!(
            lit.environment.as_ref().unwrap().radiance(Vec3::Y),
            Vec3::ONE
        );
        // A scene with its own sky: the two add up, in every direction.
        let own = r#", "environment": {"radiance": [0.25, 0.5, 1]}"#;
        let lit = scene(own).with_lighting(&l);
        let e = lit.environment.as_ref().unwrap();
        for d in [Vec3::Y, Vec3::X, -Vec3::Z] {
            assert_eq!(e.radiance(d), Vec3::new(1.25, 1.5, 2.0));
        }
    }

    #[test]
    fn an_image_plus_a_rotated_image_is_their_sum_in_every_texel_direction() {
        // Two 8×4 images of distinct texels, the second turned by 90°: the sum, on the
        // first's grid, is each texel's own radiance plus the second's along its centre.
        let img = |k: f32| EnvImage {
            width: 8,
            height: 4,
            texels: (0..32).map(|i| Vec3::splat(k + i as f32)).collect(),
        };
        let a = Environment::image(img(1.0), 2.0, 30.0);
        let b = Environment::image(img(100.0), 0.5, 120.0);
        let s = a.sum(&b);
        for i in 0..32 {
            let (u, theta) = ((i % 8) as f32 + 0.5, ((i / 8) as f32 + 0.5) / 4.0 * PI);
            let phi = 2.0 * PI * u / 8.0;
            let local = Vec3::new(
                theta.sin() * phi.sin(),
                theta.cos(),
                -theta.sin() * phi.cos(),
            );
            let r = 30f32.to_radians();
            let d = Vec3::new(
                r.cos() * local.x + r.sin() * local.z,
                local.y,
                -r.sin() * local.x + r.cos() * local.z,
            );
            let want = a.radiance(d) + b.radiance(d);
            assert!(
                (s.radiance(d) - want).abs().max_element() < 1e-3,
                "{i}: {} vs {want}",
                s.radiance(d)
            );
        }
    }

    #[test]
    fn replacing_lighting_drops_the_scenes_lights_and_sky() {
        let own = r#", "environment": {"radiance": [0.25, 0.5, 1]}"#;
        let l = lighting(Some(r#"{"radiance": [1, 1, 1]}"#), None, false).unwrap();
        let lit = scene(own).with_lighting(&l);
        assert!(lit.lights.is_empty());
        assert_eq!(
            lit.environment.as_ref().unwrap().radiance(Vec3::Y),
            Vec3::ONE
        );
    }

    #[test]
    fn errors_name_the_field() {
        let e = lighting(
            Some(r#"{"radiance": [1, 1, 1], "intensity": -1}"#),
            None,
            true,
        );
        assert!(e.unwrap_err().to_string().contains("environment.intensity"));
        let e = lighting(Some(r#"{"radiance": [1, 1, 1], "x": 1}"#), None, true);
        assert!(e.unwrap_err().to_string().contains("environment"));
        let bad = r#"[{"type": "directional", "direction": [0, 0, 0], "irradiance": [1, 1, 1]}]"#;
        let e = lighting(None, Some(bad), true).unwrap_err();
        assert!(e.to_string().contains("lights[0]."), "{e}");
    }
}
