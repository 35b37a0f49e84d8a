//! GPU-traced photons that stay on the GPU: the continuation pass's record buffers
//! (`super::trace::dispatch`, only their counts read back) joined into one buffer of
//! [`Photon`] records and sized in place (`gpu/shaders/photon/resident.wgsl`: the volume
//! radius of `VolumeRadius::of`, caustic records widened to a pixel as the `ispm` upload
//! does), which the binned estimators copy into their photon texture. Only the record
//! count and the caustic count come back to the CPU.

use super::scene::GpuPhotonScene;
use super::trace::{dispatch, Dispatched};
use super::{Binding, ComputePass};
use crate::error::{Error, Result};
use crate::gpu::layout::buffer_init;
use crate::gpu::{self, GpuContext, Pipelines};
use crate::photon::density::CAUSTIC_DENSITY;
use crate::photon::radius::{VolumeRadius, DENSITY_EXPONENT, MAX_WIDENING};
use crate::photon::{Photon, PhotonRay, PhotonTraceSettings};
use bytemuck::{Pod, Zeroable};

/// Set to `readback` to read the GPU-traced photons back even where the estimators could
/// bind them (the benchmarks' old path, and the tests' reference).
pub const RECORDS_ENV: &str = "GI_PHOTON_RECORDS";

thread_local! {
    static FORCED_READBACK: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Makes this thread's frames read GPU-traced photons back (`true`) or keep them on the GPU
/// where they can (`false`, the default), for the tests' comparisons.
pub fn force_readback(on: bool) {
    FORCED_READBACK.with(|f| f.set(on));
}

pub(crate) fn forced() -> bool {
    FORCED_READBACK.with(std::cell::Cell::get)
        || std::env::var(RECORDS_ENV).is_ok_and(|v| v.eq_ignore_ascii_case("readback"))
}

/// The sizing pass's pipeline, compiled on first use.
struct SizePass(ComputePass);

impl Pipelines for SizePass {
    fn create(ctx: &GpuContext) -> Self {
        let parts = [include_str!("../shaders/photon/resident.wgsl")];
        let bindings = [Binding::ReadWrite, Binding::Uniform(48), Binding::ReadWrite];
        SizePass(ComputePass::new(
            ctx,
            "resident_size",
            &bindings,
            &parts,
            false,
        ))
    }
}

/// Records per sizing dispatch (workgroups of 64 within one dimension's 65535).
const CHUNK: u64 = 64 * 65535;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SizeParams {
    eye: [f32; 3],
    r_base: f32,
    r_max: f32,
    exponent: f32,
    max_widening: f32,
    caustic_density: f32,
    pixel_per_metre: f32,
    first: u32,
    count: u32,
    _pad: u32,
}

/// How the records are sized: the frame's volume radii, and the eye and pixel footprint
/// (per metre of distance) that caustic kernels are widened to.
#[derive(Clone, Copy, Debug)]
pub struct Sizing {
    pub radius: VolumeRadius,
    pub eye: [f32; 3],
    pub pixel_per_metre: f32,
}

/// A frame's GPU-traced photons on the GPU, sized for the splat.
pub struct ResidentPhotons {
    /// `count` records of [`Photon`] (at least one record's bytes).
    pub buffer: wgpu::Buffer,
    pub count: u32,
    /// Of them, caustic (`photon::density::is_caustic`).
    pub caustic: u32,
}

/// The paths of one light's trace: its record buffers (one per dispatch) and counts.
#[derive(Default)]
pub struct Traced {
    parts: Vec<Dispatched>,
    pub stored: u64,
    pub absorbed: u64,
    pub escaped: u64,
    pub truncated: u64,
}

/// Follows `rays` on the GPU as [`super::trace::continue_paths`] does (the same photons for
/// the same seed), leaving the records on the GPU.
pub fn continue_paths(
    ctx: &GpuContext,
    scene: &GpuPhotonScene,
    rays: &[PhotonRay],
    s: &PhotonTraceSettings,
    seed: u64,
) -> Result<Traced> {
    super::trace::refuse_differentials(s)?;
    let mut out = Traced::default();
    for (k, chunk) in rays.chunks(super::trace::CHUNK).enumerate() {
        let seed = super::trace::chunk_seed(seed, k);
        let first = chunk.len() as u64 * super::trace::RECORDS_PER_PATH;
        let d = match dispatch(ctx, scene, chunk, s, seed, first)? {
            Ok(d) => d,
            Err(needed) => dispatch(ctx, scene, chunk, s, seed, needed)?
                .map_err(|_| Error::Internal("GPU photon count changed on retry".into()))?,
        };
        out.stored += d.stored;
        out.absorbed += d.absorbed;
        out.escaped += d.escaped;
        out.truncated += d.truncated;
        out.parts.push(d);
    }
    Ok(out)
}

/// The records of `traced` (in order) joined into one buffer and sized with `sizing`;
/// waits for the caustic count.
pub fn join(ctx: &GpuContext, traced: &[Traced], sizing: Sizing) -> Result<ResidentPhotons> {
    let record = std::mem::size_of::<Photon>() as u64;
    let count: u64 = traced.iter().map(|t| t.stored).sum();
    let bytes = count.max(1) * record;
    ctx.check_buffer("the GPU-traced photons", bytes)?;
    let buffer = gpu::create_buffer(
        &ctx.device,
        &wgpu::BufferDescriptor {
            label: Some("resident photons"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        },
    );
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let mut at = 0;
    for d in traced.iter().flat_map(|t| &t.parts) {
        if d.stored > 0 {
            encoder.copy_buffer_to_buffer(&d.records, 0, &buffer, at, d.stored * record);
        }
        at += d.stored * record;
    }
    ctx.queue.submit([encoder.finish()]);
    let caustic = size(ctx, &buffer, count, sizing)?;
    Ok(ResidentPhotons {
        buffer,
        count: count as u32,
        caustic,
    })
}

/// Sizes the `count` records of `buffer` in place; returns how many are caustic.
fn size(ctx: &GpuContext, buffer: &wgpu::Buffer, count: u64, sizing: Sizing) -> Result<u32> {
    let p = SizePass::get(ctx);
    let storage = wgpu::BufferUsages::STORAGE;
    let caustics = buffer_init(
        ctx,
        "resident caustic count",
        &[0; 16],
        storage | wgpu::BufferUsages::COPY_SRC,
    );
    let caustics_rb = gpu::readback_buffer(&ctx.device, "resident caustic readback", 16);
    let mut index = None;
    let mut first = 0;
    while first < count {
        let n = (count - first).min(CHUNK);
        let params = SizeParams {
            eye: sizing.eye,
            r_base: sizing.radius.r_base,
            r_max: sizing.radius.r_max,
            exponent: DENSITY_EXPONENT,
            max_widening: MAX_WIDENING,
            caustic_density: CAUSTIC_DENSITY,
            pixel_per_metre: sizing.pixel_per_metre,
            first: first as u32,
            count: n as u32,
            _pad: 0,
        };
        let params = buffer_init(
            ctx,
            "resident params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM,
        );
        let last = first + n >= count;
        let copies = [(&caustics, &caustics_rb, 16)];
        let copies: &[_] = if last { &copies } else { &[] };
        let buffers = [buffer, &params, &caustics];
        index = Some(p.0.run(ctx, &buffers, None, n as u32, copies));
        first += n;
    }
    let Some(index) = index else {
        return Ok(0);
    };
    let counts = ctx.read_buffers_with(&[&caustics_rb], Some(index), |_, b| {
        u32::from_le_bytes([b[0], b[1], b[2], b[3]])
    })?;
    Ok(counts[0])
}

/// `photons` sized on the GPU as [`join`] sizes GPU-traced records, read back, with the
/// caustic count (the parity test of the sizing pass against the CPU's radii).
pub fn sized_on_gpu(
    ctx: &GpuContext,
    photons: &[Photon],
    sizing: Sizing,
) -> Result<(Vec<Photon>, u32)> {
    let bytes = std::mem::size_of_val(photons).max(64) as u64;
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let mut data = bytemuck::cast_slice::<Photon, u8>(photons).to_vec();
    data.resize(bytes as usize, 0);
    let buffer = buffer_init(ctx, "photons to size", &data, usage);
    let caustic = size(ctx, &buffer, photons.len() as u64, sizing)?;
    let rb = gpu::readback_buffer(&ctx.device, "sized photons readback", bytes);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(&buffer, 0, &rb, 0, bytes);
    let index = ctx.queue.submit([encoder.finish()]);
    let out = ctx.read_buffers_with(&[&rb], Some(index), |_, b| {
        bytemuck::cast_slice::<u8, Photon>(&b[..std::mem::size_of_val(photons)]).to_vec()
    })?;
    Ok((out[0].clone(), caustic))
}
