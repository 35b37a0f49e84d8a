//! The photon trace on the GPU (issue #45 item 1): the uber BSDF's sampling and Russian
//! roulette in WGSL ([`SCATTER`], the formulas of `photon::trace::scatter_local`), and the
//! continuation pass ([`trace`]) that follows the bounce maps' first-scatter rays over the
//! scene's BVH ([`super::bvh`]) and writes photon records in the CPU trace's layout; it
//! also follows the photons of area lights, the sun and the sky from their emission
//! ([`emitted`]: emitted on the CPU as the CPU trace emits them).
//! [`PhotonTrace`] is the `photon_trace` setting. Pipelines are made on first use: a scene
//! not traced on the GPU compiles none of this.

pub mod emitted;
pub mod resident;
pub mod scatter_query;
pub mod scene;
pub mod trace;

use super::layout::{buffer, storage_entry, storage_rw_entry, uniform_entry_sized};
use super::{GpuContext, Pipelines};
use crate::error::{Error, Result};
use crate::scene::Scene;
use std::str::FromStr;

/// BSDF sampling and the roulette (after the shared `types.wgsl` and `bsdf.wgsl`).
pub const SCATTER: &str = include_str!("../shaders/photon/scatter.wgsl");

/// Where method `ispm` traces the photons after their first scatter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PhotonTrace {
    /// Per adapter ([`PhotonTrace::resolve`]).
    #[default]
    Auto,
    /// On the CPU (`photon::trace`), the reference.
    Cpu,
    /// On the GPU ([`trace::continue_paths`]).
    Gpu,
}

impl PhotonTrace {
    pub const ALL: &'static [PhotonTrace] =
        &[PhotonTrace::Auto, PhotonTrace::Cpu, PhotonTrace::Gpu];

    pub fn name(self) -> &'static str {
        match self {
            PhotonTrace::Auto => "auto",
            PhotonTrace::Cpu => "cpu",
            PhotonTrace::Gpu => "gpu",
        }
    }

    /// The trace to run on `adapter` for `scene` and why. `footprints`: the frame sizes
    /// photon volumes by differentials, which the GPU trace does not carry. An explicit
    /// `gpu` on a scene or setting the GPU trace cannot reproduce is a setting error;
    /// `auto` then traces on the CPU, as it does on CPU devices, where the GPU traversal is
    /// 13–25× slower than the CPU's (docs/bench/gpu-bvh.md).
    pub fn resolve(
        self,
        adapter: &wgpu::AdapterInfo,
        scene: &Scene,
        footprints: bool,
    ) -> Result<(PhotonTrace, String)> {
        let refused = if footprints {
            Some(
                "footprint_volumes needs photon differentials, which the GPU trace does not carry"
                    .to_string(),
            )
        } else {
            unsupported(scene)
        };
        Ok(match (self, refused) {
            (PhotonTrace::Gpu, Some(why)) => {
                return Err(Error::setting("photon_trace", format!("`gpu`: {why}")))
            }
            (PhotonTrace::Auto, Some(why)) => (PhotonTrace::Cpu, why),
            (PhotonTrace::Auto, None) if adapter.device_type == wgpu::DeviceType::Cpu => (
                PhotonTrace::Cpu,
                format!(
                    "`{}` is a CPU device: its BVH traversal is 13-25x slower than the CPU's \
                     (docs/bench/gpu-bvh.md)",
                    adapter.name
                ),
            ),
            (PhotonTrace::Auto, None) => (
                PhotonTrace::Gpu,
                format!(
                    "`{}` is a GPU: photons traced without a CPU round trip",
                    adapter.name
                ),
            ),
            (chosen, _) => (chosen, "chosen in the settings".into()),
        })
    }
}

impl FromStr for PhotonTrace {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        crate::error::parse_named(
            s,
            PhotonTrace::ALL,
            PhotonTrace::name,
            "photon_trace",
            "photon trace",
        )
    }
}

/// Why the GPU trace cannot reproduce `scene`'s photons, if it cannot: it samples the uber
/// BSDF with GGX only, reads no textures and traverses no alpha masks.
pub fn unsupported(scene: &Scene) -> Option<String> {
    if scene.has_alpha_masks() {
        return Some("the GPU traversal has no alpha masks".into());
    }
    if let Some(i) = scene.material_maps.iter().position(|m| !m.is_empty()) {
        return Some(format!(
            "material {i} has texture maps, which the GPU trace does not read"
        ));
    }
    let exact = |m: &crate::bsdf::Material| {
        m.coating.is_some()
            || m.conductor.is_some()
            || m.rough_glass
            || m.thin.is_some()
            || m.distribution != crate::bsdf::Distribution::Ggx
    };
    scene
        .materials
        .iter()
        .position(exact)
        .map(|i| format!("material {i} is an exact model (coating, conductor, rough or thin glass, Beckmann), which the GPU trace samples only as the uber BSDF"))
}

/// A compute pass of this module: its group-0 layout and pipeline (entry `entry` of the
/// concatenated `parts`, group 1 the BVH's when `bvh`).
pub(crate) struct ComputePass {
    pub layout: wgpu::BindGroupLayout,
    pub pipeline: wgpu::ComputePipeline,
}

/// The binding kinds of a [`ComputePass`]'s group 0, in binding order.
#[derive(Clone, Copy)]
pub(crate) enum Binding {
    Read,
    ReadWrite,
    Uniform(u64),
}

impl ComputePass {
    pub fn new(
        ctx: &GpuContext,
        entry: &str,
        bindings: &[Binding],
        parts: &[&str],
        bvh: bool,
    ) -> Self {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let entries: Vec<_> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| match *b {
                Binding::Read => storage_entry(i as u32, compute),
                Binding::ReadWrite => storage_rw_entry(i as u32, compute),
                Binding::Uniform(size) => uniform_entry_sized(i as u32, compute, false, size),
            })
            .collect();
        let layout = super::pipeline::bind_group_layout(device, entry, &entries);
        let bvh_layout = bvh.then(|| super::bvh::BvhLayout::get(ctx));
        let mut layouts = vec![&layout];
        if let Some(b) = &bvh_layout {
            layouts.push(&b.layout);
        }
        let pipeline_layout = super::pipeline::pipeline_layout(device, entry, &layouts);
        let shared = [
            super::shaders::COMMON,
            super::shaders::BSDF,
            super::shaders::SAMPLE,
        ];
        let mut all = vec![shared[0], shared[1], shared[2], SCATTER];
        all.extend_from_slice(parts);
        let module = super::shaders::module(device, entry, &all);
        let pipeline = super::compute_pipeline_of(device, &pipeline_layout, &module, entry);
        ComputePass { layout, pipeline }
    }

    /// Binds `buffers` as group 0 (and `bvh` as group 1), runs one thread per item of `n`
    /// in workgroups of 64 and copies each `(from, to, bytes)` after it; submitted.
    pub fn run(
        &self,
        ctx: &GpuContext,
        buffers: &[&wgpu::Buffer],
        bvh: Option<&wgpu::BindGroup>,
        n: u32,
        copies: &[(&wgpu::Buffer, &wgpu::Buffer, u64)],
    ) -> wgpu::SubmissionIndex {
        let entries: Vec<_> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| buffer(i as u32, b))
            .collect();
        let group = super::create_bind_group(
            &ctx.device,
            &wgpu::BindGroupDescriptor {
                label: Some("gpu photon group"),
                layout: &self.layout,
                entries: &entries,
            },
        );
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &group, &[]);
            if let Some(b) = bvh {
                pass.set_bind_group(1, b, &[]);
            }
            pass.dispatch_workgroups(n.div_ceil(64), 1, 1);
        }
        for (from, to, bytes) in copies {
            encoder.copy_buffer_to_buffer(from, 0, to, 0, *bytes);
        }
        ctx.queue.submit([encoder.finish()])
    }
}

/// A storage buffer of `bytes` that can be copied out of.
pub(crate) fn output_buffer(ctx: &GpuContext, label: &str, bytes: u64) -> wgpu::Buffer {
    super::create_buffer(
        &ctx.device,
        &wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes.max(16),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        },
    )
}
