//! WGSL sources. Shared code lives in `shaders/common/` and is prepended to a pass's own file
//! by plain string concatenation when the module is created (WGSL has no includes).

/// Structs shared by the passes (`Material`, `Light`, `View`) and octahedral normal packing.
pub const COMMON: &str = include_str!("shaders/common/types.wgsl");
/// The uber BSDF: the formulas of `bsdf::Material::eval`.
pub const BSDF: &str = include_str!("shaders/common/bsdf.wgsl");
/// Texture lookups and textured materials (group 1 of the passes that rasterize the scene).
pub const TEXTURE: &str = include_str!("shaders/common/texture.wgsl");
/// The photon-volume estimate term shared by the indirect estimators (needs `BSDF`).
pub const PHOTON_VOLUME: &str = include_str!("shaders/common/photon_volume.wgsl");
/// Order-independent (fixed-point) sums of non-negative RGB terms.
pub const FIXED_SUM: &str = include_str!("shaders/common/fixed_sum.wgsl");
/// Light views of the bounce maps and reflective shadow maps: view, vertices, spot falloff.
pub const LIGHT_VIEW: &str = include_str!("shaders/common/light_view.wgsl");
/// Global ray-bundle views and fragment nodes (`bidir`).
pub const BUNDLE_TYPES: &str = include_str!("shaders/common/bundle_types.wgsl");
/// Shadow-map layer choice and PCF lookup.
pub const SHADOW_LOOKUP: &str = include_str!("shaders/common/shadow_lookup.wgsl");
/// Deferred direct lighting of one G-buffer sample (groups 0 and 1 of the direct passes).
pub const DIRECT_SHADE: &str = include_str!("shaders/common/direct_shade.wgsl");

pub const GBUFFER: &str = include_str!("shaders/gbuffer.wgsl");
pub const SHADOW: &str = include_str!("shaders/shadow.wgsl");
pub const SHADOW_MASKED: &str = include_str!("shaders/shadow_masked.wgsl");
pub const DIRECT: &str = include_str!("shaders/direct.wgsl");
pub const DIRECT_EDGES: &str = include_str!("shaders/direct_edges.wgsl");
pub const BOUNCE: &str = include_str!("shaders/bounce.wgsl");
pub const VOLUME: &str = include_str!("shaders/volume.wgsl");
pub const TILED: &str = include_str!("shaders/tiled.wgsl");
pub const CLUSTER: &str = include_str!("shaders/cluster.wgsl");
pub const UPSAMPLE: &str = include_str!("shaders/upsample.wgsl");
pub const COMPOSITE: &str = include_str!("shaders/composite.wgsl");
pub const RSM: &str = include_str!("shaders/rsm.wgsl");
pub const BIDIR: &str = include_str!("shaders/bidir.wgsl");
pub const BUNDLES: &str = include_str!("shaders/bundles.wgsl");

/// Creates a shader module from `parts`, concatenated in order (common code first).
pub fn module(device: &wgpu::Device, label: &str, parts: &[&str]) -> wgpu::ShaderModule {
    let source = parts.join("\n");
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}
