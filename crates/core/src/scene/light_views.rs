//! Light views: where the passes that look from the lights (shadow maps, ISPM bounce maps,
//! reflective shadow maps) look, at what resolution, and the view math they share. Pure
//! geometry over the scene: the raster passes render these views, the CPU traces the same
//! photons through them (`photon::bounce`).

use crate::error::{Error, Result};
use crate::scene::{Bounds, Light, Scene};
use glam::{Mat4, Vec2, Vec3, Vec4};

/// Cube faces in layer order: forward and up vectors.
pub const CUBE_FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::Y),
    (Vec3::NEG_X, Vec3::Y),
    (Vec3::Y, Vec3::Z),
    (Vec3::NEG_Y, Vec3::Z),
    (Vec3::Z, Vec3::Y),
    (Vec3::NEG_Z, Vec3::Y),
];

/// Largest light-view side (texels).
const MAX_VIEW_RES: u32 = 4096;
/// Widest spot cone a light view covers (tan of the half angle, about 84°).
const MAX_SPOT_TAN: f32 = 10.0;
/// Extra field of view of the shadow maps, in shadow texels on each side, so PCF taps near
/// a view's border stay inside it.
const SHADOW_MARGIN_TEXELS: f32 = 8.0;
/// The layered targets of light views (plus their readback copies) stay within this many
/// bytes.
const MAX_LAYER_BYTES: u64 = 2 << 30;

/// World -> view for an eye at `eye` looking along `dir` (right-handed, looking down −z).
pub fn look_to(eye: Vec3, dir: Vec3, up: Vec3) -> Mat4 {
    let f = dir.normalize();
    let s = f.cross(up).normalize();
    let u = s.cross(f);
    Mat4::from_cols(
        Vec4::new(s.x, u.x, -f.x, 0.0),
        Vec4::new(s.y, u.y, -f.y, 0.0),
        Vec4::new(s.z, u.z, -f.z, 0.0),
        Vec4::new(-eye.dot(s), -eye.dot(u), eye.dot(f), 1.0),
    )
}

/// View -> clip with depth in [0, 1] (WebGPU), vertical field of view `fov_y` in radians.
pub fn perspective(fov_y: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
    let h = 1.0 / (0.5 * fov_y).tan();
    let r = far / (near - far);
    Mat4::from_cols(
        Vec4::new(h / aspect, 0.0, 0.0, 0.0),
        Vec4::new(0.0, h, 0.0, 0.0),
        Vec4::new(0.0, 0.0, r, -1.0),
        Vec4::new(0.0, 0.0, r * near, 0.0),
    )
}

/// A square view of half-width `tan_half` at unit distance.
pub fn square_perspective(tan_half: f32, near: f32, far: f32) -> Mat4 {
    perspective(2.0 * tan_half.atan(), 1.0, near, far)
}

/// View -> clip of a square orthographic view of half-width `half`, depth 0 at the eye to 1
/// at `depth` along the view axis (WebGPU's depth range).
pub fn orthographic(half: f32, depth: f32) -> Mat4 {
    Mat4::from_cols(
        Vec4::new(1.0 / half, 0.0, 0.0, 0.0),
        Vec4::new(0.0, 1.0 / half, 0.0, 0.0),
        Vec4::new(0.0, 0.0, -1.0 / depth, 0.0),
        Vec4::new(0.0, 0.0, 0.0, 1.0),
    )
}

/// An orthographic view along the unit direction `dir` (the way the light travels) that
/// covers the sphere `bounds`, its square `grow` times the sphere's cross-section: world ->
/// clip, the world size of its square's side and its depth extent (world units from depth 0
/// to 1). For distant lights: the sun, the sky's sampled directions.
pub fn orthographic_view(dir: Vec3, bounds: Bounds, grow: f32) -> (Mat4, f32, f32) {
    let r = bounds.radius * 1.01 + 1e-4;
    let eye = bounds.centre - dir * r;
    let up = if dir.y.abs() < 0.99 { Vec3::Y } else { Vec3::X };
    let half = r * grow;
    let depth = 2.0 * r;
    (
        orthographic(half, depth) * look_to(eye, dir, up),
        2.0 * half,
        depth,
    )
}

/// The direction a directional light's shadow is cast along: its axis, or with `u` a
/// direction drawn uniformly from its disc of directions (progressive passes draw a new one
/// each, so that their mean has the disc's penumbra); other lights: their axis or zero.
pub fn distant_direction(light: &Light, u: Option<Vec2>) -> Vec3 {
    match (*light, u) {
        (Light::Directional { direction, .. }, None) => direction,
        (Light::Directional { direction, .. }, Some(u)) => light
            .sample_towards(u)
            .map_or(direction, |(towards, _)| -towards),
        (Light::Spot { direction, .. }, _) => direction,
        _ => Vec3::ZERO,
    }
}

/// Axis-aligned bounds of the scene's vertices.
pub fn bounds(scene: &Scene) -> (Vec3, Vec3) {
    let (lo, hi) = scene.vertex_box();
    if lo.x > hi.x {
        return (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    }
    (lo, hi)
}

/// The eight corners of the box `lo..hi`.
pub fn corners(lo: Vec3, hi: Vec3) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// Views a light needs to see all it lights: a cube of six for a point light, one for a
/// spot light.
pub fn views_of(light: &Light) -> u32 {
    match light {
        Light::Point { .. } => 6,
        Light::Spot { .. } => 1,
        // Distant lights have no perspective views.
        Light::Directional { .. } => 0,
    }
}

/// Shadow-map layers of a light: a cube of six for a point light, one perspective view for a
/// spot light, one orthographic view over the scene for a directional light.
pub fn shadow_layers_of(light: &Light) -> u32 {
    match light {
        Light::Point { .. } => 6,
        Light::Spot { .. } | Light::Directional { .. } => 1,
    }
}

/// Light views of all the scene's lights.
pub fn view_count(scene: &Scene) -> u32 {
    scene.lights.iter().map(views_of).sum()
}

/// Distance from `p` to the farthest corner of the scene's bounds, with a margin.
fn far_from(p: Vec3, lo: Vec3, hi: Vec3) -> f32 {
    corners(lo, hi)
        .map(|c| (c - p).length())
        .into_iter()
        .fold(0.0f32, f32::max)
        * 1.01
        + 1e-3
}

/// A spot light's view axis and up vector.
fn spot_axes(direction: Vec3) -> (Vec3, Vec3) {
    let up = if direction.y.abs() < 0.99 {
        Vec3::Y
    } else {
        Vec3::X
    };
    (direction, up)
}

/// A light's layers among the shadow maps: the first, how many, the world size of a texel
/// at unit distance (perspective views) or of a texel (orthographic views), and an
/// orthographic view's depth extent in world units (0 for perspective views).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowLayers {
    pub first_layer: u32,
    pub layers: u32,
    pub texel_scale: f32,
    pub depth_extent: f32,
}

/// The shadow-map views of the scene's lights for `size`² maps: per light its layers, and
/// world -> clip per layer (a cube of six for a point light, one view for a spot light, an
/// orthographic view over the scene's bounding sphere for a directional light along
/// `directions[i]`, else its axis), depth ranges covering the scene's bounds.
pub fn shadow_views(
    scene: &Scene,
    size: u32,
    directions: Option<&[Vec3]>,
) -> (Vec<ShadowLayers>, Vec<Mat4>) {
    let (lo, hi) = bounds(scene);
    let mut lights = Vec::with_capacity(scene.lights.len());
    let mut matrices = Vec::new();
    let grow = 1.0 + 2.0 * SHADOW_MARGIN_TEXELS / size as f32;
    for (i, light) in scene.lights.iter().enumerate() {
        let first_layer = matrices.len() as u32;
        let p = light.position();
        let far = far_from(p, lo, hi);
        let near = (far * 1e-3).max(1e-5);
        // The world size of a texel (at unit distance for perspective views) and the depth
        // extent of an orthographic view.
        let (texel_scale, depth_extent) = match *light {
            Light::Point { .. } => {
                let t = grow;
                for (forward, up) in CUBE_FACES {
                    matrices.push(square_perspective(t, near, far) * look_to(p, forward, up));
                }
                (2.0 * t / size as f32, 0.0)
            }
            Light::Spot {
                direction,
                cos_outer,
                ..
            } => {
                let t = (cos_outer.acos().tan() * grow).max(1e-3);
                let (forward, up) = spot_axes(direction);
                matrices.push(square_perspective(t, near, far) * look_to(p, forward, up));
                (2.0 * t / size as f32, 0.0)
            }
            Light::Directional { .. } => {
                let dir = directions.map_or_else(|| distant_direction(light, None), |d| d[i]);
                let (m, side, depth) = orthographic_view(dir, scene.bounds(), grow);
                matrices.push(m);
                (side / size as f32, depth)
            }
        };
        lights.push(ShadowLayers {
            first_layer,
            layers: matrices.len() as u32 - first_layer,
            texel_scale,
            depth_extent,
        });
    }
    (lights, matrices)
}

/// One light view whose texels are photons leaving the light (an ISPM bounce-map layer, a
/// reflective-shadow-map layer): the light, the view's resolution and projection, and the
/// corrected texel area.
#[derive(Clone, Copy, Debug)]
pub struct LightView {
    pub light: usize,
    pub res: u32,
    /// World -> clip.
    pub view_proj: Mat4,
    pub position: Vec3,
    /// The view's axis (unit).
    pub forward: Vec3,
    /// Area of a texel at unit distance, corrected so that the light's texels sum to its
    /// power (see [`light_views`]).
    pub texel_area: f32,
}

/// The light views of a scene for a budget of `texels`: resolution per light proportional
/// to its share of the total power, texel areas corrected so that each light's texels sum
/// to its power (a texel's power is I(ω)·A·cos³θ).
pub fn light_views(scene: &Scene, texels: u64) -> Vec<LightView> {
    let (lo, hi) = bounds(scene);
    // The views see the point and spot lights (the others' photons are cast on the CPU).
    let bounds = scene.bounds();
    let total: f32 = scene
        .lights
        .iter()
        .filter(|l| l.is_local())
        .map(|l| l.power(bounds).element_sum())
        .sum();
    let mut views_out = Vec::new();
    for (li, light) in scene.lights.iter().enumerate() {
        let power = light.power(bounds).element_sum();
        if !(power > 0.0 && total > 0.0 && light.is_local()) {
            continue;
        }
        let p = light.position();
        let far = far_from(p, lo, hi);
        let near = (far * 1e-4).max(1e-6);
        let views: Vec<(Vec3, Vec3, f32)> = match *light {
            Light::Point { .. } => CUBE_FACES.iter().map(|&(f, u)| (f, u, 1.0)).collect(),
            Light::Spot {
                direction,
                cos_outer,
                ..
            } => {
                let t = cos_outer.clamp(-1.0, 1.0).acos().tan();
                let t = if t.is_finite() && t > 0.0 {
                    t.clamp(1e-3, MAX_SPOT_TAN)
                } else {
                    MAX_SPOT_TAN
                };
                let (forward, up) = spot_axes(direction);
                vec![(forward, up, t)]
            }
            Light::Directional { .. } => continue,
        };
        let per_view = texels as f64 * (power / total) as f64 / views.len() as f64;
        let res = (per_view.sqrt().round() as u32).clamp(1, MAX_VIEW_RES);
        // Σ over texel centres of falloff·A·cos³θ, for the round-off correction.
        let mut grid = 0.0f64;
        for &(_, _, t) in &views {
            let area = (2.0 * t as f64 / res as f64).powi(2);
            for j in 0..res {
                for i in 0..res {
                    let x = (2.0 * (i as f64 + 0.5) / res as f64 - 1.0) * t as f64;
                    let y = (2.0 * (j as f64 + 0.5) / res as f64 - 1.0) * t as f64;
                    let c = 1.0 / (1.0 + x * x + y * y).sqrt();
                    let falloff = light.falloff(c as f32) as f64;
                    grid += falloff * area * c * c * c;
                }
            }
        }
        let intensity = light.intensity().element_sum() as f64;
        let correction = if grid > 0.0 && intensity > 0.0 {
            power as f64 / (intensity * grid)
        } else {
            0.0
        };
        for (forward, up, t) in views {
            let view_proj = square_perspective(t, near, far) * look_to(p, forward, up);
            let area = (2.0 * t / res as f32).powi(2);
            views_out.push(LightView {
                light: li,
                res,
                view_proj,
                position: p,
                forward: forward.normalize(),
                texel_area: (area as f64 * correction) as f32,
            });
        }
    }
    views_out
}

/// The targets rendered per light view, in errors and labels.
pub struct LayerKind {
    /// Label prefix and the name in errors ("bounce map", "reflective shadow map").
    pub name: &'static str,
    /// The setting that sizes the layers (named by the errors).
    pub setting: &'static str,
    /// One label per target.
    pub targets: &'static [&'static str],
}

/// The ISPM bounce maps' five targets. Traced maps (`photon::bounce`) keep the same memory
/// bound, so that `photons` means the same on every device.
pub const BOUNCE_MAPS: LayerKind = LayerKind {
    name: "bounce map",
    setting: "photons",
    targets: &[
        "bounce origin",
        "bounce direction",
        "bounce power",
        "bounce incident",
        "bounce expected",
    ],
};

/// A setting error when `kind`'s targets for `views` (`Rgba32Float`, one array layer per
/// view at the largest view's resolution) would outgrow their memory bound.
pub fn check_layer_memory(views: &[LightView], kind: &LayerKind) -> Result<()> {
    let max_res = views.iter().map(|l| l.res).max().unwrap_or(1) as u64;
    let bytes = max_res * max_res * views.len() as u64 * 16 * kind.targets.len() as u64;
    if bytes > MAX_LAYER_BYTES {
        return Err(Error::setting(
            kind.setting,
            format!(
                "the {}s would take {} MiB of memory (at most {} MiB); lower `{}`",
                kind.name,
                bytes >> 20,
                MAX_LAYER_BYTES >> 20,
                kind.setting
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cornell (one point light): six faces of √(budget / 6) texels a side whose texel
    /// solid angles, with the round-off correction, add up to 4π.
    #[test]
    fn light_views_follow_budget_and_power() {
        let scene = crate::scene::builtin::load("cornell").expect("scene");
        let views = light_views(&scene, 10_000);
        assert_eq!(views.len(), 6);
        let mut solid_angle = 0.0f64;
        for l in &views {
            assert_eq!(l.res, 41);
            for j in 0..l.res {
                for i in 0..l.res {
                    let x = 2.0 * (i as f64 + 0.5) / l.res as f64 - 1.0;
                    let y = 2.0 * (j as f64 + 0.5) / l.res as f64 - 1.0;
                    let c = 1.0 / (1.0 + x * x + y * y).sqrt();
                    solid_angle += l.texel_area as f64 * c * c * c;
                }
            }
        }
        assert!((solid_angle / (4.0 * std::f64::consts::PI) - 1.0).abs() < 1e-5);
    }
}
