//! The indirect estimators' WGSL (`estimate/shaders/`), each joined after the shared code of
//! `gpu::shaders` when its module is created.

/// The photon-volume estimate term shared by the estimators (needs `gpu::shaders::BSDF`).
pub const PHOTON_VOLUME: &str = include_str!("shaders/photon_volume.wgsl");

pub const VOLUME: &str = include_str!("shaders/volume.wgsl");
pub const TILED: &str = include_str!("shaders/tiled.wgsl");
pub const CLUSTER: &str = include_str!("shaders/cluster.wgsl");
pub const UPSAMPLE: &str = include_str!("shaders/upsample.wgsl");
