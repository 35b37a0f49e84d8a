//! [`Mode::Directional`](super::Mode::Directional) (Moreau et al. 2016 section 4.7): the
//! cluster hierarchy and walk of [`super::cluster`], with the accepted photons' flux kept
//! per node in octant buckets of direction instead of a quadratic in position.

use super::cluster::ClusterPipelines;

/// The shading's pipelines: the accepted photons' flux summed per node and octant, then
/// each view sample's sum over its nodes and its leaf's test list
/// ([`super::cluster::record_node_shading`]).
pub(super) fn shading(p: &ClusterPipelines) -> [&wgpu::ComputePipeline; 2] {
    [&p.directional_accumulate, &p.directional_shade]
}
