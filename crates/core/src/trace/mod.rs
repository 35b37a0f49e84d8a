//! CPU ray tracing: the obvhs BVH over the scene's triangles, surface interactions, the
//! reference path tracer and the light tracer that completes it for caustic paths.

pub mod bvh;
pub mod bvh_flat;
pub mod direct;
pub mod direct_mis;
pub mod interaction;
pub mod light_tracer;
pub mod light_vertex;
pub mod path;

pub use bvh::{Hit, SceneBvh};
pub use interaction::Interaction;
