//! [`Mode::Tiled`](super::Mode::Tiled) (Mara et al. 2013, as Moreau et al. 2016 section 3.2
//! describe it): the photons are binned to screen tiles (counting, prefix sum, list build;
//! each tile bounded by the world-space box of its view samples) and every view sample
//! sums its tile's list (`estimate/shaders/tiled.wgsl`).

use super::passes::{BinnedPasses, TILED_PARTS};
use super::{Binned, Dispatch};
use crate::gpu::timer::Timer;

/// The tiled estimator's pipelines.
pub(super) struct TiledPipelines {
    tile_bounds: wgpu::ComputePipeline,
    bin_count: wgpu::ComputePipeline,
    scan: wgpu::ComputePipeline,
    bin_fill: wgpu::ComputePipeline,
    shade: wgpu::ComputePipeline,
}

impl BinnedPasses {
    fn tiled_pipelines(&self, device: &wgpu::Device) -> &TiledPipelines {
        self.tiled.get_or_init(|| {
            let [tile_bounds, bin_count, scan, bin_fill, shade] = self.pipelines(
                device,
                "tiled shader",
                &TILED_PARTS,
                ["tile_bounds", "bin_count", "scan", "bin_fill", "shade"],
            );
            TiledPipelines {
                tile_bounds,
                bin_count,
                scan,
                bin_fill,
                shade,
            }
        })
    }
}

/// Records the tiles' bounds and the binning: per photon the tiles it overlaps counted,
/// the counts' prefix sum (the lists' offsets), the lists filled.
pub(super) fn record_binning(
    b: &Binned,
    passes: &BinnedPasses,
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    timer: &mut Timer,
    d: Dispatch,
) {
    let p = passes.tiled_pipelines(device);
    let [tx, ty] = b.grid.tiles;
    let mut pass = b.compute_pass(encoder, timer, "tile bounds", "tiled binning");
    pass.set_pipeline(&p.tile_bounds);
    pass.dispatch_workgroups(tx, ty, 1);
    drop(pass);
    b.record_node_copy(encoder);
    let mut pass = b.compute_pass(encoder, timer, "tiled binning", "tiled binning");
    if d.any {
        pass.set_pipeline(&p.bin_count);
        pass.dispatch_workgroups(d.gx, d.gy, 1);
    }
    pass.set_pipeline(&p.scan);
    pass.dispatch_workgroups(1, 1, 1);
    if d.any {
        pass.set_pipeline(&p.bin_fill);
        pass.dispatch_workgroups(d.gx, d.gy, 1);
    }
}

/// Records the shading: every view sample sums its tile's list.
pub(super) fn record_shading(
    b: &Binned,
    passes: &BinnedPasses,
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    timer: &mut Timer,
) {
    let p = passes.tiled_pipelines(device);
    let [tx, ty] = b.grid.tiles;
    let mut pass = b.compute_pass(encoder, timer, "tiled shading", "tiled shading");
    pass.set_pipeline(&p.shade);
    pass.dispatch_workgroups(tx, ty, 1);
}
