//! A batch of ray queries on the GPU over a [`GpuBvh`]: closest hits and occlusion, read
//! back. For the CPU/GPU parity tests and the rays/s measurement; the photon trace calls
//! `bvh_closest` inside its own pass instead.

use super::{BvhLayout, GpuBvh};
use crate::error::{Error, Result};
use crate::gpu::layout::{buffer, buffer_init, storage_entry, storage_rw_entry};
use crate::gpu::{self, GpuContext, Pipelines};
use crate::sampling::{uniform_sphere, Rng};
use crate::scene::Scene;
use crate::trace::bvh_flat::NONE;
use crate::trace::Hit;
use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};

/// `QueryRay` in WGSL: origin and the segment's end tmax (the segment is (0, tmax)); the
/// direction, and 1.0 for an occlusion (any-hit) query, 0.0 for a closest-hit one.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct QueryRay {
    pub origin_tmax: [f32; 4],
    pub dir_any: [f32; 4],
}

impl QueryRay {
    pub fn new(origin: Vec3, dir: Vec3, tmax: f32, any: bool) -> Self {
        QueryRay {
            origin_tmax: origin.extend(tmax).into(),
            dir_any: dir.extend(any as u32 as f32).into(),
        }
    }
    pub fn origin(&self) -> Vec3 {
        Vec4::from(self.origin_tmax).truncate()
    }
    pub fn dir(&self) -> Vec3 {
        Vec4::from(self.dir_any).truncate()
    }
    pub fn tmax(&self) -> f32 {
        self.origin_tmax[3]
    }
    pub fn any(&self) -> bool {
        self.dir_any[3] != 0.0
    }
}

/// The query pipeline and its group-0 layout, compiled on first use.
pub struct QueryPipeline {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl Pipelines for QueryPipeline {
    fn create(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = gpu::pipeline::bind_group_layout(
            device,
            "bvh query layout",
            &[
                storage_entry(0, compute),
                storage_rw_entry(1, compute),
                storage_rw_entry(2, compute),
            ],
        );
        let bvh = BvhLayout::get(ctx);
        let pipeline_layout =
            gpu::pipeline::pipeline_layout(device, "bvh query", &[&layout, &bvh.layout]);
        let module = gpu::shaders::module(
            device,
            "bvh query",
            &[super::WGSL, include_str!("../shaders/bvh/query.wgsl")],
        );
        let pipeline = gpu::create_compute_pipeline(
            device,
            &wgpu::ComputePipelineDescriptor {
                label: Some("bvh query"),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some("query"),
                compilation_options: Default::default(),
                cache: None,
            },
        );
        QueryPipeline { layout, pipeline }
    }
}

/// Rays per dispatch (the workgroup count stays under the 65535 limit of one dimension).
const CHUNK: usize = 64 * 65535;

/// Traces `rays` over `bvh` on `ctx`; one answer per ray, in order: the closest hit (for
/// occlusion queries any blocker) as a flat scene triangle, as [`SceneBvh::intersect`]
/// gives it. An error when a traversal stack overflowed (its hit may be missing).
///
/// [`SceneBvh::intersect`]: crate::trace::SceneBvh::intersect
pub fn query(ctx: &GpuContext, bvh: &GpuBvh, rays: &[QueryRay]) -> Result<Vec<Option<Hit>>> {
    let p = QueryPipeline::get(ctx);
    let mut out = Vec::with_capacity(rays.len());
    for chunk in rays.chunks(CHUNK) {
        out.extend(ctx.scoped("bvh query", || query_chunk(ctx, &p, bvh, chunk))?);
    }
    Ok(out)
}

fn query_chunk(
    ctx: &GpuContext,
    p: &QueryPipeline,
    bvh: &GpuBvh,
    rays: &[QueryRay],
) -> Result<Vec<Option<Hit>>> {
    let device = &ctx.device;
    let size = (rays.len() * 16) as u64;
    ctx.check_buffer("the ray queries' hits", size)?;
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let input = buffer_init(ctx, "bvh query rays", bytemuck::cast_slice(rays), usage);
    let overflows = buffer_init(ctx, "bvh query overflows", &[0; 16], usage);
    let hits = gpu::create_buffer(
        device,
        &wgpu::BufferDescriptor {
            label: Some("bvh query hits"),
            size,
            usage,
            mapped_at_creation: false,
        },
    );
    let readback = gpu::readback_buffer(device, "bvh query readback", size);
    let overflow_readback = gpu::readback_buffer(device, "bvh query overflow readback", 16);
    let group = gpu::create_bind_group(
        device,
        &wgpu::BindGroupDescriptor {
            label: Some("bvh query group"),
            layout: &p.layout,
            entries: &[buffer(0, &input), buffer(1, &hits), buffer(2, &overflows)],
        },
    );
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("bvh query"),
    });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("bvh query"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&p.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.set_bind_group(1, &bvh.group, &[]);
        pass.dispatch_workgroups((rays.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&hits, 0, &readback, 0, size);
    encoder.copy_buffer_to_buffer(&overflows, 0, &overflow_readback, 0, 16);
    let index = ctx.queue.submit([encoder.finish()]);
    let words = |bytes: &[u8]| -> Vec<[u32; 4]> {
        bytes
            .chunks_exact(16)
            .map(bytemuck::pod_read_unaligned)
            .collect()
    };
    let mut out =
        ctx.read_buffers_with(&[&readback, &overflow_readback], Some(index), |_, b| {
            words(b)
        })?;
    let overflowed = out[1].first().map_or(0, |w| w[0]);
    if overflowed > 0 {
        return Err(Error::Gpu(format!(
            "the BVH traversal stack overflowed on {overflowed} rays"
        )));
    }
    Ok(std::mem::take(&mut out[0])
        .into_iter()
        .map(|[t, triangle, u, v]| {
            (triangle != NONE).then(|| Hit {
                t: f32::from_bits(t),
                triangle,
                u: f32::from_bits(u),
                v: f32::from_bits(v),
            })
        })
        .collect())
}

/// `n` random rays around `scene` (for the parity tests and the rays/s measurement):
/// origins in the cube of 0.6 of its bounding sphere (inside a room), directions uniform on the sphere,
/// one in 16 along a coordinate axis (zero components of both signs); every third an
/// occlusion query with tmax up to the scene's diameter, the others closest-hit queries
/// over an unbounded segment.
pub fn random_rays(scene: &Scene, n: usize, seed: u64) -> Vec<QueryRay> {
    let b = scene.bounds();
    let mut rng = Rng::new(seed, 0, 0);
    let axes = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    (0..n)
        .map(|i| {
            let u = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let o = b.centre + (u * 2.0 - 1.0) * 0.6 * b.radius;
            let d = if i % 16 == 0 {
                axes[(rng.next_f32() * 6.0) as usize % 6]
            } else {
                uniform_sphere(rng.next_2d())
            };
            let any = i % 3 == 0;
            let tmax = if any {
                rng.next_f32() * 2.0 * b.radius
            } else {
                f32::INFINITY
            };
            QueryRay::new(o, d, tmax, any)
        })
        .collect()
}
