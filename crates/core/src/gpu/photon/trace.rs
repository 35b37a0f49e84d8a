//! The photon continuation pass: the bounce maps' first-scatter rays followed on the GPU
//! (`gpu/shaders/photon/continue.wgsl`) into photon records of the CPU trace's layout
//! ([`Photon`]), the same counts of absorbed, escaped and truncated paths as
//! `photon::trace::continue_paths`. [`continue_paths`] reads the records back (for the
//! `ispm` ring, the CPU's volume radii, boundary compensation and specular gathers);
//! `dispatch` leaves them on the GPU for `super::resident`, whose buffer the binned
//! estimators copy from. Not carried: photon differentials (`footprint_radius` 0).

use super::scene::GpuPhotonScene;
use super::{output_buffer, Binding, ComputePass};
use crate::error::{Error, Result};
use crate::gpu::layout::buffer_init;
use crate::gpu::{self, GpuContext, Pipelines};
use crate::photon::{Photon, PhotonRay, PhotonSet, PhotonTraceSettings};

/// The continuation pass's pipeline, compiled on first use.
struct ContinuePass(ComputePass);

impl Pipelines for ContinuePass {
    fn create(ctx: &GpuContext) -> Self {
        let parts = [
            crate::gpu::bvh::WGSL,
            include_str!("../shaders/photon/continue.wgsl"),
        ];
        let bindings = [
            Binding::Read,
            Binding::Read,
            Binding::Read,
            Binding::Uniform(16),
            Binding::ReadWrite,
            Binding::ReadWrite,
        ];
        ContinuePass(ComputePass::new(
            ctx,
            "continue_paths",
            &bindings,
            &parts,
            true,
        ))
    }
}

/// Compiles the pass now (for the cold-compile measurement; otherwise on first use).
pub fn compile(ctx: &GpuContext) {
    ContinuePass::get(ctx);
}

/// Whether the pass was compiled on `ctx`.
pub fn compiled(ctx: &GpuContext) -> bool {
    ctx.has_pipelines::<ContinuePass>()
}

/// Records a path stores on average before the first try's buffer overflows (the pass
/// counts every record, so an overflow is retried once at the exact size).
pub(crate) const RECORDS_PER_PATH: u64 = 3;
/// Bytes of the counters (stored, absorbed, escaped, truncated, overflows, 3 spare).
const COUNTS: u64 = 32;
/// Rays per dispatch (workgroups of 64 within one dimension's 65535).
pub(crate) const CHUNK: usize = 64 * 65535;

/// `gpu` traces no photon differentials: a `SettingError` when `s` asks for them.
pub(crate) fn refuse_differentials(s: &PhotonTraceSettings) -> Result<()> {
    match s.differentials {
        Some(_) => Err(Error::setting(
            "photon_trace",
            "`gpu` traces no photon differentials (footprint_volumes)",
        )),
        None => Ok(()),
    }
}

/// The seed of dispatch `k` of a trace seeded `seed`.
pub(crate) fn chunk_seed(seed: u64, k: usize) -> u32 {
    (seed ^ (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)) as u32 ^ (seed >> 32) as u32
}

/// Follows `rays` over `scene` on the GPU with `s.max_bounces` and `s.store_direct`
/// (differentials are not traced: an error when `s` asks for them). The photons come in
/// the CPU trace's order (by path, then bounce), not the same photons: the random numbers
/// are the GPU's own stream of `seed`.
pub fn continue_paths(
    ctx: &GpuContext,
    scene: &GpuPhotonScene,
    rays: &[PhotonRay],
    s: &PhotonTraceSettings,
    seed: u64,
) -> Result<PhotonSet> {
    refuse_differentials(s)?;
    let mut set = PhotonSet::default();
    for (k, chunk) in rays.chunks(CHUNK).enumerate() {
        let seed = chunk_seed(seed, k);
        let mut part = trace_chunk(
            ctx,
            scene,
            chunk,
            s,
            seed,
            chunk.len() as u64 * RECORDS_PER_PATH,
        )?;
        if let Err(needed) = part {
            part = trace_chunk(ctx, scene, chunk, s, seed, needed)?;
        }
        let part = part.map_err(|_| Error::Internal("GPU photon count changed on retry".into()))?;
        set.append(part);
    }
    set.emitted = rays.len() as u64;
    Ok(set)
}

/// One dispatch's output left on the GPU: the records buffer (`stored` records of
/// [`Photon`], in the order the GPU wrote them, each path's index in `_pad0`) and the
/// path counts.
pub(crate) struct Dispatched {
    pub records: wgpu::Buffer,
    pub stored: u64,
    pub absorbed: u64,
    pub escaped: u64,
    pub truncated: u64,
}

thread_local! {
    static RECORDS_READ_BACK: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// How many GPU-traced photon records this thread has read back to the CPU (the tests
/// read it around a frame: records the estimators bind on the GPU are not counted).
pub fn records_read_back() -> u64 {
    RECORDS_READ_BACK.with(|n| n.get())
}

/// One dispatch over `rays` with room for `capacity` records: the photons, or `Err(n)`
/// when `n` records did not fit.
fn trace_chunk(
    ctx: &GpuContext,
    scene: &GpuPhotonScene,
    rays: &[PhotonRay],
    s: &PhotonTraceSettings,
    seed: u32,
    capacity: u64,
) -> Result<std::result::Result<PhotonSet, u64>> {
    let d = match dispatch(ctx, scene, rays, s, seed, capacity)? {
        Ok(d) => d,
        Err(needed) => return Ok(Err(needed)),
    };
    let (stored, record) = (d.stored, std::mem::size_of::<Photon>() as u64);
    let bytes = (stored * record).max(record);
    let records_rb = gpu::readback_buffer(&ctx.device, "photon records readback", bytes);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(&d.records, 0, &records_rb, 0, bytes);
    let index = ctx.queue.submit([encoder.finish()]);
    let mut photons: Vec<Photon> = ctx.read_buffers_with(&[&records_rb], Some(index), |_, b| {
        bytemuck::cast_slice::<u8, Photon>(&b[..(stored * record) as usize]).to_vec()
    })?[0]
        .clone();
    RECORDS_READ_BACK.with(|n| n.set(n.get() + stored));
    // The CPU trace's order: by path (the pad word), then bounce.
    photons.sort_unstable_by_key(|p| (p._pad0, p.bounce));
    let mut set = PhotonSet {
        absorbed: d.absorbed,
        escaped: d.escaped,
        truncated: d.truncated,
        ..Default::default()
    };
    for mut p in photons {
        p._pad0 = 0;
        set.store(p);
    }
    Ok(Ok(set))
}

/// One dispatch over `rays` with room for `capacity` records, reading back only the
/// counts: the records left on the GPU, or `Err(n)` when `n` records did not fit.
pub(crate) fn dispatch(
    ctx: &GpuContext,
    scene: &GpuPhotonScene,
    rays: &[PhotonRay],
    s: &PhotonTraceSettings,
    seed: u32,
    capacity: u64,
) -> Result<std::result::Result<Dispatched, u64>> {
    let p = ContinuePass::get(ctx);
    let record = std::mem::size_of::<Photon>() as u64;
    let bytes = capacity.max(1) * record;
    ctx.check_buffer("the GPU-traced photons", bytes)?;
    let storage = wgpu::BufferUsages::STORAGE;
    let params = [s.max_bounces, s.store_direct as u32, seed, capacity as u32];
    let rays_buf = buffer_init(
        ctx,
        "photon trace rays",
        bytemuck::cast_slice(rays),
        storage,
    );
    let params_buf = buffer_init(
        ctx,
        "photon trace params",
        bytemuck::cast_slice(&params),
        wgpu::BufferUsages::UNIFORM,
    );
    let records = output_buffer(ctx, "photon trace records", bytes);
    let counts = buffer_init(
        ctx,
        "photon trace counts",
        &[0; COUNTS as usize],
        storage | wgpu::BufferUsages::COPY_SRC,
    );
    let counts_rb = gpu::readback_buffer(&ctx.device, "photon counts readback", COUNTS);
    let buffers = [
        &rays_buf,
        &scene.tris,
        &scene.materials,
        &params_buf,
        &records,
        &counts,
    ];
    let copies = [(&counts, &counts_rb, COUNTS)];
    let index = ctx.scoped("GPU photon trace", || {
        Ok(p.0.run(
            ctx,
            &buffers,
            Some(&scene.bvh.group),
            rays.len() as u32,
            &copies,
        ))
    })?;
    let counts: Vec<u32> = ctx.read_buffers_with(&[&counts_rb], Some(index), |_, b| {
        bytemuck::pod_read_unaligned::<[u32; 8]>(&b[..32]).to_vec()
    })?[0]
        .clone();
    let stored = counts[0] as u64;
    if counts[4] > 0 {
        return Err(Error::Gpu(format!(
            "the BVH traversal stack overflowed on {} photon rays",
            counts[4]
        )));
    }
    if stored > capacity {
        return Ok(Err(stored));
    }
    Ok(Ok(Dispatched {
        records,
        stored,
        absorbed: counts[1] as u64,
        escaped: counts[2] as u64,
        truncated: counts[3] as u64,
    }))
}
