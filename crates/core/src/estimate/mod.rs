//! Indirect-light estimators over one photon set, run by the frame engine after the eye
//! G-buffer. Each writes the same estimate (the photon-volume term of
//! `gpu/shaders/common/photon_volume.wgsl` summed over the photons) into an
//! [`target::IndirectTarget`], by a different route:
//! - [`volumes::Volumes`]: the rasterizer draws a bounding shape per photon (ISPM, section 5);
//! - [`binned::Binned`]: compute passes bin the photons into lists: per screen tile
//!   (`tiled`: Mara et al. 2013, Moreau et al. 2016 section 3.2) or per node of a view-sample
//!   cluster hierarchy with trivial acceptance (`cluster`: Moreau et al. section 4);
//! - [`cpu::CpuEstimate`]: the tiled binning and sum on the CPU, for CPU devices (`cpu`).
//!
//! [`Estimator`] is the user's choice; `auto` picks per adapter ([`Estimator::resolve`]).

pub mod binned;
pub mod cpu;
pub mod target;
pub mod volume_shape;
pub mod volumes;
pub mod wgsl;

pub use binned::{Binned, Mode};
pub use cpu::CpuEstimate;
pub use volumes::Volumes;

use crate::error::{Error, Result};
use std::str::FromStr;

/// Which indirect estimator splats the photons (method `ispm`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Estimator {
    /// Picked per adapter ([`Estimator::resolve`]).
    #[default]
    Auto,
    /// Raster photon volumes.
    Volumes,
    /// Tiled splatting in compute.
    Tiled,
    /// The view-sample cluster hierarchy in compute.
    Cluster,
    /// The cluster hierarchy's directional approximation (octant flux per node).
    Directional,
    /// The photon volumes' estimate computed on the CPU (for CPU devices).
    Cpu,
}

impl Estimator {
    pub const ALL: &'static [Estimator] = &[
        Estimator::Auto,
        Estimator::Volumes,
        Estimator::Tiled,
        Estimator::Cluster,
        Estimator::Directional,
        Estimator::Cpu,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Estimator::Auto => "auto",
            Estimator::Volumes => "volumes",
            Estimator::Tiled => "tiled",
            Estimator::Cluster => "cluster",
            Estimator::Directional => "directional",
            Estimator::Cpu => "cpu",
        }
    }

    /// The estimator to run on `adapter` and why: an explicit choice stands; `auto` follows
    /// the measurements in docs/bench/estimators.md.
    pub fn resolve(self, adapter: &wgpu::AdapterInfo) -> (Estimator, String) {
        if self != Estimator::Auto {
            return (self, "chosen in the settings".into());
        }
        auto_choice(adapter)
    }
}

/// `auto`: CPU devices (lavapipe, llvmpipe) compute the estimate on the CPU; GPUs measured or
/// documented to rasterize on a small part of the chip run compute; the rest keep the raster
/// volumes.
fn auto_choice(adapter: &wgpu::AdapterInfo) -> (Estimator, String) {
    let name = adapter.name.to_lowercase();
    if adapter.device_type == wgpu::DeviceType::Cpu {
        return (
            Estimator::Cpu,
            format!(
                "`{}` is a CPU device: the estimate computed natively on the CPU was the \
                 fastest there, 5-8x tiled's splat (docs/bench/frame.md)",
                adapter.name
            ),
        );
    }
    const DATACENTER: &[&str] = &["h100", "h200", "h800", "a100", "a800", "b100", "b200"];
    if DATACENTER.iter().any(|d| name.contains(d)) {
        return (
            Estimator::Tiled,
            format!(
                "`{}` is a datacenter GPU: it runs vertex and fragment work on few of its \
                 units (an H100 on 2 of 66 TPCs), compute on all of them",
                adapter.name
            ),
        );
    }
    (
        Estimator::Volumes,
        format!(
            "`{}` has full raster hardware: the ISPM photon volumes",
            adapter.name
        ),
    )
}

impl FromStr for Estimator {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        crate::error::parse_named(s, Estimator::ALL, Estimator::name, "estimator", "estimator")
    }
}

/// The estimator a renderer runs, with its GPU resources.
pub enum IndirectEstimate {
    Volumes(Box<Volumes>),
    Binned(Box<Binned>),
    Cpu(Box<CpuEstimate>),
}

impl IndirectEstimate {
    pub fn kind(&self) -> Estimator {
        match self {
            IndirectEstimate::Volumes(_) => Estimator::Volumes,
            IndirectEstimate::Binned(b) => match b.mode() {
                Mode::Tiled => Estimator::Tiled,
                Mode::Cluster => Estimator::Cluster,
                Mode::Directional => Estimator::Directional,
            },
            IndirectEstimate::Cpu(_) => Estimator::Cpu,
        }
    }

    /// Records the estimate of the uploaded photons and its upsampling.
    pub fn record(
        &self,
        ctx: &crate::gpu::GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut crate::gpu::timer::Timer,
    ) {
        self.record_splat(ctx, encoder, timer);
        self.record_upsample(ctx, encoder, timer);
    }

    /// Records the estimate of the uploaded photons at the estimate's resolution.
    pub fn record_splat(
        &self,
        ctx: &crate::gpu::GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut crate::gpu::timer::Timer,
    ) {
        match self {
            IndirectEstimate::Volumes(v) => v.record(ctx, encoder, timer),
            IndirectEstimate::Binned(t) => t.record(ctx, encoder, timer),
            // Written by `CpuEstimate::compute` before the frame's last submission.
            IndirectEstimate::Cpu(_) => {}
        }
    }

    /// Records the upsampling of the estimate to full resolution (nothing at subsample 1).
    pub fn record_upsample(
        &self,
        ctx: &crate::gpu::GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut crate::gpu::timer::Timer,
    ) {
        self.target().record_upsample(ctx, encoder, timer);
    }

    /// The target the estimate writes.
    pub fn target(&self) -> &target::IndirectTarget {
        match self {
            IndirectEstimate::Volumes(v) => &v.target,
            IndirectEstimate::Binned(b) => &b.target,
            IndirectEstimate::Cpu(c) => &c.target,
        }
    }

    fn target_mut(&mut self) -> &mut target::IndirectTarget {
        match self {
            IndirectEstimate::Volumes(v) => &mut v.target,
            IndirectEstimate::Binned(b) => &mut b.target,
            IndirectEstimate::Cpu(c) => &mut c.target,
        }
    }

    /// Has the upsampling add `full`'s estimate, made at full resolution
    /// ([`target::IndirectTarget::set_full_resolution`]).
    pub fn add_full_resolution(
        &mut self,
        ctx: &crate::gpu::GpuContext,
        gbuf: &crate::raster::gbuffer::GBuffer,
        full: &IndirectEstimate,
    ) {
        let view = full.output().1;
        self.target_mut().set_full_resolution(ctx, gbuf, view);
    }

    /// Photon-list entries of the last estimate: all, and trivial accepts (binned only).
    pub fn list_entries(&self) -> (u64, u64) {
        match self {
            IndirectEstimate::Volumes(_) => (0, 0),
            IndirectEstimate::Binned(b) => b.entries(),
            IndirectEstimate::Cpu(c) => (c.entries(), 0),
        }
    }

    /// GPU memory held beyond the targets (bytes by part), like Moreau et al.'s Table 1.
    pub fn memory(&self) -> Vec<(String, u64)> {
        let parts = match self {
            IndirectEstimate::Volumes(v) => v.memory(),
            IndirectEstimate::Binned(t) => t.memory(),
            IndirectEstimate::Cpu(c) => c.memory(),
        };
        parts.into_iter().map(|(n, b)| (n.to_string(), b)).collect()
    }

    /// Sets where in its pixel the eye G-buffer is sampled (progressive passes move it).
    pub fn set_sample_centre(&mut self, centre: glam::Vec2) {
        self.target_mut().set_sample_centre(centre);
    }

    /// The estimate at full resolution.
    pub fn output(&self) -> (&wgpu::Texture, &wgpu::TextureView) {
        match self {
            IndirectEstimate::Volumes(v) => v.output(),
            IndirectEstimate::Binned(t) => t.output(),
            IndirectEstimate::Cpu(c) => c.target.output(),
        }
    }
}
