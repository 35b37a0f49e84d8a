//! What the `Renderer` tests share: small settings, a frame with every image, image
//! differences and means.

use gi_core::frame::{FrameDesc, Images};
use gi_core::{Image, Method};

/// 40×30, 4 spp, 6k photons (k 20), depth 4: small enough for every method in a test.
pub fn settings(method: Method) -> gi_core::RenderOptions {
    gi_core::RenderOptions::defaults(method)
        .with("width", 40)
        .with("height", 30)
        .with("spp", 4)
        .with("photons", 6_000)
        .with("k", 20)
        .with("max_depth", 4)
}

/// A frame with every image, its own seed, overlapped.
pub fn all() -> FrameDesc {
    FrameDesc {
        seed: None,
        images: Images::ALL,
        serial: false,
        readout: Default::default(),
    }
}

/// Largest per-channel difference of two images of one size.
pub fn max_difference(a: &Image, b: &Image) -> f32 {
    assert_eq!((a.width, a.height), (b.width, b.height));
    super::max_difference(a, b, 1.0)
}

/// The mean of every channel of every pixel.
pub fn mean(img: &Image) -> f32 {
    img.pixels.iter().map(|p| p.element_sum()).sum::<f32>() / (3 * img.pixels.len()) as f32
}
