//! The scene as the GPU photon trace reads it: the BVH ([`GpuBvh`]), every flat triangle's
//! world corners, vertex normals and material, and the materials' uber parameters.

use crate::error::{Error, Result};
use crate::gpu::bvh::GpuBvh;
use crate::gpu::layout::buffer_init;
use crate::gpu::raw::MaterialRaw;
use crate::gpu::GpuContext;
use crate::scene::Scene;
use crate::trace::SceneBvh;
use bytemuck::{Pod, Zeroable};

/// `PhotonTri` in WGSL: corners (w of the first: the material index's bits) and normals.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct PhotonTri {
    pub corners: [[f32; 4]; 3],
    pub normals: [[f32; 4]; 3],
}

/// The scene's buffers for [`super::trace::continue_paths`].
pub struct GpuPhotonScene {
    pub bvh: GpuBvh,
    pub tris: wgpu::Buffer,
    pub materials: wgpu::Buffer,
    /// Bytes uploaded (BVH, triangles, materials).
    pub bytes: u64,
}

impl GpuPhotonScene {
    /// Uploads `scene` with its `bvh`; a setting error for a scene the GPU trace cannot
    /// reproduce ([`super::unsupported`]).
    pub fn upload(ctx: &GpuContext, scene: &Scene, bvh: &SceneBvh) -> Result<GpuPhotonScene> {
        if let Some(why) = super::unsupported(scene) {
            return Err(Error::setting("photon_trace", format!("`gpu`: {why}")));
        }
        let gpu_bvh = GpuBvh::upload(ctx, bvh)?;
        let tris: Vec<PhotonTri> = (0..scene.triangle_count())
            .map(|t| {
                let (p, n) = scene.corners(t);
                let material = f32::from_bits(scene.triangle_material(t));
                PhotonTri {
                    corners: [p[0].extend(material), p[1].extend(0.0), p[2].extend(0.0)]
                        .map(Into::into),
                    normals: n.map(|n| n.extend(0.0).into()),
                }
            })
            .collect();
        let materials: Vec<MaterialRaw> = scene.materials.iter().map(|m| m.to_raw()).collect();
        let tri_bytes: &[u8] = bytemuck::cast_slice(&tris);
        ctx.check_buffer("the photon trace's triangles", tri_bytes.len() as u64)?;
        let storage = wgpu::BufferUsages::STORAGE;
        let material_bytes: &[u8] = bytemuck::cast_slice(&materials);
        Ok(GpuPhotonScene {
            bytes: gpu_bvh.bytes + (tri_bytes.len() + material_bytes.len()) as u64,
            bvh: gpu_bvh,
            tris: buffer_init(ctx, "photon trace triangles", tri_bytes, storage),
            materials: buffer_init(ctx, "photon trace materials", material_bytes, storage),
        })
    }
}
