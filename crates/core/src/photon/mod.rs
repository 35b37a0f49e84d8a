//! Photons (work in progress: merged with the photon tracer branch).
pub mod differential;
pub mod footprint;
pub mod lbvh;
