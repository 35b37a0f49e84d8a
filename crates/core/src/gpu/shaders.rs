//! WGSL loading, and the WGSL every layer shares (`shaders/common/`): the GPU mirrors of the
//! core's structs, the uber BSDF, texture lookups, fixed-point sums and the vertex stages.
//! A pass's own WGSL lives beside it (`raster/shaders/`, `estimate/shaders/`) and is joined
//! after the shared code when its module is created (WGSL has no includes).

/// Structs shared by the passes (`Material`, `Light`, `View`) and octahedral normal packing.
pub const COMMON: &str = include_str!("shaders/common/types.wgsl");
/// The uber BSDF: the formulas of `bsdf::Material::eval`.
pub const BSDF: &str = include_str!("shaders/common/bsdf.wgsl");
/// Mitsuba's models (coated plastics, conductors, Beckmann) as the CPU evaluates them; after
/// [`BSDF`].
pub const MODELS: &str = include_str!("shaders/common/models.wgsl");
/// The uber BSDF's sampling helpers (lobe probabilities, densities, direction samples,
/// dielectric Fresnel, path density); after [`BSDF`].
pub const SAMPLE: &str = include_str!("shaders/common/sample.wgsl");
/// Texture lookups and textured materials (group 1 of the passes that rasterize the scene).
pub const TEXTURE: &str = include_str!("shaders/common/texture.wgsl");
/// Order-independent (fixed-point) sums of non-negative RGB terms.
pub const FIXED_SUM: &str = include_str!("shaders/common/fixed_sum.wgsl");
/// The vertex stage of full-screen passes (one triangle, no vertex buffer).
pub const FULLSCREEN: &str = include_str!("shaders/common/fullscreen.wgsl");
/// The scene's vertices and what the passes that rasterize it carry to the fragments.
pub const SCENE_VERTEX: &str = include_str!("shaders/common/scene_vertex.wgsl");

/// Creates a shader module from `parts`, concatenated in order (common code first).
pub fn module(device: &wgpu::Device, label: &str, parts: &[&str]) -> wgpu::ShaderModule {
    let source = parts.join("\n");
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}
