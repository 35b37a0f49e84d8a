//! The scene's textures on the GPU: every mip level of every texture packed into the pages
//! of one `Rgba16Float` 2D array (an atlas with explicit mip handling), a table of level
//! rectangles, and the materials' texture indices. `shaders/common/texture.wgsl` reads it
//! with `textureLoad` and does the wrap, bilinear and level blending itself, with the
//! arithmetic of [`crate::texture::Texture::sample`], so the CPU and GPU agree texel for
//! texel (the CPU rounds its texels to `f16` as well). Texture reads, not storage-buffer
//! loops: on lavapipe the latter are many times slower.
//!
//! Pages are as large as the largest texture (at most [`crate::texture::MAX_TEXTURE_SIZE`]);
//! levels are placed on shelves by decreasing height.

use crate::error::{Error, Result};
use crate::gpu::layout::{buffer, texture};
use crate::gpu::{self, GpuContext};
use crate::scene::{MaterialMaps, Scene};
use crate::texture::Texture;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

pub const PAGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Entries per row of the table texture (`TEX_TABLE_WIDTH` in WGSL).
pub const TABLE_WIDTH: u32 = 1024;

/// One mip level's rectangle in the atlas (`TexLevel` in WGSL): 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct LevelRaw {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
    pub page: u32,
    pub _pad: [u32; 3],
}

/// A material's textures (`MaterialMaps` in WGSL; `u32::MAX` = none): 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct MapsRaw {
    pub diffuse: u32,
    pub specular: u32,
    pub roughness: u32,
    pub normal: u32,
    pub alpha: u32,
    pub alpha_cutoff: f32,
    pub emission: u32,
    pub _pad: u32,
}

impl MaterialMaps {
    pub fn to_raw(&self) -> MapsRaw {
        let i = |t: Option<u32>| t.unwrap_or(u32::MAX);
        MapsRaw {
            diffuse: i(self.diffuse),
            specular: i(self.specular),
            roughness: i(self.roughness),
            normal: i(self.normal),
            alpha: i(self.alpha),
            alpha_cutoff: self.alpha_cutoff,
            emission: i(self.emission),
            _pad: 0,
        }
    }
}

/// Which fragment shader the passes that rasterize the scene use (`fs_main`, `fs_textured`,
/// `fs_masked`): a scene without textures pays nothing for them, and only a scene with
/// alpha masks gets a shader that may discard (which costs early depth testing).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    Plain,
    Textured,
    Masked,
}

impl Variant {
    pub const ALL: [Variant; 3] = [Variant::Plain, Variant::Textured, Variant::Masked];

    pub fn of(scene: &Scene) -> Variant {
        if scene.has_alpha_masks() {
            Variant::Masked
        } else if scene.material_maps.iter().any(|m| !m.is_empty()) {
            Variant::Textured
        } else {
            Variant::Plain
        }
    }

    pub fn entry_point(self) -> &'static str {
        match self {
            Variant::Plain => "fs_main",
            Variant::Textured => "fs_textured",
            Variant::Masked => "fs_masked",
        }
    }
}

/// Where every level of every texture lies in the atlas.
#[derive(Clone, Debug, PartialEq)]
pub struct Atlas {
    pub page_size: u32,
    pub pages: u32,
    /// All levels, texture by texture, finest first.
    pub levels: Vec<LevelRaw>,
    /// Per texture: index of its first level in `levels`, and its number of levels.
    pub info: Vec<[u32; 2]>,
}

impl Atlas {
    /// The table the shaders read (see `texture.wgsl`): per texture (first level's entry,
    /// levels, width | height << 16, 0), then per level (x | y << 16, width | height << 16,
    /// page, 0). Sizes and positions fit 16 bits: pages are at most 4096 texels a side.
    pub fn table(&self) -> Vec<[u32; 4]> {
        let n = self.info.len() as u32;
        let mut out: Vec<[u32; 4]> = self
            .info
            .iter()
            .map(|&[first, count]| {
                let l = self.levels[first as usize];
                [n + first, count, l.width | l.height << 16, 0]
            })
            .collect();
        out.extend(
            self.levels
                .iter()
                .map(|l| [l.x | l.y << 16, l.width | l.height << 16, l.page, 0]),
        );
        out
    }

    /// Packs the levels of `textures` on shelves of square pages as large as the largest
    /// texture.
    pub fn pack(textures: &[Arc<Texture>]) -> Atlas {
        let page_size = textures
            .iter()
            .map(|t| t.width().max(t.height()))
            .max()
            .unwrap_or(1);
        let mut levels = Vec::new();
        let mut info = Vec::new();
        for t in textures {
            info.push([levels.len() as u32, t.levels.len() as u32]);
            for l in &t.levels {
                levels.push(LevelRaw {
                    width: l.width,
                    height: l.height,
                    ..Zeroable::zeroed()
                });
            }
        }
        let mut order: Vec<usize> = (0..levels.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse((levels[i].height, levels[i].width)));
        let (mut page, mut x, mut y, mut shelf) = (0u32, 0u32, 0u32, 0u32);
        for i in order {
            let (w, h) = (levels[i].width, levels[i].height);
            if x + w > page_size {
                y += shelf;
                x = 0;
                shelf = 0;
            }
            if y + h > page_size {
                page += 1;
                x = 0;
                y = 0;
                shelf = 0;
            }
            levels[i].x = x;
            levels[i].y = y;
            levels[i].page = page;
            x += w;
            shelf = shelf.max(h);
        }
        Atlas {
            page_size,
            pages: page + 1,
            levels,
            info,
        }
    }
}

/// The bind group layout of group 1 of every pass that rasterizes the scene: the atlas, the
/// level table, the texture table and the material maps.
pub fn layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let vis = wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("textures bind group layout"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: vis,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2Array,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: vis,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Uint,
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            super::storage_entry(2, vis),
        ],
    })
}

/// The scene's textures and material maps on the GPU, with their bind group.
pub struct GpuTextures {
    pub group: wgpu::BindGroup,
    maps: wgpu::Buffer,
    pub atlas: Atlas,
}

impl GpuTextures {
    /// Packs and uploads the scene's textures. Fails with a GPU error when the atlas needs
    /// larger or more pages than the adapter allows.
    pub fn new(ctx: &GpuContext, scene: &Scene, layout: &wgpu::BindGroupLayout) -> Result<Self> {
        let atlas = Atlas::pack(&scene.textures);
        let pages = atlas_pages(ctx, scene, &atlas)?;
        let view = pages.create_view(&wgpu::TextureViewDescriptor {
            label: Some("texture atlas"),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let table_view = level_table(ctx, &atlas)?.create_view(&Default::default());
        let maps = super::buffer_init(
            ctx,
            "material maps",
            bytemuck::cast_slice(&maps_raw(scene)),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        let group = gpu::create_bind_group(
            &ctx.device,
            &wgpu::BindGroupDescriptor {
                label: Some("textures bind group"),
                layout,
                entries: &[texture(0, &view), texture(1, &table_view), buffer(2, &maps)],
            },
        );
        Ok(GpuTextures { group, maps, atlas })
    }

    /// Uploads the material maps again (after a material update).
    pub fn write_maps(&self, ctx: &GpuContext, scene: &Scene) {
        gpu::write_buffer(
            &ctx.queue,
            "material maps",
            &self.maps,
            0,
            bytemuck::cast_slice(&maps_raw(scene)),
        );
    }
}

/// The atlas's pages as a texture array with every texture's levels uploaded (half floats),
/// after checking that the adapter holds pages of that size and number and that memory
/// allows them.
fn atlas_pages(ctx: &GpuContext, scene: &Scene, atlas: &Atlas) -> Result<wgpu::Texture> {
    let limits = ctx.device.limits();
    if atlas.page_size > limits.max_texture_dimension_2d {
        return Err(Error::Gpu(format!(
            "a {}-texel texture exceeds the GPU's {} texels a side",
            atlas.page_size, limits.max_texture_dimension_2d
        )));
    }
    if atlas.pages > limits.max_texture_array_layers {
        return Err(Error::Gpu(format!(
            "the textures need {} atlas pages of {}², more than the GPU's {} layers",
            atlas.pages, atlas.page_size, limits.max_texture_array_layers
        )));
    }
    let bytes = atlas.page_size as u64 * atlas.page_size as u64 * 8 * atlas.pages as u64;
    crate::memory::check(|| "the texture atlas".to_string(), bytes)?;
    let size = wgpu::Extent3d {
        width: atlas.page_size,
        height: atlas.page_size,
        // A D2Array view needs its dimension; a single layer is fine.
        depth_or_array_layers: atlas.pages,
    };
    let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
    let pages = gpu::texture_array(&ctx.device, "texture atlas", size, PAGE_FORMAT, usage);
    for (t, tex) in scene.textures.iter().enumerate() {
        let first = atlas.info[t][0] as usize;
        for (l, level) in tex.levels.iter().enumerate() {
            let r = atlas.levels[first + l];
            let texels: Vec<u16> = level
                .texels
                .iter()
                .flat_map(|v| v.to_array().map(|x| half::f16::from_f32(x).to_bits()))
                .collect();
            let bytes: &[u8] = bytemuck::cast_slice(&texels);
            crate::gpu::alloc::note_upload("texture atlas", bytes.len() as u64);
            ctx.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &pages,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: r.x,
                        y: r.y,
                        z: r.page,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                bytes,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(r.width * 8),
                    rows_per_image: Some(r.height),
                },
                wgpu::Extent3d {
                    width: r.width,
                    height: r.height,
                    depth_or_array_layers: 1,
                },
            );
        }
    }
    Ok(pages)
}

/// The atlas's level table ([`Atlas::table`]) as a texture of `TABLE_WIDTH` entries a row,
/// uploaded; fails when it needs more rows than the adapter allows.
fn level_table(ctx: &GpuContext, atlas: &Atlas) -> Result<wgpu::Texture> {
    let table = atlas.table();
    let rows = (table.len() as u32).div_ceil(TABLE_WIDTH).max(1);
    if rows > ctx.device.limits().max_texture_dimension_2d {
        return Err(Error::Gpu(format!(
            "{} texture levels exceed the GPU's texture table",
            atlas.levels.len()
        )));
    }
    let mut padded = table;
    padded.resize((rows * TABLE_WIDTH) as usize, [0; 4]);
    let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
    let format = wgpu::TextureFormat::Rgba32Uint;
    let table_texture = gpu::texture_2d(
        &ctx.device,
        "texture table",
        TABLE_WIDTH,
        rows,
        format,
        usage,
    );
    let bytes: &[u8] = bytemuck::cast_slice(&padded);
    crate::gpu::alloc::note_upload("texture table", bytes.len() as u64);
    ctx.queue.write_texture(
        table_texture.as_image_copy(),
        bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(TABLE_WIDTH * 16),
            rows_per_image: Some(rows),
        },
        table_texture.size(),
    );
    Ok(table_texture)
}

fn maps_raw(scene: &Scene) -> Vec<MapsRaw> {
    scene.material_maps.iter().map(|m| m.to_raw()).collect()
}

/// Group 1 of the passes that rasterize the scene (textures and material maps).
pub struct TexturesLayout {
    pub layout: wgpu::BindGroupLayout,
}

impl crate::gpu::Pipelines for TexturesLayout {
    fn create(ctx: &GpuContext) -> Self {
        TexturesLayout {
            layout: layout(&ctx.device),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tex(w: u32, h: u32) -> Arc<Texture> {
        Arc::new(Texture::new(w, h, &vec![0.5; (w * h * 4) as usize]).unwrap())
    }

    /// Levels never overlap and stay inside their page.
    #[test]
    fn packing_has_no_overlaps() {
        let textures = vec![tex(64, 64), tex(17, 5), tex(1, 1), tex(40, 64), tex(64, 3)];
        let a = Atlas::pack(&textures);
        assert_eq!(a.page_size, 64);
        let total: usize = textures.iter().map(|t| t.levels.len()).sum();
        assert_eq!(a.levels.len(), total);
        for (i, r) in a.levels.iter().enumerate() {
            assert!(r.x + r.width <= a.page_size && r.y + r.height <= a.page_size);
            assert!(r.page < a.pages);
            for s in &a.levels[i + 1..] {
                let apart = r.page != s.page
                    || r.x + r.width <= s.x
                    || s.x + s.width <= r.x
                    || r.y + r.height <= s.y
                    || s.y + s.height <= r.y;
                assert!(apart, "{r:?} overlaps {s:?}");
            }
        }
        assert_eq!(a.info[2], [a.info[1][0] + 5, 1]);
    }
}
