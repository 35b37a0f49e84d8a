//! Bind-group layout entries, bind-group entries and buffers that every pass builds with.

use super::raw::ViewRaw;
use super::GpuContext;

/// Bytes of a [`ViewRaw`] (a view picked by dynamic offset).
pub const VIEW_SIZE: u64 = std::mem::size_of::<ViewRaw>() as u64;

/// A `View` uniform picked by dynamic offset, seen by the vertex and fragment stages.
pub fn view_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    uniform_entry_sized(
        binding,
        wgpu::ShaderStages::VERTEX_FRAGMENT,
        true,
        VIEW_SIZE,
    )
}

/// A uniform buffer bound whole, seen by the vertex and fragment stages.
pub fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A uniform buffer of at least `size` bytes, optionally picked by dynamic offset.
pub fn uniform_entry_sized(
    binding: u32,
    visibility: wgpu::ShaderStages,
    dynamic: bool,
    size: u64,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: dynamic,
            min_binding_size: wgpu::BufferSize::new(size),
        },
        count: None,
    }
}

/// A read-only storage buffer.
pub fn storage_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    storage(binding, visibility, true)
}

/// A read-write storage buffer.
pub fn storage_rw_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    storage(binding, visibility, false)
}

fn storage(
    binding: u32,
    visibility: wgpu::ShaderStages,
    read_only: bool,
) -> wgpu::BindGroupLayoutEntry {
    entry(
        binding,
        visibility,
        wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
    )
}

/// A 2D float texture read with `textureLoad` (not filtered).
pub fn texture_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    let sample_type = wgpu::TextureSampleType::Float { filterable: false };
    texture_2d_entry(binding, visibility, sample_type)
}

/// A 2D array of depth textures (shadow maps), read with a comparison sampler.
pub fn depth_array_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    let ty = wgpu::BindingType::Texture {
        sample_type: wgpu::TextureSampleType::Depth,
        view_dimension: wgpu::TextureViewDimension::D2Array,
        multisampled: false,
    };
    entry(binding, visibility, ty)
}

/// A comparison sampler (shadow-map lookups).
pub fn comparison_sampler_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    let ty = wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison);
    entry(binding, visibility, ty)
}

/// A 2D unsigned-integer texture read with `textureLoad`.
pub fn uint_texture_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    texture_2d_entry(binding, visibility, wgpu::TextureSampleType::Uint)
}

fn texture_2d_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    sample_type: wgpu::TextureSampleType,
) -> wgpu::BindGroupLayoutEntry {
    let ty = wgpu::BindingType::Texture {
        sample_type,
        view_dimension: wgpu::TextureViewDimension::D2,
        multisampled: false,
    };
    entry(binding, visibility, ty)
}

/// A 2D storage texture of `format`, written only.
pub fn storage_texture_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    format: wgpu::TextureFormat,
) -> wgpu::BindGroupLayoutEntry {
    let ty = wgpu::BindingType::StorageTexture {
        access: wgpu::StorageTextureAccess::WriteOnly,
        format,
        view_dimension: wgpu::TextureViewDimension::D2,
    };
    entry(binding, visibility, ty)
}

/// A layout entry of one binding.
fn entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BindingType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty,
        count: None,
    }
}

/// The bind-group entry of a texture view.
pub fn texture(binding: u32, view: &wgpu::TextureView) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::TextureView(view),
    }
}

/// The bind-group entry of a whole buffer.
pub fn buffer(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

/// The bind-group entry of the first `size` bytes of `buffer` (later records by dynamic
/// offset).
pub fn dynamic_buffer(binding: u32, buffer: &wgpu::Buffer, size: u64) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer,
            offset: 0,
            size: wgpu::BufferSize::new(size),
        }),
    }
}

/// The binding of the first [`ViewRaw`] of `buffer` (later ones by dynamic offset).
pub fn view_binding(buffer: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer,
        offset: 0,
        size: wgpu::BufferSize::new(VIEW_SIZE),
    })
}

/// A buffer holding `bytes` (counted); empty data is padded to one 256-byte block, since
/// zero-sized bindings are invalid.
pub fn buffer_init(
    ctx: &GpuContext,
    label: &str,
    bytes: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let zeros = [0u8; 256];
    let contents = if bytes.is_empty() { &zeros[..] } else { bytes };
    super::create_buffer_init(
        &ctx.device,
        &wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        },
    )
}
