//! gi core: scene model, the uber BSDF, CPU ray tracing (obvhs) and the reference
//! renderer. Later techniques (GPU rasterization, ISPM, photon maps) build on these.
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
