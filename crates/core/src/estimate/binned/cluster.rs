//! [`Mode::Cluster`](super::Mode::Cluster) (Moreau et al. 2016 section 4): the view samples
//! of each tile are split into clusters by depth and normal, a 3-level hierarchy of boxes
//! and normal cones is built over them, each photon walks it top-down (rejecting by bounds
//! and cone, *trivially accepting* nodes wholly inside its kernel), and accepted photons are
//! summed per node exactly as a quadratic in the sample position, so a sample pays for the
//! photons that only overlap its leaf (`estimate/shaders/cluster.wgsl`). The hierarchy and
//! the walk are [`super::directional`]'s too.

use super::passes::{BinnedPasses, TILED_PARTS};
use super::{Binned, Dispatch};
use crate::estimate::wgsl;
use crate::gpu::timer::Timer;

/// The hierarchy's pipelines: building, walking, binning, and the two shadings (cluster
/// and directional).
pub(super) struct ClusterPipelines {
    leaves: wgpu::ComputePipeline,
    parents1: wgpu::ComputePipeline,
    parents2: wgpu::ComputePipeline,
    top_count: wgpu::ComputePipeline,
    jobs0: wgpu::ComputePipeline,
    mid_count: wgpu::ComputePipeline,
    jobs1: wgpu::ComputePipeline,
    low_count: wgpu::ComputePipeline,
    scan: wgpu::ComputePipeline,
    top_fill: wgpu::ComputePipeline,
    mid_fill: wgpu::ComputePipeline,
    low_fill: wgpu::ComputePipeline,
    accumulate: wgpu::ComputePipeline,
    shade: wgpu::ComputePipeline,
    pub directional_accumulate: wgpu::ComputePipeline,
    pub directional_shade: wgpu::ComputePipeline,
}

impl BinnedPasses {
    pub(super) fn cluster_pipelines(&self, device: &wgpu::Device) -> &ClusterPipelines {
        self.cluster.get_or_init(|| {
            let [
                leaves,
                parents1,
                parents2,
                top_count,
                jobs0,
                mid_count,
                jobs1,
                low_count,
                scan,
                top_fill,
                mid_fill,
                low_fill,
                accumulate,
                shade,
                directional_accumulate,
                directional_shade,
            ] = self.pipelines(
                device,
                "cluster shader",
                &[&TILED_PARTS[..], &[wgsl::CLUSTER]].concat(),
                [
                    "cluster_leaves",
                    "cluster_parents1",
                    "cluster_parents2",
                    "cluster_top_count",
                    "cluster_jobs0",
                    "cluster_mid_count",
                    "cluster_jobs1",
                    "cluster_low_count",
                    "scan",
                    "cluster_top_fill",
                    "cluster_mid_fill",
                    "cluster_low_fill",
                    "cluster_accumulate",
                    "cluster_shade",
                    "directional_accumulate",
                    "directional_shade",
                ],
            );
            ClusterPipelines {
                leaves,
                parents1,
                parents2,
                top_count,
                jobs0,
                mid_count,
                jobs1,
                low_count,
                scan,
                top_fill,
                mid_fill,
                low_fill,
                accumulate,
                shade,
                directional_accumulate,
                directional_shade,
            }
        })
    }
}

/// Records the hierarchy's build (leaves, then the two parent levels), the photons' walk
/// in sub-passes over job lists, and the binning (counting, prefix sum, filling).
pub(super) fn record_binning(
    b: &Binned,
    passes: &BinnedPasses,
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    timer: &mut Timer,
    d: Dispatch,
) {
    let p = passes.cluster_pipelines(device);
    let (grid, r) = (&b.grid, &b.res);
    let [tx, ty] = grid.tiles;
    let mut pass = b.compute_pass(encoder, timer, "cluster hierarchy", "cluster hierarchy");
    pass.set_pipeline(&p.leaves);
    pass.dispatch_workgroups(tx, ty, 1);
    pass.set_pipeline(&p.parents1);
    pass.dispatch_workgroups((grid.l1[0] * grid.l1[1]).div_ceil(64), 1, 1);
    pass.set_pipeline(&p.parents2);
    pass.dispatch_workgroups((grid.l2[0] * grid.l2[1]).div_ceil(64), 1, 1);
    drop(pass);
    b.record_node_copy(encoder);
    // The walk in sub-passes over job lists, counting then filling; the job passes' sizes
    // come from the GPU (indirect dispatch, arguments copied out of `counts` between
    // passes).
    if d.any {
        for (level, count, args) in [(0, &p.top_count, &p.jobs0), (1, &p.mid_count, &p.jobs1)] {
            let mut pass = b.compute_pass(encoder, timer, "cluster walk", "cluster binning");
            pass.set_pipeline(count);
            if level == 0 {
                pass.dispatch_workgroups(d.gx, d.gy, 1);
            } else {
                pass.dispatch_workgroups_indirect(&r.job_args, 0);
            }
            pass.set_pipeline(args);
            pass.dispatch_workgroups(1, 1, 1);
            drop(pass);
            let from = (grid.slots as u64 + 4 + 3 * level) * 4;
            encoder.copy_buffer_to_buffer(&r.counts, from, &r.job_args, 12 * level, 12);
        }
    }
    let mut pass = b.compute_pass(encoder, timer, "cluster binning", "cluster binning");
    if d.any {
        pass.set_pipeline(&p.low_count);
        pass.dispatch_workgroups_indirect(&r.job_args, 12);
    }
    pass.set_pipeline(&p.scan);
    pass.dispatch_workgroups(1, 1, 1);
    if d.any {
        pass.set_pipeline(&p.top_fill);
        pass.dispatch_workgroups(d.gx, d.gy, 1);
        pass.set_pipeline(&p.mid_fill);
        pass.dispatch_workgroups_indirect(&r.job_args, 0);
        pass.set_pipeline(&p.low_fill);
        pass.dispatch_workgroups_indirect(&r.job_args, 12);
    }
}

/// The shading's pipelines: the accepted photons summed per node as a quadratic, then each
/// view sample's sum over its nodes and its leaf's test list ([`record_node_shading`]).
pub(super) fn shading(p: &ClusterPipelines) -> [&wgpu::ComputePipeline; 2] {
    [&p.accumulate, &p.shade]
}

/// Records a shading over the hierarchy under stage `stage`: `accumulate` once per node,
/// then `shade` once per tile.
pub(super) fn record_node_shading(
    b: &Binned,
    [accumulate, shade]: [&wgpu::ComputePipeline; 2],
    encoder: &mut wgpu::CommandEncoder,
    timer: &mut Timer,
    stage: &'static str,
    nodes: Dispatch,
) {
    let [tx, ty] = b.grid.tiles;
    let mut pass = b.compute_pass(encoder, timer, stage, stage);
    pass.set_pipeline(accumulate);
    pass.dispatch_workgroups(nodes.gx, nodes.gy, 1);
    pass.set_pipeline(shade);
    pass.dispatch_workgroups(tx, ty, 1);
}
