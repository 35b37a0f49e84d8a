//! Keyframed animation: the scene description's optional `animation` section.
//!
//! A track animates some fields of one target (the camera, a light, an object's transform, a
//! material) through keys at increasing times (seconds). At time `t` every animated target
//! takes its description at rest with the animated fields replaced by the tracks' values
//! ([`Animation::values_at`]); [`Scene::animation_at`] turns those into [`SceneUpdate`]s.
//! Numbers and vectors are interpolated linearly per component (an object's `translate`,
//! `rotate` in degrees and `scale` each on their own), booleans and strings step; before the
//! first key and after the last the end keys hold.
//!
//! Everything is validated when the scene is loaded: times increase, targets exist, the
//! fields can be animated and every key's value is a valid description. Values between keys
//! are checked again when evaluated (two valid camera keys can pass through a degenerate
//! pose), so an error names the time.

use super::desc::{AnimationDesc, Interpolation, SceneDesc, TrackDesc, TrackTarget};
use super::update::UpdateTarget;
use super::{camera_from_desc, light_from_desc, material_from_desc, Scene, SceneUpdate};
use crate::error::{Error, Result};
use serde_json::{Map, Value};

/// The fields a track of each target may animate.
fn animatable(target: TrackTarget) -> &'static [&'static str] {
    match target {
        TrackTarget::Camera => &["position", "look_at", "up", "fov"],
        TrackTarget::Light => &[
            "position",
            "direction",
            "intensity",
            "inner_angle",
            "outer_angle",
            "irradiance",
            "angular_diameter",
        ],
        TrackTarget::Object => &["translate", "rotate", "scale", "matrix"],
        TrackTarget::Material => &[
            "diffuse",
            "specular",
            "roughness",
            "fresnel",
            "transmission",
            "ior",
            "emission",
            "two_sided",
        ],
    }
}

/// A validated animation.
#[derive(Clone, Debug)]
pub struct Animation {
    duration: f64,
    /// Every animated target with its description at rest (scene format; an object's is its
    /// transform), in order of first appearance.
    targets: Vec<(UpdateTarget, Map<String, Value>)>,
    tracks: Vec<Track>,
}

#[derive(Clone, Debug)]
struct Track {
    /// Index into `Animation::targets`.
    target: usize,
    times: Vec<f64>,
    values: Vec<Map<String, Value>>,
    interpolation: Interpolation,
}

/// `a` to `b` at `s` in [0, 1]: numbers and arrays of numbers per component (a number
/// against an array broadcasts, as a uniform `scale` against a triple), anything else steps
/// (`a`). `None` when the two cannot be interpolated (different types or lengths).
fn lerp(a: &Value, b: &Value, s: f64) -> Option<Value> {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64()?, y.as_f64()?);
            let v = if x == y { x } else { x + (y - x) * s };
            serde_json::Number::from_f64(v).map(Value::Number)
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .map(|(x, y)| lerp(x, y, s))
            .collect::<Option<Vec<_>>>()
            .map(Value::Array),
        (Value::Number(_), Value::Array(y)) => lerp(&Value::Array(vec![a.clone(); y.len()]), b, s),
        (Value::Array(x), Value::Number(_)) => lerp(a, &Value::Array(vec![b.clone(); x.len()]), s),
        (Value::Bool(_), Value::Bool(_)) | (Value::String(_), Value::String(_)) => Some(a.clone()),
        _ => None,
    }
}

impl Track {
    /// The animated fields at time `t`.
    fn sample(&self, t: f64) -> Map<String, Value> {
        let n = self.times.len();
        if n == 1 || t <= self.times[0] {
            return self.values[0].clone();
        }
        if t >= self.times[n - 1] {
            return self.values[n - 1].clone();
        }
        // times[i] <= t < times[i + 1]
        let i = self.times.partition_point(|&x| x <= t) - 1;
        let a = &self.values[i];
        if self.interpolation == Interpolation::Step {
            return a.clone();
        }
        let b = &self.values[i + 1];
        let s = (t - self.times[i]) / (self.times[i + 1] - self.times[i]);
        a.iter()
            .map(|(k, va)| {
                let v = b.get(k).and_then(|vb| lerp(va, vb, s));
                (k.clone(), v.unwrap_or_else(|| va.clone()))
            })
            .collect()
    }
}

/// The fields of an object's transform that a `matrix` excludes.
const TRS: [&str; 3] = ["translate", "rotate", "scale"];

/// `fields` laid over a target's description `rest`: a `matrix` replaces the whole
/// transform (translate/rotate/scale at rest are dropped).
fn overlay(rest: &mut Map<String, Value>, fields: Map<String, Value>) {
    if fields.contains_key("matrix") {
        rest.retain(|k, _| !TRS.contains(&k.as_str()));
    }
    rest.extend(fields);
}

/// JSON of a description (never fails for the description types).
fn to_map<T: serde::Serialize>(v: &T) -> Map<String, Value> {
    match serde_json::to_value(v) {
        Ok(Value::Object(m)) => m,
        _ => Map::new(),
    }
}

/// The field path that `Scene::update_from_json` and `Scene::apply` use for `target`.
fn update_prefix(target: &UpdateTarget) -> String {
    match target {
        UpdateTarget::Camera => "camera".into(),
        UpdateTarget::Light(i) => format!("lights[{i}]"),
        UpdateTarget::Object(i) => format!("objects[{i}].transform"),
        UpdateTarget::Material(name) => format!("materials.{name}"),
    }
}

/// Re-roots an update's error (`lights[0].intensity`) at `field` (`animation.tracks[2]
/// .keys[1].value`) in `source`.
fn reroot(e: Error, target: &UpdateTarget, source: &str, field: &str) -> Error {
    match e {
        Error::Scene {
            field: f, message, ..
        } => {
            let rest = f.strip_prefix(&update_prefix(target)).unwrap_or("");
            Error::scene(source, format!("{field}{rest}"), message)
        }
        other => other,
    }
}

impl Scene {
    /// Validates an update's values as `Scene::apply` would, without applying it.
    fn check_update(&self, u: &SceneUpdate) -> Result<()> {
        let err = |field: String, msg: &str| Error::scene("scene update", field, msg);
        match u {
            SceneUpdate::Camera(desc) => {
                let desc = super::desc::CameraDesc {
                    width: self.camera.width,
                    height: self.camera.height,
                    ..desc.clone()
                };
                camera_from_desc(&desc).map_err(|(f, m)| err(format!("camera.{f}"), m))?;
            }
            SceneUpdate::Light { index, light } => {
                light_from_desc(light).map_err(|(f, m)| err(format!("lights[{index}].{f}"), m))?;
            }
            SceneUpdate::Material { name, material } => {
                material_from_desc(material)
                    .map_err(|(f, m)| err(format!("materials.{name}.{f}"), m))?;
            }
            // `update_from_json` validated the transform (finite, non-zero scale).
            SceneUpdate::Transform { .. } => {}
        }
        Ok(())
    }

    /// Length of the scene's animation in seconds (`None`: the scene has no `animation`).
    pub fn animation_duration(&self) -> Option<f64> {
        self.animation.as_ref().map(|a| a.duration)
    }

    /// The animated targets' descriptions at time `t` (seconds), validated: the description
    /// at rest with the animated fields replaced (an object's: its whole transform). Empty
    /// without an animation.
    pub fn animation_values(&self, t: f64) -> Result<Vec<(UpdateTarget, Value)>> {
        Ok(self
            .animation_evaluate(t)?
            .into_iter()
            .map(|(target, value, _)| (target, value))
            .collect())
    }

    /// The scene updates that pose the scene at time `t` (seconds), validated: applying
    /// them in order cannot fail. Empty without an animation.
    pub fn animation_at(&self, t: f64) -> Result<Vec<SceneUpdate>> {
        Ok(self
            .animation_evaluate(t)?
            .into_iter()
            .map(|(_, _, u)| u)
            .collect())
    }

    fn animation_evaluate(&self, t: f64) -> Result<Vec<(UpdateTarget, Value, SceneUpdate)>> {
        if !t.is_finite() {
            return Err(Error::setting("time", format!("must be finite, got {t}")));
        }
        let Some(anim) = &self.animation else {
            return Ok(Vec::new());
        };
        let source = format!("animation at t = {t} s");
        anim.values_at(t)
            .into_iter()
            .map(|(target, value)| {
                let u = self
                    .update_from_json(&target, &value)
                    .and_then(|u| self.check_update(&u).map(|_| u))
                    .map_err(|e| reroot(e, &target, &source, &update_prefix(&target)))?;
                Ok((target, value, u))
            })
            .collect()
    }
}

impl Animation {
    /// Length in seconds: the description's `duration`, else the last key's time.
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// Every animated target's description at time `t` (seconds), not yet validated (see
    /// [`Scene::animation_values`]).
    pub fn values_at(&self, t: f64) -> Vec<(UpdateTarget, Value)> {
        let mut out = self.targets.clone();
        for track in &self.tracks {
            overlay(&mut out[track.target].1, track.sample(t));
        }
        out.into_iter()
            .map(|(target, m)| (target, Value::Object(m)))
            .collect()
    }

    /// Validates the `animation` section of `desc` against the scene built from it.
    pub(crate) fn from_desc(
        anim: &AnimationDesc,
        desc: &SceneDesc,
        scene: &Scene,
        source: &str,
    ) -> Result<Animation> {
        let mut out = Animation {
            duration: 0.0,
            targets: Vec::new(),
            tracks: Vec::new(),
        };
        // (target index, field, track index) of every animated field so far.
        let mut animated: Vec<(usize, String, usize)> = Vec::new();
        for (i, track) in anim.tracks.iter().enumerate() {
            let at = format!("animation.tracks[{i}]");
            let err = |field: &str, msg: String| Error::scene(source, format!("{at}{field}"), msg);
            let (target, rest) = resolve_target(track, desc, scene).map_err(|(f, m)| err(f, m))?;
            let ti = match out.targets.iter().position(|(t, _)| *t == target) {
                Some(ti) => ti,
                None => {
                    out.targets.push((target.clone(), rest));
                    out.targets.len() - 1
                }
            };
            if track.keys.is_empty() {
                return Err(err(".keys", "needs at least one key".into()));
            }
            let allowed = animatable(track.target);
            let first: Vec<&String> = track.keys[0].value.keys().collect();
            for (k, key) in track.keys.iter().enumerate() {
                let kat = format!(".keys[{k}]");
                if !key.time.is_finite() || key.time < 0.0 {
                    return Err(err(
                        &format!("{kat}.time"),
                        "must be finite and non-negative (seconds)".into(),
                    ));
                }
                if k > 0 && key.time <= track.keys[k - 1].time {
                    return Err(err(
                        &format!("{kat}.time"),
                        format!(
                            "times must increase: {} is not after keys[{}].time = {}",
                            key.time,
                            k - 1,
                            track.keys[k - 1].time
                        ),
                    ));
                }
                if key.value.is_empty() {
                    return Err(err(
                        &format!("{kat}.value"),
                        format!("gives no field (animatable: {})", allowed.join(", ")),
                    ));
                }
                for f in key.value.keys() {
                    if !allowed.contains(&f.as_str()) {
                        let what = format!("{:?}", track.target).to_lowercase();
                        return Err(err(
                            &format!("{kat}.value.{f}"),
                            format!(
                                "cannot be animated (a {what} track animates {})",
                                allowed.join(", ")
                            ),
                        ));
                    }
                }
                let fields: Vec<&String> = key.value.keys().collect();
                if fields != first {
                    return Err(err(
                        &format!("{kat}.value"),
                        format!(
                            "every key of a track gives the same fields: {} here, {} in keys[0]",
                            fields
                                .iter()
                                .map(|s| s.as_str())
                                .collect::<Vec<_>>()
                                .join(", "),
                            first
                                .iter()
                                .map(|s| s.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    ));
                }
                if k > 0 {
                    let prev = &track.keys[k - 1].value;
                    for (f, v) in &key.value {
                        if lerp(&prev[f], v, 0.5).is_none() {
                            return Err(err(
                                &format!("{kat}.value.{f}"),
                                format!(
                                    "cannot be interpolated from keys[{}] (different types or lengths)",
                                    k - 1
                                ),
                            ));
                        }
                    }
                }
                // The key's value on the description at rest must be a valid description.
                let mut full = out.targets[ti].1.clone();
                overlay(&mut full, key.value.clone());
                let value_at = format!("{at}{kat}.value");
                scene
                    .update_from_json(&target, &Value::Object(full))
                    .and_then(|u| scene.check_update(&u))
                    .map_err(|e| reroot(e, &target, source, &value_at))?;
            }
            for f in first {
                let clash = already_animated(&animated, ti, f);
                clash.map_or(Ok(()), |m| Err(err(&format!(".keys[0].value.{f}"), m)))?;
                animated.push((ti, f.clone(), i));
            }
            out.tracks.push(Track {
                target: ti,
                times: track.keys.iter().map(|k| k.time).collect(),
                values: track.keys.iter().map(|k| k.value.clone()).collect(),
                interpolation: track.interpolation,
            });
        }
        let last = out
            .tracks
            .iter()
            .filter_map(|t| t.times.last().copied())
            .fold(0.0, f64::max);
        out.duration = match anim.duration {
            Some(d) if d.is_finite() && d > 0.0 => d,
            Some(_) => {
                return Err(Error::scene(
                    source,
                    "animation.duration",
                    "must be positive and finite (seconds)",
                ))
            }
            None => last,
        };
        Ok(out)
    }
}

/// Why field `f` of target `ti` cannot be animated by another track, given the (target,
/// field, track) triples `animated` so far: the field is animated already, or a `matrix`
/// and translate/rotate/scale would describe one transform two ways.
fn already_animated(animated: &[(usize, String, usize)], ti: usize, f: &str) -> Option<String> {
    if let Some((_, _, j)) = animated.iter().find(|(t, g, _)| *t == ti && g == f) {
        return Some(format!("already animated by animation.tracks[{j}]"));
    }
    let is_trs = |g: &str| TRS.contains(&g);
    let excludes = |g: &str| (f == "matrix" && is_trs(g)) || (is_trs(f) && g == "matrix");
    let (_, g, j) = animated.iter().find(|(t, g, _)| *t == ti && excludes(g))?;
    Some(format!(
        "`matrix` excludes translate/rotate/scale (animation.tracks[{j}] animates `{g}`)"
    ))
}

/// A track's error: the field under `animation.tracks[i]` (`.index`) and the message.
type TrackError = (&'static str, String);

/// The update target of a track and the description at rest of what it animates.
fn resolve_target(
    track: &TrackDesc,
    desc: &SceneDesc,
    scene: &Scene,
) -> std::result::Result<(UpdateTarget, Map<String, Value>), TrackError> {
    let no = |field: &'static str, what: &str| -> std::result::Result<(), TrackError> {
        Err((field, format!("a {what} track takes no `{}`", &field[1..])))
    };
    match track.target {
        TrackTarget::Camera => {
            if track.index.is_some() {
                no(".index", "camera")?;
            }
            if track.name.is_some() {
                no(".name", "camera")?;
            }
            let mut rest = to_map(&desc.camera);
            rest.remove("width");
            rest.remove("height");
            Ok((UpdateTarget::Camera, rest))
        }
        TrackTarget::Light => {
            if track.name.is_some() {
                no(".name", "light (lights are addressed by `index`)")?;
            }
            let i = track
                .index
                .ok_or((".index", "a light track needs the light's `index`".into()))?;
            let light = desc.lights.get(i).ok_or_else(|| {
                (
                    ".index",
                    format!("no such light (the scene has {})", desc.lights.len()),
                )
            })?;
            Ok((UpdateTarget::Light(i), to_map(light)))
        }
        TrackTarget::Object => {
            let i = match (&track.name, track.index) {
                (Some(_), Some(_)) => {
                    return Err((
                        ".index",
                        "give the object's `name` or `index`, not both".into(),
                    ))
                }
                (Some(name), None) => scene
                    .object_index(name)
                    .ok_or_else(|| (".name", format!("no object named `{name}`")))?,
                (None, Some(i)) if i < desc.objects.len() => i,
                (None, Some(_)) => {
                    return Err((
                        ".index",
                        format!("no such object (the scene has {})", desc.objects.len()),
                    ))
                }
                (None, None) => {
                    return Err((".name", "an object track needs the object's `name`".into()))
                }
            };
            // An object described by a matrix: at rest, the matrix taken apart into
            // translate/rotate/scale where it has no shear (so that a `translate` track
            // moves it), else the matrix itself.
            let rest = match scene.object_desc(i) {
                Some(Ok(d)) if desc.objects[i].transform.matrix.is_some() => to_map(&d),
                Some(Err(rows)) => {
                    let mut m = Map::new();
                    m.insert("matrix".into(), serde_json::json!(rows));
                    m
                }
                _ => to_map(&desc.objects[i].transform),
            };
            Ok((UpdateTarget::Object(i), rest))
        }
        TrackTarget::Material => {
            if track.index.is_some() {
                no(".index", "material (materials are addressed by `name`)")?;
            }
            let name = track.name.clone().ok_or((
                ".name",
                "a material track needs the material's `name`".into(),
            ))?;
            let rest = match desc.materials.get(&name) {
                Some(m) => to_map(m),
                None => to_map(
                    &scene
                        .material_desc(&name)
                        .ok_or_else(|| (".name", format!("no material named `{name}`")))?,
                ),
            };
            Ok((UpdateTarget::Material(name), rest))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;
    use serde_json::json;
    use std::collections::HashMap;

    /// The built-in Cornell box (named objects) with `animation` as its animation section.
    fn with_animation(animation: Value) -> Result<Scene> {
        let mut desc: Value =
            serde_json::from_str(builtin::json("cornell-anim").expect("built-in")).expect("json");
        desc["animation"] = animation;
        Scene::from_json(&desc.to_string(), "test.json", &HashMap::new())
    }

    fn light_position(u: &[SceneUpdate], index: usize) -> [f32; 3] {
        u.iter()
            .find_map(|u| match u {
                SceneUpdate::Light {
                    index: i,
                    light: crate::scene::desc::LightDesc::Point { position, .. },
                } if *i == index => Some(*position),
                _ => None,
            })
            .expect("light update")
    }

    fn close(a: [f32; 3], b: [f32; 3]) -> bool {
        // f32 round-off of a lerp between values of order 1.
        a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-6)
    }

    /// The built-in animation: linear between keys, the end keys held outside, the object's
    /// transform from its interpolated translate/rotate and its described scale.
    #[test]
    fn builtin_animation_evaluates() {
        let scene = builtin::load("cornell-anim").expect("scene");
        assert_eq!(scene.animation_duration(), Some(4.0));
        let u = scene.animation_at(0.25).expect("valid");
        assert_eq!(u.len(), 2, "one update per animated target");
        assert!(close(
            light_position(&u, 0),
            [(0.45 + 0.3182) / 2.0, 1.6, 0.3182 / 2.0]
        ));
        for (t, expect) in [(-1.0, [0.45, 1.6, 0.0]), (0.0, [0.45, 1.6, 0.0])] {
            assert!(close(
                light_position(&scene.animation_at(t).expect("valid"), 0),
                expect
            ));
        }
        assert!(close(
            light_position(&scene.animation_at(99.0).expect("valid"), 0),
            [0.45, 1.6, 0.0]
        ));
        assert!(close(
            light_position(&scene.animation_at(2.0).expect("valid"), 0),
            [-0.45, 1.6, 0.0]
        ));
        // The tall box at t = 1.5: halfway between keys 1 and 2.
        let tall = scene.object_index("tall box").expect("named");
        let transform = scene
            .animation_at(1.5)
            .expect("valid")
            .into_iter()
            .find_map(|u| match u {
                SceneUpdate::Transform { object, transform } if object == tall => Some(transform),
                _ => None,
            })
            .expect("transform update");
        let expect = crate::scene::transform_matrix(&crate::scene::desc::TransformDesc {
            translate: [-0.5, 0.6, -0.05],
            rotate: [0.0, 35.0, 0.0],
            scale: crate::scene::desc::Scale::Uniform(1.0),
            matrix: None,
        })
        .expect("valid");
        assert!(transform.abs_diff_eq(expect, 1e-6), "{transform} {expect}");
        // Applying the updates moves the box's vertices there.
        let mut posed = scene.clone();
        for u in scene.animation_at(1.5).expect("valid") {
            posed.apply(&u).expect("valid");
        }
        let r = posed.objects[tall].vertices.clone();
        let local = posed.meshes[posed.objects[tall].mesh as usize].positions[0];
        assert!(
            (posed.flat().positions[r.start as usize] - expect.transform_point3(local)).length()
                < 1e-5
        );
        // A scene without an animation has none.
        let still = builtin::load("cornell").expect("scene");
        assert_eq!(still.animation_duration(), None);
        assert!(still.animation_at(1.0).expect("valid").is_empty());
    }

    /// Step interpolation holds each key; in linear tracks booleans step; a uniform scale
    /// interpolates against a triple; two tracks on one light merge into one update.
    #[test]
    fn step_booleans_scale_and_merged_tracks() {
        let scene = with_animation(json!({"tracks": [
            {"target": "light", "index": 0, "interpolation": "step", "keys": [
                {"time": 0, "value": {"intensity": [1, 1, 1]}},
                {"time": 1, "value": {"intensity": [5, 5, 5]}}]},
            {"target": "light", "index": 0, "keys": [
                {"time": 0, "value": {"position": [0, 1, 0]}},
                {"time": 2, "value": {"position": [0, 1.8, 0]}}]},
            {"target": "material", "name": "red", "keys": [
                {"time": 0, "value": {"fresnel": false, "roughness": 0.2}},
                {"time": 1, "value": {"fresnel": true, "roughness": 0.6}}]},
            {"target": "object", "name": "short box", "keys": [
                {"time": 0, "value": {"scale": 1}},
                {"time": 1, "value": {"scale": [1, 2, 3]}}]}
        ]}))
        .expect("valid");
        assert_eq!(scene.animation_duration(), Some(2.0), "the last key's time");
        let values = scene.animation_values(0.5).expect("valid");
        assert_eq!(values.len(), 3);
        let light = &values[0];
        assert_eq!(light.0, UpdateTarget::Light(0));
        assert_eq!(nums(&light.1["intensity"]), [1.0; 3], "step");
        assert_eq!(nums(&light.1["position"]), [0.0, 1.2, 0.0]);
        assert_eq!(
            light.1["type"],
            json!("point"),
            "the rest of the description"
        );
        let values = scene.animation_values(1.0).expect("valid");
        assert_eq!(nums(&values[0].1["intensity"]), [5.0; 3]);
        let mat = &scene.animation_values(0.75).expect("valid")[1];
        assert_eq!(mat.0, UpdateTarget::Material("red".into()));
        assert_eq!(mat.1["fresnel"], json!(false), "booleans step");
        assert!((mat.1["roughness"].as_f64().expect("number") - 0.5).abs() < 1e-12);
        assert_eq!(
            nums(&mat.1["diffuse"]),
            nums(&scene_value("red")),
            "fields not animated are kept"
        );
        let obj = &scene.animation_values(0.5).expect("valid")[2];
        assert_eq!(nums(&obj.1["scale"]), [1.0, 1.5, 2.0]);
        assert_eq!(nums(&obj.1["rotate"]), [0.0, -17.0, 0.0]);
    }

    /// The numbers of a JSON array (integers and floats alike).
    fn nums(v: &Value) -> Vec<f64> {
        v.as_array()
            .expect("array")
            .iter()
            .map(|x| x.as_f64().expect("number"))
            .collect()
    }

    fn scene_value(material: &str) -> Value {
        let desc: Value =
            serde_json::from_str(builtin::json("cornell-anim").expect("built-in")).expect("json");
        let d = &desc["materials"][material]["diffuse"];
        // As the description's f32 fields serialise.
        Value::Array(
            d.as_array()
                .expect("array")
                .iter()
                .map(|v| json!(v.as_f64().expect("number") as f32 as f64))
                .collect(),
        )
    }

    /// Every kind of malformed animation is a scene error naming the field.
    #[test]
    fn errors_name_the_field() {
        let key = |t: f64, v: Value| json!({"time": t, "value": v});
        let light =
            |keys: Vec<Value>| json!({"tracks": [{"target": "light", "index": 0, "keys": keys}]});
        let p = |x: f64| json!({"position": [x, 1, 0]});
        let cases = [
            (
                light(vec![key(1.0, p(0.0)), key(1.0, p(1.0))]),
                "animation.tracks[0].keys[1].time",
                "increase",
            ),
            (
                light(vec![key(-1.0, p(0.0))]),
                "animation.tracks[0].keys[0].time",
                "non-negative",
            ),
            (light(vec![]), "animation.tracks[0].keys", "at least one"),
            (
                json!({"tracks": [{"target": "light", "index": 3, "keys": [key(0.0, p(0.0))]}]}),
                "animation.tracks[0].index",
                "no such light",
            ),
            (
                json!({"tracks": [{"target": "object", "name": "teapot", "keys": [key(0.0, json!({"translate": [0, 0, 0]}))]}]}),
                "animation.tracks[0].name",
                "teapot",
            ),
            (
                json!({"tracks": [{"target": "material", "name": "gold", "keys": [key(0.0, json!({"roughness": 0.1}))]}]}),
                "animation.tracks[0].name",
                "gold",
            ),
            (
                json!({"tracks": [{"target": "camera", "index": 0, "keys": [key(0.0, json!({"fov": 30}))]}]}),
                "animation.tracks[0].index",
                "camera",
            ),
            (
                json!({"tracks": [{"target": "sun", "keys": []}]}),
                "animation.tracks[0].target",
                "unknown variant",
            ),
            (
                json!({"tracks": [{"target": "camera", "keys": [key(0.0, json!({"width": 64}))]}]}),
                "animation.tracks[0].keys[0].value.width",
                "cannot be animated",
            ),
            (
                json!({"tracks": [{"target": "object", "name": "tall box", "keys": [key(0.0, json!({"matrix": [[1, 0, 0, 0]]}))]}]}),
                "animation.tracks[0].keys[0].value.matrix",
                "3 or 4 rows of 4 numbers",
            ),
            (
                light(vec![
                    key(0.0, p(0.0)),
                    key(1.0, json!({"intensity": [1, 1, 1]})),
                ]),
                "animation.tracks[0].keys[1].value",
                "same fields",
            ),
            (
                light(vec![
                    key(0.0, p(0.0)),
                    key(1.0, json!({"position": [1, 1]})),
                ]),
                "animation.tracks[0].keys[1].value.position",
                "interpolated",
            ),
            (
                light(vec![
                    key(0.0, json!({"intensity": [1, 1, 1]})),
                    key(1.0, json!({"intensity": [1, -1, 1]})),
                ]),
                "animation.tracks[0].keys[1].value.intensity",
                "non-negative",
            ),
            (
                light(vec![key(0.0, json!({"direction": [0, -1, 0]}))]),
                "animation.tracks[0].keys[0].value",
                "direction",
            ),
            (
                json!({"tracks": [
                    {"target": "light", "index": 0, "keys": [key(0.0, p(0.0))]},
                    {"target": "light", "index": 0, "keys": [key(0.0, p(1.0))]}]}),
                "animation.tracks[1].keys[0].value.position",
                "already animated by animation.tracks[0]",
            ),
            (
                json!({"duration": -1, "tracks": []}),
                "animation.duration",
                "positive",
            ),
            (
                json!({"tracks": [{"target": "light", "index": 0, "keys": [key(0.0, p(0.0))], "interp": "step"}]}),
                "animation.tracks[0]",
                "interp",
            ),
        ];
        for (anim, field, message) in cases {
            let e = with_animation(anim.clone()).expect_err(&anim.to_string());
            match &e {
                Error::Scene {
                    source_name,
                    field: f,
                    message: m,
                } => {
                    assert_eq!(source_name, "test.json");
                    assert!(f.starts_with(field), "{f} for {anim}: {m}");
                    assert!(m.contains(message) || f.contains(message), "{e}");
                }
                other => panic!("{other}"),
            }
        }
    }

    /// Valid keys can interpolate to an invalid pose: the error names the time and field.
    #[test]
    fn degenerate_pose_between_keys_is_an_error() {
        let scene = with_animation(json!({"tracks": [{"target": "camera", "keys": [
            {"time": 0, "value": {"position": [0, 1, 1], "look_at": [0, 1, -1]}},
            {"time": 1, "value": {"position": [0, 1, -1], "look_at": [0, 1, 1]}}]}]}))
        .expect("the keys are valid");
        assert!(scene.animation_at(0.25).is_ok());
        let e = scene.animation_at(0.5).expect_err("camera on its target");
        assert!(
            e.to_string()
                .starts_with("animation at t = 0.5 s: camera.look_at: must differ"),
            "{e}"
        );
        assert!(matches!(
            scene.animation_at(f64::NAN),
            Err(Error::Setting { name: "time", .. })
        ));
    }

    /// Interpolation of JSON values.
    #[test]
    fn lerp_values() {
        assert_eq!(lerp(&json!(1.0), &json!(3.0), 0.25), Some(json!(1.5)));
        assert_eq!(
            lerp(&json!([0, 2]), &json!([4, 2]), 0.5),
            Some(json!([2.0, 2.0]))
        );
        assert_eq!(lerp(&json!("a"), &json!("b"), 0.9), Some(json!("a")));
        assert_eq!(lerp(&json!([1, 2]), &json!([1, 2, 3]), 0.5), None);
        assert_eq!(lerp(&json!(true), &json!(1), 0.5), None);
        // Exactly the key at s = 0, whatever the other end.
        assert_eq!(lerp(&json!(0.1), &json!(1e30), 0.0), Some(json!(0.1)));
    }
}
