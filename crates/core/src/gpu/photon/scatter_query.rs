//! A batch of GPU photon scatterings on given random numbers, read back: the parity test of
//! the WGSL sampling against `photon::trace::scatter_local` (`tests/gpu_photon_scatter.rs`).

use super::{output_buffer, Binding, ComputePass};
use crate::bsdf::{Lobe, Material};
use crate::error::Result;
use crate::gpu::layout::buffer_init;
use crate::gpu::raw::MaterialRaw;
use crate::gpu::{self, GpuContext, Pipelines};
use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};

/// `ScatterInput` in WGSL: the material, local `wo`, local geometric normal, power, and the
/// random numbers (u, u2.x, u2.y, u_rr).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ScatterInput {
    pub material: MaterialRaw,
    pub wo: [f32; 4],
    pub ng: [f32; 4],
    pub power: [f32; 4],
    pub u: [f32; 4],
}

impl ScatterInput {
    pub fn new(m: &Material, wo: Vec3, ng: Vec3, power: Vec3, u: Vec4) -> Self {
        ScatterInput {
            material: m.to_raw(),
            wo: wo.extend(0.0).into(),
            ng: ng.extend(0.0).into(),
            power: power.extend(0.0).into(),
            u: u.into(),
        }
    }
}

/// A GPU scattering: local direction, power after the roulette, survival probability and
/// lobe; `None` when absorbed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuScattered {
    pub wi: Vec3,
    pub power: Vec3,
    pub q: f32,
    pub lobe: Lobe,
}

/// The lobe of a WGSL lobe number (`LOBE_*` in scatter.wgsl).
pub fn lobe_of(n: u32) -> Option<Lobe> {
    [
        Lobe::Diffuse,
        Lobe::Glossy,
        Lobe::Mirror,
        Lobe::GlassReflect,
        Lobe::GlassRefract,
    ]
    .get(n as usize)
    .copied()
}

struct ScatterQuery(ComputePass);

impl Pipelines for ScatterQuery {
    fn create(ctx: &GpuContext) -> Self {
        let parts = [include_str!("../shaders/photon/scatter_query.wgsl")];
        let bindings = [Binding::Read, Binding::ReadWrite];
        ScatterQuery(ComputePass::new(
            ctx,
            "scatter_query",
            &bindings,
            &parts,
            false,
        ))
    }
}

/// Runs `photon_scatter` on every input; one answer per input, in order.
pub fn scatter(ctx: &GpuContext, inputs: &[ScatterInput]) -> Result<Vec<Option<GpuScattered>>> {
    let p = ScatterQuery::get(ctx);
    let size = (inputs.len() * 32) as u64;
    ctx.check_buffer("the scatter queries", size)?;
    let usage = wgpu::BufferUsages::STORAGE;
    let input = buffer_init(ctx, "scatter inputs", bytemuck::cast_slice(inputs), usage);
    let output = output_buffer(ctx, "scatter outputs", size);
    let readback = gpu::readback_buffer(&ctx.device, "scatter readback", size.max(16));
    let index = ctx.scoped("scatter query", || {
        Ok(p.0.run(
            ctx,
            &[&input, &output],
            None,
            inputs.len() as u32,
            &[(&output, &readback, size.max(16))],
        ))
    })?;
    let mut out = ctx.read_buffers_with(&[&readback], Some(index), |_, b| {
        b.chunks_exact(32)
            .take(inputs.len())
            .map(|c| {
                let w: [f32; 8] = bytemuck::pod_read_unaligned(c);
                let lobe = lobe_of(w[3].to_bits())?;
                Some(GpuScattered {
                    wi: Vec3::new(w[0], w[1], w[2]),
                    power: Vec3::new(w[4], w[5], w[6]),
                    q: w[7],
                    lobe,
                })
            })
            .collect()
    })?;
    Ok(std::mem::take(&mut out[0]))
}
