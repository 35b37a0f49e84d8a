//! [`Mode::Directional`](super::Mode::Directional) (Moreau et al. 2016 section 4.7): the
//! cluster hierarchy and walk of [`super::cluster`], with the accepted photons' flux kept
//! per node in octant buckets of direction instead of a quadratic in position.

use super::passes::BinnedPasses;
use super::{Binned, Dispatch};
use crate::gpu::timer::Timer;

/// Records the shading: the accepted photons' flux summed per node and octant, then each
/// view sample's sum over its nodes and its leaf's test list.
pub(super) fn record_shading(
    b: &Binned,
    passes: &BinnedPasses,
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    timer: &mut Timer,
    nodes: Dispatch,
) {
    let p = passes.cluster_pipelines(device);
    let [tx, ty] = b.grid.tiles;
    let mut pass = b.compute_pass(encoder, timer, "directional shading", "directional shading");
    pass.set_pipeline(&p.directional_accumulate);
    pass.dispatch_workgroups(nodes.gx, nodes.gy, 1);
    pass.set_pipeline(&p.directional_shade);
    pass.dispatch_workgroups(tx, ty, 1);
}
