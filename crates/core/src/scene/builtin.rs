//! Built-in scenes, stored as JSON scene descriptions (primitives only) in `crates/core/scenes/`.

use super::Scene;
use crate::error::{Error, Result};
use std::collections::HashMap;

/// (name, description, JSON text) of every built-in scene; the first is the default.
pub const BUILTINS: &[(&str, &str, &str)] = &[
    (
        "cornell",
        "Cornell box, one point light below the ceiling",
        include_str!("../../scenes/cornell.json"),
    ),
    (
        "cornell-glass",
        "Cornell box with a glass and a mirror sphere (refractive and reflective caustics)",
        include_str!("../../scenes/cornell-glass.json"),
    ),
    (
        "cornell-anim",
        "Cornell box animated over 4 s: the light circles, the tall box slides and turns",
        include_str!("../../scenes/cornell-anim.json"),
    ),
    (
        "caustic-ring",
        "mirror ring on a diffuse floor: cardioid caustic",
        include_str!("../../scenes/caustic-ring.json"),
    ),
    (
        "mirror-shadow",
        "mirror sphere throwing a dim, spread-out caustic onto a floor a wall shadows",
        include_str!("../../scenes/mirror-shadow.json"),
    ),
    (
        "ring-room",
        "the caustic-ring's mirror ring in a closed white room (caustic amid indirect light)",
        include_str!("../../scenes/ring-room.json"),
    ),
    (
        "furnace",
        "closed diffuse sphere (R = 1, albedo 0.5), point light (I = 1) at its centre",
        include_str!("../../scenes/furnace.json"),
    ),
];

/// The JSON text of a built-in scene.
pub fn json(name: &str) -> Option<&'static str> {
    BUILTINS
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, _, j)| *j)
}

/// Loads a built-in scene by name.
pub fn load(name: &str) -> Result<Scene> {
    let text = json(name).ok_or_else(|| Error::Scene {
        source_name: name.to_string(),
        field: "(name)".into(),
        message: format!(
            "no built-in scene named `{name}` (available: {})",
            BUILTINS.iter().map(|b| b.0).collect::<Vec<_>>().join(", ")
        ),
    })?;
    Scene::from_json(text, name, &HashMap::new())
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_builtin_loads() {
        for (name, _, _) in super::BUILTINS {
            let s = super::load(name).unwrap();
            assert!(
                !s.flat().triangles.is_empty() && !s.lights.is_empty(),
                "{name}"
            );
        }
        assert!(super::load("nope").is_err());
    }
}
