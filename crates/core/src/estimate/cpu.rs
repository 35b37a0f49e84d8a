//! The photon-volume estimate computed on the CPU (estimator `cpu`), for CPU devices: there
//! the "GPU" runs on the same cores, and its loops over photon lists run 10–35× slower than
//! native code (lavapipe reads storage buffers and workgroup memory slowly in loops).
//!
//! The same estimate as the GPU estimators: the term of `common/photon_volume.wgsl` (the
//! ellipsoid test, the 2D Epanechnikov kernel, the normal agreement, the BSDF of the view
//! sample) summed over the photons whose ellipsoid holds each view sample, one sample per
//! `subsample` × `subsample` block of the eye G-buffer (read back when it was redrawn:
//! frames whose lights or photons alone changed reuse the samples). The
//! photons are binned like `tiled.wgsl`'s: each into the 8×8-texel tiles under the screen
//! rectangle of its bounding sphere whose samples' world box it meets; each tile's samples
//! then sum the photons of its list in parallel. Every step is conservative, so a sample
//! gets exactly the photons whose ellipsoid holds it: the image equals the tiled estimate's
//! up to float summation order (test `cpu_estimate_equals_tiled` in tests/estimators.rs).
//! The upsampling and the composite stay on the GPU.

use super::target::IndirectTarget;
use crate::bsdf::Material;
use crate::error::{Error, Result};
use crate::gpu::{self, GpuContext};
use crate::photon::radius::VolumeRadius;
use crate::photon::radius::Z_RATIO;
use crate::photon::Photon;
use crate::raster::gbuffer::GBuffer;
use crate::raster::oct_decode;
use crate::sampling::Frame;
use crate::scene::Scene;
use glam::{Mat4, Vec2, Vec3, Vec4};
use rayon::prelude::*;

/// Tile side (low-resolution texels), as in `tiled.wgsl`.
const TILE: u32 = 8;
/// Relative slack of the sphere-box test (a photon wrongly kept costs one rejected test).
const SLACK: f32 = 1e-4;
/// The G-buffer textures read back: position, normals (f32), diffuse, specular (f16),
/// emission (f32; w: the material's index + 1, for its exact model).
const GBUFFER_TEXTURES: [(usize, u32); 5] = [(0, 16), (1, 16), (2, 8), (3, 8), (5, 16)];

/// One view sample of the low-resolution target.
#[derive(Clone, Copy)]
struct ViewSample {
    position: Vec3,
    frame: Frame,
    wo: Vec3,
    material: Material,
    /// ρ/π when the material is Lambertian (no specular lobe, no Fresnel coupling): the
    /// BSDF is then that constant on the viewer's side, and the sum factors it out.
    lambertian: Option<Vec3>,
}

/// The frame's parameters of the estimate.
#[derive(Clone, Copy)]
struct Params {
    view_proj: Mat4,
    eye: Vec3,
    r_max: f32,
}

pub struct CpuEstimate {
    pub target: IndirectTarget,
    /// Mappable copies of the G-buffer textures and their bytes per row.
    readback: Vec<(wgpu::Buffer, u32)>,
    size: [u32; 2],
    params: Option<Params>,
    photons: Vec<Photon>,
    /// Photon-list entries of the last estimate.
    entries: u64,
    /// The view samples of the last estimate and the G-buffer generation they were read
    /// from: a frame whose G-buffer was not redrawn (the lights or the photons changed, not
    /// the view) reuses them instead of reading the G-buffer back.
    samples: Vec<Option<ViewSample>>,
    samples_generation: Option<u64>,
    /// The target holds zeros (the last estimate had no photons).
    zero: bool,
}

impl CpuEstimate {
    pub fn new(ctx: &GpuContext, gbuf: &GBuffer, width: u32, height: u32, k: u32) -> Self {
        let readback = GBUFFER_TEXTURES
            .iter()
            .map(|&(_, texel)| {
                let row = (width * texel).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
                let buffer = gpu::readback_buffer(
                    &ctx.device,
                    "cpu estimate gbuffer",
                    row as u64 * height as u64,
                );
                (buffer, row)
            })
            .collect();
        CpuEstimate {
            target: IndirectTarget::new(ctx, gbuf, width, height, k),
            readback,
            size: [width, height],
            params: None,
            photons: Vec::new(),
            entries: 0,
            samples: Vec::new(),
            samples_generation: None,
            zero: false,
        }
    }

    /// The photons of the next estimate (their `footprint_radius` is the volume radius).
    pub fn set_photons(&mut self, photons: &[Photon]) {
        self.photons.clear();
        self.photons.extend_from_slice(photons);
    }

    /// The view, the eye and the radius bound of the next estimate; the upsampling's
    /// parameters.
    pub fn write_params(&mut self, ctx: &GpuContext, scene: &Scene, radius: VolumeRadius) {
        self.target.write_params(ctx, scene);
        self.params = Some(Params {
            view_proj: self.target.view_proj(scene),
            eye: scene.camera.position,
            r_max: radius.r_max,
        });
    }

    /// Photon-list entries of the last estimate.
    pub fn entries(&self) -> u64 {
        self.entries
    }

    /// Bytes held beyond the targets: the G-buffer copies, the view samples and the photons.
    pub fn memory(&self) -> Vec<(&'static str, u64)> {
        vec![
            (
                "gbuffer copies",
                self.readback.iter().map(|(b, _)| b.size()).sum(),
            ),
            (
                "photons",
                (self.photons.capacity() * std::mem::size_of::<Photon>()) as u64,
            ),
            (
                "view samples",
                (self.samples.capacity() * std::mem::size_of::<Option<ViewSample>>()) as u64,
            ),
            (
                "photon lists",
                self.entries * std::mem::size_of::<Entry>() as u64,
            ),
        ]
    }

    /// Reads the eye G-buffer back (waiting for the work submitted so far) unless its
    /// `generation` is that of the last estimate's, computes the estimate and writes it into
    /// the low-resolution target. Returns the seconds spent waiting for the G-buffer (with
    /// the GPU work submitted before it), `None` where it was not read back.
    /// The view samples' BSDF is their G-buffer's uber material, or `scene`'s material
    /// itself where the GPU passes shade its exact model (`raster::exact_models`).
    pub fn compute(
        &mut self,
        ctx: &GpuContext,
        (gbuf, scene): (&GBuffer, &Scene),
        generation: u64,
    ) -> Result<Option<f64>> {
        let params = self
            .params
            .ok_or_else(|| Error::Gpu("cpu estimate without parameters".into()))?;
        // No photons (the caustic photons' estimate of a scene without caustics): zeros,
        // written once, without reading the G-buffer back.
        if self.photons.is_empty() {
            if !self.zero {
                self.entries = 0;
                self.write(
                    ctx,
                    &vec![Vec4::ZERO; self.target.low_size.iter().product::<u32>() as usize],
                );
                self.zero = true;
            }
            return Ok(None);
        }
        self.zero = false;
        let mut waited = None;
        if self.samples_generation != Some(generation) {
            let t = std::time::Instant::now();
            self.samples_generation = None;
            self.samples = self.read_samples(ctx, (gbuf, scene), params.eye)?;
            self.samples_generation = Some(generation);
            waited = Some(t.elapsed().as_secs_f64());
        }
        let samples = &self.samples;
        let [lw, lh] = self.target.low_size;
        let tiles = [lw.div_ceil(TILE), lh.div_ceil(TILE)];
        let lists = bin(&self.photons, samples, [lw, lh], tiles, params)?;
        self.entries = lists.iter().map(|l| l.len() as u64).sum();
        let rows: Vec<Vec<Vec4>> = (0..tiles[1])
            .into_par_iter()
            .map(|ty| {
                let mut band = vec![Vec4::ZERO; (lw * TILE.min(lh - ty * TILE)) as usize];
                let mut lambertian = Box::new(TileSamples::default());
                for tx in 0..tiles[0] {
                    let list = &lists[(ty * tiles[0] + tx) as usize];
                    lambertian.clear();
                    for y in ty * TILE..((ty + 1) * TILE).min(lh) {
                        for x in tx * TILE..((tx + 1) * TILE).min(lw) {
                            let Some(s) = &samples[(y * lw + x) as usize] else {
                                continue;
                            };
                            let slot = ((y - ty * TILE) * TILE + x - tx * TILE) as usize;
                            let out = &mut band[((y - ty * TILE) * lw + x) as usize];
                            if !lambertian.set(slot, s) {
                                *out = list_sum(&self.photons, list, s, slot, params.r_max)
                                    .extend(0.0);
                            }
                        }
                    }
                    if lambertian.any {
                        lambertian.sum(&self.photons, list, params.r_max);
                        for (slot, rho) in lambertian.rho.iter().enumerate() {
                            let (x, y) = (tx * TILE + slot as u32 % TILE, slot as u32 / TILE);
                            if let Some(rho) = rho {
                                band[(y * lw + x) as usize] =
                                    (*rho * lambertian.sum_of(slot)).extend(0.0);
                            }
                        }
                    }
                }
                band
            })
            .collect();
        self.write(ctx, &rows.concat());
        Ok(waited)
    }

    /// Uploads the estimate `texels` (one per low-resolution texel) to the target.
    fn write(&self, ctx: &GpuContext, texels: &[Vec4]) {
        let [lw, lh] = self.target.low_size;
        gpu::alloc::note_upload("cpu estimate", (texels.len() * 16) as u64);
        ctx.queue.write_texture(
            self.target.low.as_image_copy(),
            bytemuck::cast_slice(texels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(lw * 16),
                rows_per_image: Some(lh),
            },
            self.target.low.size(),
        );
    }

    /// The view samples of the low-resolution texels: the G-buffer pixel at the centre of
    /// each block (`tiled.wgsl`'s `sample_pixel`), `None` where it saw no surface.
    fn read_samples(
        &self,
        ctx: &GpuContext,
        (gbuf, scene): (&GBuffer, &Scene),
        eye: Vec3,
    ) -> Result<Vec<Option<ViewSample>>> {
        let [w, h] = self.size;
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("cpu estimate gbuffer copies"),
            });
        for (&(texture, _), (buffer, row)) in GBUFFER_TEXTURES.iter().zip(&self.readback) {
            encoder.copy_texture_to_buffer(
                gbuf.textures[texture].as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(*row),
                        rows_per_image: Some(h),
                    },
                },
                gbuf.textures[texture].size(),
            );
        }
        let index = ctx.queue.submit([encoder.finish()]);
        let buffers: Vec<&wgpu::Buffer> = self.readback.iter().map(|(b, _)| b).collect();
        let bytes = ctx.read_buffers(&buffers, Some(index))?;
        let rows: Vec<u32> = self.readback.iter().map(|(_, r)| *r).collect();
        let f32x4 = |t: usize, x: u32, y: u32| -> Vec4 {
            let o = (y * rows[t] + x * 16) as usize;
            Vec4::from_array(bytemuck::pod_read_unaligned(&bytes[t][o..o + 16]))
        };
        let f16x4 = |t: usize, x: u32, y: u32| -> Vec4 {
            let o = (y * rows[t] + x * 8) as usize;
            let h: [u16; 4] = bytemuck::pod_read_unaligned(&bytes[t][o..o + 8]);
            Vec4::from_array(h.map(|v| half::f16::from_bits(v).to_f32()))
        };
        let k = self.target.subsample;
        let [lw, lh] = self.target.low_size;
        Ok((0..lw * lh)
            .into_par_iter()
            .map(|i| {
                let (x, y) = (
                    (i % lw * k + k / 2).min(w - 1),
                    (i / lw * k + k / 2).min(h - 1),
                );
                let pos = f32x4(0, x, y);
                if pos.w == 0.0 {
                    return None;
                }
                let normals = f32x4(1, x, y);
                let (diffuse, specular) = (f16x4(2, x, y), f16x4(3, x, y));
                let position = pos.truncate();
                let uber = Material {
                    diffuse: diffuse.truncate(),
                    roughness: diffuse.w,
                    specular: specular.truncate(),
                    fresnel: specular.w > 0.5,
                    transmission: Vec3::ZERO,
                    ..Default::default()
                };
                let exact = exact_material(scene, f32x4(4, x, y).w, uber.diffuse);
                let material = exact.unwrap_or(uber);
                let plain = exact.is_none() && material.specular == Vec3::ZERO && !material.fresnel;
                Some(ViewSample {
                    position,
                    frame: Frame::new(oct_decode(Vec2::new(normals.x, normals.y))),
                    wo: (eye - position).normalize(),
                    lambertian: plain.then(|| material.diffuse / std::f32::consts::PI),
                    material,
                })
            })
            .collect())
    }
}

/// The material of G-buffer index `w` (its index + 1) where the GPU passes shade its exact
/// model ([`crate::raster::exact_models::shades_exactly`]), with the diffuse texel of the
/// sample's stand-in albedo `diffuse` applied ([`crate::raster::exact_models::textured_model`]).
fn exact_material(scene: &Scene, w: f32, diffuse: Vec3) -> Option<Material> {
    use crate::raster::exact_models::{shades_exactly, textured_model};
    let i = (w.max(0.0) + 0.5) as usize;
    let m = scene.materials.get(i.checked_sub(1)?)?;
    let maps = scene.material_maps.get(i - 1).copied().unwrap_or_default();
    shades_exactly(m, &maps).then(|| textured_model(m, &maps, diffuse))
}

/// A photon in a tile's list: its index and the tile's texels under its screen rectangle
/// (x0, y0, x1, y1, inclusive, relative to the tile): only they can be in its volume.
#[derive(Clone, Copy)]
struct Entry {
    photon: u32,
    rect: [u8; 4],
}

impl Entry {
    fn covers(&self, slot: usize) -> bool {
        let (x, y) = ((slot as u32 % TILE) as u8, (slot as u32 / TILE) as u8);
        (self.rect[0]..=self.rect[2]).contains(&x) && (self.rect[1]..=self.rect[3]).contains(&y)
    }
}

/// Per tile, the photons whose bounding sphere may reach one of its samples: those under
/// the tile in the screen rectangle of the sphere's box (one texel of slack), meeting the
/// world box of the tile's samples.
fn bin(
    photons: &[Photon],
    samples: &[Option<ViewSample>],
    [lw, lh]: [u32; 2],
    tiles: [u32; 2],
    params: Params,
) -> Result<Vec<Vec<Entry>>> {
    let n_tiles = (tiles[0] * tiles[1]) as usize;
    let mut boxes = vec![(Vec3::INFINITY, Vec3::NEG_INFINITY); n_tiles];
    for (i, s) in samples.iter().enumerate() {
        if let Some(s) = s {
            let (x, y) = (i as u32 % lw, i as u32 / lw);
            let b = &mut boxes[((y / TILE) * tiles[0] + x / TILE) as usize];
            *b = (b.0.min(s.position), b.1.max(s.position));
        }
    }
    // The screen rectangles in parallel, then the lists in photon order.
    let corners = box_corners(params.view_proj);
    let rects: Vec<Option<[u32; 4]>> = photons
        .par_iter()
        .map(|p| {
            let r = p.footprint_radius.min(params.r_max);
            if r.is_nan() || r <= 0.0 {
                return None;
            }
            screen_rect(p.position(), r, params.view_proj, &corners, [lw, lh])
        })
        .collect();
    // Wide kernels over many tiles (kernel_scale 4 with a million photons) could need more
    // memory than there is: a typed error instead of an abort, from the tiles under the
    // rectangles (a bound of the entries).
    let bound: u64 = rects
        .iter()
        .flatten()
        .map(|[x0, y0, x1, y1]| ((x1 / TILE - x0 / TILE + 1) * (y1 / TILE - y0 / TILE + 1)) as u64)
        .sum();
    // Twice: the runs' lists and the joined ones.
    let needed = 2 * bound * std::mem::size_of::<Entry>() as u64;
    if let Some(available) = crate::memory::available() {
        if needed > available / 3 {
            return Err(Error::OutOfMemory {
                what: format!("the CPU estimate's photon lists ({bound} entries at most)"),
                needed,
                available,
            });
        }
    }
    // The lists of contiguous runs of photons in parallel, then joined per tile in run
    // order: each list keeps photon order (the sums' order), whatever the thread count.
    let run = photons
        .len()
        .div_ceil(4 * rayon::current_num_threads())
        .max(4096);
    let runs: Vec<Vec<Vec<Entry>>> = photons
        .par_chunks(run)
        .zip(rects.par_chunks(run))
        .enumerate()
        .map(|(k, (photons, rects))| {
            let mut lists = vec![Vec::new(); n_tiles];
            for (j, (p, rect)) in photons.iter().zip(rects).enumerate() {
                if let Some(rect) = rect {
                    let i = (k * run + j) as u32;
                    push_entries(&mut lists, i, p, *rect, &boxes, tiles[0], params.r_max);
                }
            }
            lists
        })
        .collect();
    let lists = match <[_; 1]>::try_from(runs) {
        Ok([lists]) => lists,
        Err(runs) => (0..n_tiles)
            .into_par_iter()
            .map(|t| {
                let mut list = Vec::with_capacity(runs.iter().map(|r| r[t].len()).sum());
                for r in &runs {
                    list.extend_from_slice(&r[t]);
                }
                list
            })
            .collect(),
    };
    Ok(lists)
}

/// Appends photon `i` to the lists of the tiles under its screen rectangle whose samples'
/// world box its bounding sphere meets.
fn push_entries(
    lists: &mut [Vec<Entry>],
    i: u32,
    p: &Photon,
    [x0, y0, x1, y1]: [u32; 4],
    boxes: &[(Vec3, Vec3)],
    tiles_x: u32,
    r_max: f32,
) {
    let (c, r) = (p.position(), p.footprint_radius.min(r_max));
    let reach = r * (1.0 + SLACK) + SLACK * c.abs().max_element();
    for ty in y0 / TILE..=y1 / TILE {
        for tx in x0 / TILE..=x1 / TILE {
            let t = (ty * tiles_x + tx) as usize;
            let (lo, hi) = boxes[t];
            if c.clamp(lo, hi).distance_squared(c) <= reach * reach {
                let within = |v: u32, t: u32| v.clamp(t * TILE, t * TILE + TILE - 1) - t * TILE;
                lists[t].push(Entry {
                    photon: i,
                    rect: [
                        within(x0, tx) as u8,
                        within(y0, ty) as u8,
                        within(x1, tx) as u8,
                        within(y1, ty) as u8,
                    ],
                });
            }
        }
    }
}

/// The clip-space offsets of the corners of the box [−1, 1]³ from its centre: a box of
/// half-size r about c has its corners at view_proj·c + r·offset.
fn box_corners(view_proj: Mat4) -> [Vec4; 8] {
    std::array::from_fn(|i| {
        let sign = |bit: usize| if i & bit == 0 { -1.0 } else { 1.0 };
        view_proj * Vec4::new(sign(1), sign(2), sign(4), 0.0)
    })
}

/// The texels (x0, y0, x1, y1, inclusive) under the screen rectangle of the box of the
/// sphere (`c`, `r`), widened by a texel; the whole screen when the box reaches behind
/// the eye, `None` when it lies wholly behind. `corners`: [`box_corners`] of `view_proj`.
fn screen_rect(
    c: Vec3,
    r: f32,
    view_proj: Mat4,
    corners: &[Vec4; 8],
    [lw, lh]: [u32; 2],
) -> Option<[u32; 4]> {
    let centre = view_proj * c.extend(1.0);
    let (mut lo, mut hi) = (Vec2::splat(1.0), Vec2::splat(-1.0));
    let (mut w_min, mut w_max) = (f32::INFINITY, f32::NEG_INFINITY);
    for corner in corners {
        let q = centre + r * *corner;
        w_min = w_min.min(q.w);
        w_max = w_max.max(q.w);
        let ndc = Vec2::new(q.x, q.y) / q.w.max(1e-6);
        lo = lo.min(ndc);
        hi = hi.max(ndc);
    }
    if w_max <= 0.0 {
        return None;
    }
    if w_min <= 1e-6 {
        (lo, hi) = (Vec2::splat(-1.0), Vec2::splat(1.0));
    }
    let (lo, hi) = (
        lo.clamp(Vec2::NEG_ONE, Vec2::ONE),
        hi.clamp(Vec2::NEG_ONE, Vec2::ONE),
    );
    let x0 = (lo.x * 0.5 + 0.5) * lw as f32 - 1.0;
    let x1 = (hi.x * 0.5 + 0.5) * lw as f32 + 1.0;
    let y0 = (0.5 - hi.y * 0.5) * lh as f32 - 1.0;
    let y1 = (0.5 - lo.y * 0.5) * lh as f32 + 1.0;
    let texel = |v: f32, n: u32| (v.floor().max(0.0) as u32).min(n - 1);
    Some([texel(x0, lw), texel(y0, lh), texel(x1, lw), texel(y1, lh)])
}

const SLOTS: usize = (TILE * TILE) as usize;

/// A tile's Lambertian view samples as arrays: the sum runs photon by photon over all of
/// them at once (the inner loop over samples vectorizes), and each sample still adds its
/// photons in list order, so the sums equal [`list_sum`]'s bit for bit.
struct TileSamples {
    p: [[f32; SLOTS]; 3],
    n: [[f32; SLOTS]; 3],
    /// n·wo (the viewer's side), 0 for slots without a Lambertian sample.
    side: [f32; SLOTS],
    acc: [[f32; SLOTS]; 3],
    rho: [Option<Vec3>; SLOTS],
    any: bool,
}

impl Default for TileSamples {
    fn default() -> Self {
        TileSamples {
            p: [[0.0; SLOTS]; 3],
            n: [[0.0; SLOTS]; 3],
            side: [0.0; SLOTS],
            acc: [[0.0; SLOTS]; 3],
            rho: [None; SLOTS],
            any: false,
        }
    }
}

impl TileSamples {
    fn clear(&mut self) {
        self.side = [0.0; SLOTS];
        self.acc = [[0.0; SLOTS]; 3];
        self.rho = [None; SLOTS];
        self.any = false;
    }

    /// Takes sample `s` into `slot` when it is Lambertian; false otherwise.
    fn set(&mut self, slot: usize, s: &ViewSample) -> bool {
        let Some(rho) = s.lambertian else {
            return false;
        };
        for a in 0..3 {
            self.p[a][slot] = s.position[a];
            self.n[a][slot] = s.frame.n[a];
        }
        self.side[slot] = s.frame.n.dot(s.wo);
        self.rho[slot] = Some(rho);
        self.any = true;
        true
    }

    /// Adds the photons of `list` (the terms of [`list_sum`]'s Lambertian loop) at the
    /// slots of the rows under their rectangles. On x86-64 CPUs with AVX2 a row of 8 slots
    /// is one vector (the same code compiled for those features, chosen at run time: the
    /// same operations in the same order, so the same sums; the SSE2 baseline takes two
    /// vectors a row). Cornell 128x128, 80k photons: the estimate stage 22-25 ms a pass
    /// against 29-35 ms with SSE2 (same runs).
    fn sum(&mut self, photons: &[Photon], list: &[Entry], r_max: f32) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU has the features the function is compiled for (checked above).
            #[allow(unsafe_code)]
            unsafe {
                self.sum_avx2(photons, list, r_max)
            };
            return;
        }
        self.sum_rows(photons, list, r_max);
    }

    /// The one exception to the workspace's `unsafe_code = "deny"`: a function compiled for
    /// CPU features is unsafe to call, and is called only where they were detected.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[allow(unsafe_code)]
    unsafe fn sum_avx2(&mut self, photons: &[Photon], list: &[Entry], r_max: f32) {
        self.sum_rows(photons, list, r_max);
    }

    #[inline(always)]
    fn sum_rows(&mut self, photons: &[Photon], list: &[Entry], r_max: f32) {
        const ROW: usize = TILE as usize;
        let [px, py, pz] = &self.p;
        let [nx, ny, nz] = &self.n;
        let side = &self.side;
        let [ar, ag, ab] = &mut self.acc;
        for e in list {
            let ph = &photons[e.photon as usize];
            let [cx, cy, cz] = ph.position;
            let [qx, qy, qz] = ph.normal;
            let [ix, iy, iz] = ph.incident;
            let [pr, pg, pb] = ph.power;
            let r = ph.footprint_radius.min(r_max);
            let r2 = r * r;
            let rz = r * Z_RATIO;
            let (inv_r2, inv_rz2) = (1.0 / r2, 1.0 / (rz * rz));
            let k0 = 2.0 / (std::f32::consts::PI * r2);
            // Whole rows of the rectangle, each a fixed run of 8 slots (vectorized).
            for row in usize::from(e.rect[1])..=usize::from(e.rect[3]) {
                let slots = row * ROW..(row + 1) * ROW;
                let at = |a: &[f32; SLOTS]| -> [f32; ROW] {
                    a[slots.clone()].try_into().unwrap_or([0.0; ROW])
                };
                let (px, py, pz, nx, ny, nz, side) =
                    (at(px), at(py), at(pz), at(nx), at(ny), at(nz), at(side));
                let mut w = [0.0f32; ROW];
                for j in 0..ROW {
                    let (dx, dy, dz) = (px[j] - cx, py[j] - cy, pz[j] - cz);
                    let h = dx * qx + dy * qy + dz * qz;
                    let d2 = (dx * dx + dy * dy + dz * dz - h * h).max(0.0);
                    let u = d2 * inv_r2;
                    let inside = u + h * h * inv_rz2 < 1.0;
                    let agree = nx[j] * qx + ny[j] * qy + nz[j] * qz > 0.5;
                    let facing = side[j] * (nx[j] * ix + ny[j] * iy + nz[j] * iz) > 0.0;
                    w[j] = if inside && agree && facing {
                        k0 * (1.0 - u)
                    } else {
                        0.0
                    };
                }
                for (acc, p) in [(&mut *ar, pr), (&mut *ag, pg), (&mut *ab, pb)] {
                    for (a, w) in acc[slots.clone()].iter_mut().zip(w) {
                        *a += p * w;
                    }
                }
            }
        }
    }

    fn sum_of(&self, slot: usize) -> Vec3 {
        Vec3::new(self.acc[0][slot], self.acc[1][slot], self.acc[2][slot])
    }
}

/// The estimate at sample `s` in `slot`: the sum of the terms of the photons of `list`
/// whose rectangles cover the slot.
fn list_sum(photons: &[Photon], list: &[Entry], s: &ViewSample, slot: usize, r_max: f32) -> Vec3 {
    let mut list = list.iter().filter(|e| e.covers(slot)).map(|e| e.photon);
    let Some(rho) = s.lambertian else {
        return list
            .map(|i| {
                let p = &photons[i as usize];
                volume_kernel(p, s, r_max).map_or(Vec3::ZERO, |k| {
                    let f = s
                        .material
                        .eval(s.frame.to_local(s.wo), s.frame.to_local(p.incident()));
                    f * p.power() * k
                })
            })
            .sum();
    };
    // Lambertian: f = ρ/π where the photon arrives on the viewer's side of the shading
    // normal (`Material::eval`'s wo.z·wi.z > 0), else 0.
    let side = s.frame.n.dot(s.wo);
    let mut sum = Vec3::ZERO;
    for i in list.by_ref() {
        let p = &photons[i as usize];
        if let Some(k) = volume_kernel(p, s, r_max) {
            if side * s.frame.n.dot(p.incident()) > 0.0 {
                sum += p.power() * k;
            }
        }
    }
    rho * sum
}

/// `common/photon_volume.wgsl`'s `volume_kernel` and `volume_normal_agrees`: the kernel
/// weight of photon `p` at sample `s`, `None` outside its ellipsoid or where the normals
/// disagree.
fn volume_kernel(p: &Photon, s: &ViewSample, r_max: f32) -> Option<f32> {
    let n = p.normal();
    let d = s.position - p.position();
    let dz = d.dot(n);
    let r = p.footprint_radius.min(r_max);
    let d2 = (d.length_squared() - dz * dz).max(0.0);
    let r2 = r * r;
    let rz = r * Z_RATIO;
    if d2 / r2 + dz * dz / (rz * rz) >= 1.0 || s.frame.n.dot(n) <= 0.5 {
        return None;
    }
    Some(2.0 / (std::f32::consts::PI * r2) * (1.0 - d2 / r2))
}
