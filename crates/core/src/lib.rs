//! gi core: a real-time global-illumination renderer. The layers, bottom up: the scene
//! model, the uber BSDF and textures ([`scene`], [`bsdf`], [`texture`], [`sampling`]); CPU
//! ray tracing over a two-level BVH and the reference path tracer ([`trace`]); photon data
//! and structures ([`photon`]); the GPU device ([`gpu`]), its raster passes ([`raster`]) and
//! indirect-light estimators ([`estimate`]); and the frame engine ([`frame`]): a
//! [`Renderer`] that runs one method's passes per frame. [`render`] is one frame of a new
//! renderer. `docs/architecture.md` draws the layers and what each may import.
//!
//! Conventions: metres; linear RGB; point/spot intensity in W/sr per channel; right-handed
//! world; pixel (0, 0) is the top-left of the image.

pub mod bsdf;
pub mod cancel;
pub mod error;
pub mod estimate;
pub mod frame;
pub mod gpu;
pub mod image;
pub mod memory;
pub mod photon;
pub mod raster;
pub mod sampling;
pub mod scene;
pub mod texture;
pub mod trace;

pub use cancel::{Progress, Silent};
pub use error::{Error, Result};
pub use frame::{
    render, FrameDesc, Images, Method, MethodOptions, RenderOptions, RenderOutput, RenderStats,
    Renderer,
};
pub use image::Image;
pub use scene::{Scene, SceneUpdate};
