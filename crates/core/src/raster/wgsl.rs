//! The raster passes' WGSL (`raster/shaders/`), each joined after the shared code of
//! `gpu::shaders` and of `raster/shaders/common/` when its module is created.

/// Light views of the bounce maps and reflective shadow maps: view and spot falloff.
pub const LIGHT_VIEW: &str = include_str!("shaders/common/light_view.wgsl");
/// Global ray-bundle views and fragment nodes (`bidir`).
pub const BUNDLE_TYPES: &str = include_str!("shaders/common/bundle_types.wgsl");
/// Shadow-map layer choice and PCF lookup.
pub const SHADOW_LOOKUP: &str = include_str!("shaders/common/shadow_lookup.wgsl");
/// Deferred direct lighting of one G-buffer sample (groups 0 and 1 of the direct passes).
pub const DIRECT_SHADE: &str = include_str!("shaders/common/direct_shade.wgsl");
/// Per-pixel light samples of the emitters outside the polygon groups (a light BVH).
pub const EMITTER_TREE: &str = include_str!("shaders/common/emitter_tree.wgsl");
/// The glossy lobe's environment light for `DIRECT_SHADE` (after it: uses its helpers).
pub const ENV_GLOSSY: &str = include_str!("shaders/common/env_glossy.wgsl");
/// The sampled sky directions' visibility over their cones for `DIRECT_SHADE` (after it).
pub const SKY_CONE: &str = include_str!("shaders/common/sky_cone.wgsl");
/// Mitsuba's exact models in the direct light: the G-buffer's material records (group 1).
pub const EXACT_MODELS: &str = include_str!("shaders/common/exact_models.wgsl");
/// The direct passes' binding of the records `EXACT_MODELS` reads.
pub const EXACT_MODELS_DIRECT: &str = include_str!("shaders/common/exact_models_direct.wgsl");
/// Linearly transformed cosines: the GGX lobe over a polygon (its includer declares the
/// table texture `ltc_table`).
pub const LTC: &str = include_str!("shaders/common/ltc.wgsl");
/// The polygon groups' glossy lobe by LTC for `DIRECT_SHADE` (after it, `ENV_GLOSSY`, `LTC`).
pub const LTC_DIRECT: &str = include_str!("shaders/common/ltc_direct.wgsl");
/// Round emitters (spheres) as the polygons of their discs, for `DIRECT_SHADE` (after it).
pub const ROUND_LIGHTS: &str = include_str!("shaders/common/round_lights.wgsl");
/// The deferred direct light's sources in order, for a pass that shades with it (after
/// `gpu::shaders::COMMON` and `BSDF`, before the pass's own entry points).
pub const DIRECT_SHADING: [&str; 11] = [
    crate::gpu::shaders::MODELS,
    SHADOW_LOOKUP,
    DIRECT_SHADE,
    EXACT_MODELS,
    EXACT_MODELS_DIRECT,
    EMITTER_TREE,
    ENV_GLOSSY,
    SKY_CONE,
    LTC,
    LTC_DIRECT,
    ROUND_LIGHTS,
];

pub const GBUFFER: &str = include_str!("shaders/gbuffer.wgsl");
pub const SHADOW: &str = include_str!("shaders/shadow.wgsl");
pub const SHADOW_MASKED: &str = include_str!("shaders/shadow_masked.wgsl");
pub const DIRECT: &str = include_str!("shaders/direct.wgsl");
pub const DIRECT_EDGES: &str = include_str!("shaders/direct_edges.wgsl");
pub const EDGE_MASK: &str = include_str!("shaders/edge_mask.wgsl");
/// The light of emitters smaller than a pixel (`raster::splat`).
pub const EMITTER_SPLAT: &str = include_str!("shaders/emitter_splat.wgsl");
pub const BOUNCE: &str = include_str!("shaders/bounce.wgsl");
pub const COMPOSITE: &str = include_str!("shaders/composite.wgsl");
pub const RSM: &str = include_str!("shaders/rsm.wgsl");
pub const BIDIR: &str = include_str!("shaders/bidir.wgsl");
/// `bidir`'s roughness clamp (§5), keeping the lobe's albedo.
pub const ROUGHNESS_CLAMP: &str = include_str!("shaders/roughness_clamp.wgsl");
/// `bidir`'s shading of Mitsuba's exact models at its pixels, with their own
/// roughness-clamp energy (after `ROUGHNESS_CLAMP` and `EXACT_MODELS`).
pub const BIDIR_MODELS: &str = include_str!("shaders/bidir_models.wgsl");
pub const BUNDLES: &str = include_str!("shaders/bundles.wgsl");
