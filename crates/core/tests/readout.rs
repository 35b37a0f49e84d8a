//! The radiance handed back in the form asked for (`FrameDesc::readout`, issue 45 item 3):
//! the 8-bit display image tone-mapped on the GPU equals the CPU tone map of the float
//! image within 1 LSB; half floats equal the float image within half precision; nothing
//! else is handed back; methods whose radiance is finished on the CPU encode there.

mod common;

use common::frames::settings;
use gi_core::frame::readout::{display_pixels, Display, Precision, Readout, Tonemap};
use gi_core::frame::{FrameDesc, Images, Renderer};
use gi_core::scene::builtin;
use gi_core::{Image, Method, RenderOutput, Silent};

fn frame(r: &mut Renderer, readout: Readout) -> RenderOutput {
    let desc = FrameDesc {
        seed: None,
        images: Images::default(),
        serial: false,
        readout,
    };
    r.render(&desc, &Silent).expect("frame")
}

/// The stage "display encode" (the GPU pass) ran in the frame.
fn encoded_on_gpu(out: &RenderOutput, pass: &str) -> bool {
    out.stats.stages.iter().any(|(n, _)| n == pass)
}

/// Every channel of every pixel, rows top first.
fn channels(img: &Image) -> Vec<f32> {
    img.pixels.iter().flat_map(|p| p.to_array()).collect()
}

/// Largest difference of two 8-bit images, and how many channels differ at all.
fn lsb_difference(a: &[u8], b: &[u8]) -> (u8, usize) {
    assert_eq!(a.len(), b.len());
    let d = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y));
    (d.clone().max().unwrap_or(0), d.filter(|&v| v > 0).count())
}

/// One frame with the float radiance and the display image: the GPU's 8-bit image
/// (rounded in the shader, so the 8-bit store is exact) equals the CPU tone map of the same
/// frame's float radiance within 1 LSB (the GPU's `pow`/`log2` differ from the CPU's in the
/// last bits of f32, which moves a value across a rounding edge at most by one step), for
/// `clip` and `agx`, with exposure. Methods `direct` and `ispm` (cornell, a frame and a
/// still frame); at least 99% of the channels are exactly equal.
#[test]
fn gpu_display_image_equals_the_cpu_tone_map() {
    let scene = builtin::load("cornell").expect("scene");
    for method in [Method::Direct, Method::Ispm] {
        let mut r = Renderer::new(&scene, &settings(method)).expect("renderer");
        for (tonemap, exposure) in [(Tonemap::Clip, 1.5), (Tonemap::Agx, 0.0)] {
            let d = Display { tonemap, exposure };
            let out = frame(
                &mut r,
                Readout {
                    radiance: Some(Precision::Float32),
                    display: Some(d),
                },
            );
            assert!(
                encoded_on_gpu(&out, "display encode"),
                "{:?}",
                out.stats.stages
            );
            let gpu = out.display.as_ref().expect("a display image");
            let cpu = display_pixels(&out.radiance, d);
            let (max, differ) = lsb_difference(gpu, &cpu);
            assert!(max <= 1, "{method:?} {tonemap:?}: {max} LSB apart");
            assert!(
                differ * 100 <= gpu.len(),
                "{method:?} {tonemap:?}: {differ} differ"
            );
            assert!(gpu.iter().any(|&v| v > 30), "{method:?}: a black image");
        }
    }
}

/// `radiance: None` with a display image hands back the display image alone (the float
/// radiance empty), and a frame asking for half floats hands back half floats within one
/// half-float step (2^-10 relative: lavapipe's Rgba16Float store rounds toward zero, where
/// round-to-nearest would be within half a step) of a still frame's 32-bit radiance.
#[test]
fn only_what_was_asked_is_handed_back() {
    let scene = builtin::load("cornell").expect("scene");
    let mut r = Renderer::new(&scene, &settings(Method::Ispm)).expect("renderer");
    let float = frame(&mut r, Readout::default());
    assert!(float.display.is_none() && float.radiance_half.is_none());
    let d = Display {
        tonemap: Tonemap::Clip,
        exposure: 0.0,
    };
    let only = frame(
        &mut r,
        Readout {
            radiance: None,
            display: Some(d),
        },
    );
    assert_eq!(only.radiance.pixels.len(), 0);
    let shown = only.display.expect("display image");
    assert!(lsb_difference(&shown, &display_pixels(&float.radiance, d)).0 <= 1);
    let half = frame(
        &mut r,
        Readout {
            radiance: Some(Precision::Float16),
            display: None,
        },
    );
    assert!(
        encoded_on_gpu(&half, "half encode"),
        "{:?}",
        half.stats.stages
    );
    assert_eq!(half.radiance.pixels.len(), 0);
    let h = half.radiance_half.expect("half floats");
    let f = channels(&float.radiance);
    assert_eq!(h.len(), f.len());
    for (a, b) in h.iter().zip(&f) {
        let tol = b.abs() * 2f32.powi(-10) + 6e-8;
        assert!((a.to_f32() - b).abs() <= tol, "half {a} against {b}");
    }
    assert!(f.iter().any(|&v| v > 0.01), "a black image");
}

/// Where the radiance is finished on the CPU (a progressive pass's running mean, `bidir`'s
/// spike spreading) the GPU reads back the float radiance and the display image is the
/// CPU tone map of the final radiance: exactly `display_pixels` of a float frame rendered
/// the same way.
#[test]
fn cpu_finished_radiance_is_encoded_on_the_cpu() {
    let scene = builtin::load("cornell").expect("scene");
    let d = Display {
        tonemap: Tonemap::Agx,
        exposure: -0.5,
    };
    let both = Readout {
        radiance: Some(Precision::Float32),
        display: Some(d),
    };
    for s in [
        settings(Method::Ispm).progressive(),
        settings(Method::Bidir),
        settings(Method::Path),
    ] {
        let mut r = Renderer::new(&scene, &s).expect("renderer");
        let out = frame(&mut r, both);
        assert!(!encoded_on_gpu(&out, "display encode"));
        let shown = out.display.expect("display image");
        assert_eq!(shown, display_pixels(&out.radiance, d));
        assert_ne!(out.radiance, Image::new(0, 0));
    }
}

/// A still frame (nothing changed since the last) records no GPU pass, not even the
/// composite: it reads the last frame's readback buffers again, so its images are the last
/// frame's bit for bit and equal a serial frame (`FrameDesc::serial`) of the same state on
/// a renderer of its own. A new readout in a still view (another exposure) composites and
/// encodes again. Methods `direct` and `ispm`.
#[test]
fn still_frames_run_no_pass_and_equal_the_serial_frame() {
    let scene = builtin::load("cornell").expect("scene");
    let readout = |exposure| Readout {
        radiance: Some(Precision::Float32),
        display: Some(Display {
            tonemap: Tonemap::Clip,
            exposure,
        }),
    };
    for method in [Method::Direct, Method::Ispm] {
        let s = settings(method);
        let mut r = Renderer::new(&scene, &s).expect("renderer");
        let first = frame(&mut r, readout(0.0));
        let still = frame(&mut r, readout(0.0));
        assert!(
            encoded_on_gpu(&first, "composite"),
            "{:?}",
            first.stats.stages
        );
        for pass in ["composite", "display encode"] {
            assert!(
                !encoded_on_gpu(&still, pass),
                "{method:?}: {pass} in a still frame"
            );
        }
        assert_eq!(still.radiance, first.radiance, "{method:?}");
        assert_eq!(still.display, first.display, "{method:?}");
        let brighter = frame(&mut r, readout(1.0));
        assert!(encoded_on_gpu(&brighter, "display encode"), "{method:?}");
        assert_eq!(brighter.radiance, first.radiance, "{method:?}");
        assert_ne!(brighter.display, first.display, "{method:?}");
        let mut serial = Renderer::new(&scene, &s).expect("renderer");
        let desc = FrameDesc {
            serial: true,
            readout: readout(0.0),
            ..Default::default()
        };
        let reference = serial.render(&desc, &Silent).expect("serial frame");
        assert_eq!(still.radiance, reference.radiance, "{method:?}");
        assert_eq!(still.display, reference.display, "{method:?}");
    }
}
