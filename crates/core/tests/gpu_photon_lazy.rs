//! A scene traced on the CPU does not compile the GPU photon trace's pipeline; one traced
//! on the GPU does (its own test binary: the device's pipelines are shared by the tests of
//! one binary).

use gi_core::frame::options::PhotonTrace;
use gi_core::scene::builtin;
use gi_core::{gpu, render, Silent};

#[test]
fn only_a_gpu_traced_frame_compiles_the_continuation_pass() {
    let ctx = gpu::context(None).expect("a GPU adapter (lavapipe in CI)");
    let mut scene = builtin::load("cornell").unwrap();
    scene.camera = scene.camera.with_size(32, 24);
    let frame = |trace: PhotonTrace| {
        let s = gi_core::options!(Ispm, photons: 2_000, spp: 1, photon_trace: trace);
        render(&scene, &s, &Silent).expect("ispm frame")
    };
    // `auto` on lavapipe is the CPU trace.
    let auto = frame(PhotonTrace::Auto);
    if ctx.info.device_type == wgpu::DeviceType::Cpu {
        assert_eq!(
            auto.stats.photon_trace, "cpu",
            "{}",
            auto.stats.photon_trace_reason
        );
    }
    frame(PhotonTrace::Cpu);
    assert!(
        auto.stats.photon_trace == "gpu" || !gpu::photon::trace::compiled(&ctx),
        "a CPU-traced frame compiled the GPU trace"
    );
    let g = frame(PhotonTrace::Gpu);
    assert_eq!(g.stats.photon_trace, "gpu");
    assert!(gpu::photon::trace::compiled(&ctx));
}
