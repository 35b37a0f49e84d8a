//! In what form a frame hands back its radiance ([`Readout`]): the float image, half floats,
//! and/or a tone-mapped 8-bit sRGB image for display. A GPU method whose composite is the
//! final radiance encodes what was asked for on the GPU and reads back only that
//! (`frame::gpu::encode`); everywhere else (CPU methods, progressive sums, radiance
//! corrected on the CPU after the readback) the same encodings run here, on the float image.
//!
//! The tone maps are those of `gi.display` (Python): `clip` (clip to [0, 1], sRGB transfer
//! curve) and `agx` (the AgX-style filmic curve), after scaling by `2^exposure`; the 8-bit
//! value is `round(255 · encoded)`. NaN and ±∞ show black, as in `gi.display.to_display`.

use super::RenderOutput;
use crate::image::Image;
use glam::Vec3;

/// Precision of the float radiance handed back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    /// 32-bit floats (`RenderOutput::radiance`).
    Float32,
    /// IEEE half floats (`RenderOutput::radiance_half`): 11 significant bits, up to 65504.
    Float16,
}

/// A display tone map (see the module).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tonemap {
    Clip,
    Agx,
}

impl Tonemap {
    /// The tone map of `gi.display` named `name` that the core implements (`clip`,
    /// `filmic`/`agx`); `None` for the others (`aces`, which Python applies itself).
    pub fn parse(name: &str) -> Option<Tonemap> {
        match name {
            "clip" => Some(Tonemap::Clip),
            "filmic" | "agx" => Some(Tonemap::Agx),
            _ => None,
        }
    }

    /// The code the GPU encoding pass switches on.
    pub(crate) fn code(self) -> u32 {
        match self {
            Tonemap::Clip => 0,
            Tonemap::Agx => 1,
        }
    }
}

/// A tone-mapped 8-bit sRGB image to hand back (`RenderOutput::display`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Display {
    pub tonemap: Tonemap,
    /// Stops: the radiance is scaled by `2^exposure` before the tone map.
    pub exposure: f32,
}

/// What a frame hands back of its radiance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Readout {
    /// The float radiance, at this precision; `None`: not at all (the display image only).
    pub radiance: Option<Precision>,
    /// The display image, if asked for.
    pub display: Option<Display>,
}

impl Default for Readout {
    /// The 32-bit float radiance, no display image.
    fn default() -> Self {
        Readout {
            radiance: Some(Precision::Float32),
            display: None,
        }
    }
}

// AgX inset/outset matrices, rows = input channels (`rgb @ M`), as in `gi.display`.
const AGX_INSET: [[f32; 3]; 3] = [
    [0.842_479_06, 0.042_328_242, 0.042_375_655],
    [0.078_433_6, 0.878_468_6, 0.078_433_6],
    [0.079_223_745, 0.079_166_13, 0.879_143],
];
const AGX_OUTSET: [[f32; 3]; 3] = [
    [1.196_879, -0.052_896_85, -0.052_971_635],
    [-0.098_020_88, 1.151_903_1, -0.098_043_45],
    [-0.099_029_74, -0.098_961_18, 1.151_073_7],
];
const AGX_MIN_EV: f32 = -12.47393;
const AGX_MAX_EV: f32 = 4.026069;
/// The AgX sigmoid's polynomial, highest power first.
const AGX_SIGMOID: [f32; 7] = [15.5, -40.14, 31.96, -6.868, 0.4298, 0.1191, -0.00232];

/// `x @ m` (a row vector times a matrix whose rows are the input channels).
fn row_times(x: Vec3, m: &[[f32; 3]; 3]) -> Vec3 {
    Vec3::from_array(std::array::from_fn(|j| {
        x.x * m[0][j] + x.y * m[1][j] + x.z * m[2][j]
    }))
}

/// The sRGB transfer curve of a linear value, clipped to [0, 1].
pub fn srgb_encode(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// The AgX-style filmic view of linear RGB: display-encoded sRGB in [0, 1].
fn agx(linear: Vec3) -> Vec3 {
    let x = row_times(linear.max(Vec3::splat(1e-10)), &AGX_INSET);
    let x = x.max(Vec3::splat(1e-10)).to_array().map(|c| {
        let t = (c.log2().clamp(AGX_MIN_EV, AGX_MAX_EV) - AGX_MIN_EV) / (AGX_MAX_EV - AGX_MIN_EV);
        AGX_SIGMOID.iter().fold(0.0, |acc, k| acc * t + k)
    });
    let x = row_times(Vec3::from_array(x), &AGX_OUTSET);
    Vec3::from_array(
        x.to_array()
            .map(|c| srgb_encode(c.clamp(0.0, 1.0).powf(2.2))),
    )
}

/// One pixel's display value in [0, 1] (see the module).
pub fn display_value(radiance: Vec3, d: Display) -> Vec3 {
    let finite = Vec3::from_array(
        radiance
            .to_array()
            .map(|c| if c.is_finite() { c } else { 0.0 }),
    );
    let x = finite.max(Vec3::ZERO) * 2f32.powf(d.exposure);
    match d.tonemap {
        Tonemap::Clip => Vec3::from_array(x.to_array().map(srgb_encode)),
        Tonemap::Agx => agx(x),
    }
}

/// An 8-bit channel of a display value in [0, 1].
fn quantize(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// The display image of `img`: RGB, 3 bytes a pixel, rows top first.
pub fn display_pixels(img: &Image, d: Display) -> Vec<u8> {
    img.pixels
        .iter()
        .flat_map(|p| display_value(*p, d).to_array().map(quantize))
        .collect()
}

/// `img` as half floats: RGB, 3 a pixel, rows top first.
pub fn half_pixels(img: &Image) -> Vec<half::f16> {
    img.pixels
        .iter()
        .flat_map(|p| p.to_array().map(half::f16::from_f32))
        .collect()
}

/// What the GPU reads back for `asked`: the same when the composite is the frame's final
/// radiance (`composite_final`), else the 32-bit floats, which [`complete`] then encodes.
pub(crate) fn on_gpu(asked: Readout, composite_final: bool) -> Readout {
    if composite_final {
        asked
    } else {
        Readout::default()
    }
}

/// Gives `out` the forms of its radiance that `asked` names and that the frame did not
/// read back (encoded from the 32-bit radiance), and drops the 32-bit radiance unless
/// asked for.
pub(crate) fn complete(out: &mut RenderOutput, asked: Readout) {
    if let (Some(d), None) = (asked.display, &out.display) {
        out.display = Some(display_pixels(&out.radiance, d));
    }
    if asked.radiance == Some(Precision::Float16) && out.radiance_half.is_none() {
        out.radiance_half = Some(half_pixels(&out.radiance));
    }
    if asked.radiance != Some(Precision::Float32) {
        out.radiance = Image::new(0, 0);
    }
    if asked.radiance != Some(Precision::Float16) {
        out.radiance_half = None;
    }
    if asked.display.is_none() {
        out.display = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_matches_the_srgb_curve() {
        let d = Display {
            tonemap: Tonemap::Clip,
            exposure: 0.0,
        };
        let v = display_value(Vec3::new(0.0, 0.18, 2.0), d);
        // sRGB of 0.18 = 0.4613561 (IEC 61966-2-1); 2 clips to 1.
        assert!((v.y - 0.461_356_1).abs() < 1e-5, "{v}");
        // 1.055·1^(1/2.4) − 0.055 rounds to 1 − 2⁻²⁴ or 1 by the platform's `powf`.
        assert!(v.x == 0.0 && (v.z - 1.0).abs() < 1e-6, "{v}");
        let d1 = Display { exposure: 1.0, ..d };
        let v1 = display_value(Vec3::splat(0.09), d1);
        assert!((v1.x - v.y).abs() < 1e-5, "exposure +1 doubles: {v1}");
        assert_eq!(
            display_value(Vec3::new(f32::NAN, f32::INFINITY, -1.0), d),
            Vec3::ZERO
        );
    }

    #[test]
    fn agx_is_monotone_and_bounded() {
        let d = Display {
            tonemap: Tonemap::Agx,
            exposure: 0.0,
        };
        let mut last = -1.0;
        for i in 0..200 {
            let v = display_value(Vec3::splat(1e-3 * 1.07f32.powi(i)), d);
            assert!(v.x >= last - 1e-6 && (0.0..=1.0).contains(&v.x), "{i}: {v}");
            last = v.x;
        }
        // Very bright white saturates towards 1; black stays near 0.
        assert!(display_value(Vec3::splat(1e4), d).x > 0.95);
        assert!(display_value(Vec3::ZERO, d).x < 0.02);
    }
}
