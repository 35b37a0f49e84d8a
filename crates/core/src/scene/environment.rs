//! Environment light: radiance arriving from infinitely far away in every direction, either
//! a constant colour or an equirectangular (latitude-longitude) HDR image, with an intensity
//! scale and a rotation about the up axis (+y).
//!
//! Image directions follow Mitsuba's `envmap`: for a unit direction `d` (pointing away from
//! the scene, towards the sky) in the environment's own frame, `u = atan2(d.x, −d.z) / 2π`
//! (wrapped to [0, 1)) and `v = acos(d.y) / π`, so the image's top row is straight up and
//! its centre column looks along +z. Texels are piecewise constant (no filtering), so the
//! radiance and the sampling density agree exactly.
//!
//! Sampling picks a texel with probability ∝ luminance · sin θ (θ at the texel's centre row)
//! from a marginal distribution over rows and a conditional one over each row's columns,
//! then a point uniformly inside the texel; the density over solid angle is
//! `p(u, v) / (2π² sin θ)` with θ of the sampled direction (PBRT, §12.6).

use crate::sampling::uniform_sphere;
use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};
use std::f32::consts::PI;

/// Largest image side (texels).
pub const MAX_SIDE: u32 = 16384;
/// Largest radiance per channel after the intensity scale (W/(sr·m²)), as `MAX_INTENSITY`
/// for point lights: estimates stay far from f32 overflow.
pub const MAX_RADIANCE: f32 = 1.0e10;

/// The scene description's `environment` section (see `docs/scene-format.md`).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentDesc {
    /// An equirectangular HDR image (EXR, HDR, ...), relative to the scene file; loaded by
    /// the Python layer and handed to the core as an [`EnvImage`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// Constant radiance (W/(sr·m²) per channel) from every direction, instead of a file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radiance: Option<[f32; 3]>,
    /// Scale applied to the image or the constant.
    #[serde(default = "one")]
    pub intensity: f32,
    /// Rotation of the environment about the up axis (+y), degrees, counter-clockwise seen
    /// from above (right-handed).
    #[serde(default)]
    pub rotation: f32,
    /// Sample the environment by importance (and combine with BSDF sampling by multiple
    /// importance sampling). `false` leaves it to rays that escape the scene after BSDF
    /// sampling: the unbiased brute-force estimator the tests compare against.
    #[serde(default = "yes")]
    pub importance: bool,
}

fn one() -> f32 {
    1.0
}
fn yes() -> bool {
    true
}

/// An equirectangular image, rows top (up) to bottom, RGB radiance per texel.
#[derive(Clone, Debug, Default)]
pub struct EnvImage {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec3>,
}

/// A sampled direction towards the environment.
#[derive(Clone, Copy, Debug)]
pub struct EnvSample {
    /// Unit world direction from the scene towards the environment.
    pub wi: Vec3,
    /// Radiance arriving from `wi`.
    pub radiance: Vec3,
    /// Density of `wi` over solid angle.
    pub pdf: f32,
}

/// Piecewise-constant 1D distribution over `n` equal cells of [0, 1).
#[derive(Clone, Debug)]
struct Distribution1D {
    /// Cumulative sums normalized to 1, `n + 1` entries starting at 0. f64: with a sun
    /// 10⁷ times brighter than the sky, f32 steps near 1 (6·10⁻⁸) would swallow the sky's
    /// cells, which the sampler could then never pick although `density` says it does.
    cdf: Vec<f64>,
    /// Cell weights (not normalized) and their sum.
    func: Vec<f32>,
    sum: f64,
}

impl Distribution1D {
    fn new(func: Vec<f32>) -> Self {
        let sum: f64 = func.iter().map(|&f| f as f64).sum();
        let mut cdf = Vec::with_capacity(func.len() + 1);
        let mut acc = 0.0f64;
        cdf.push(0.0);
        for &f in &func {
            acc += f as f64;
            // A row with no weight at all is sampled uniformly (it is never chosen by the
            // marginal, but keeps the arithmetic finite).
            cdf.push(if sum > 0.0 {
                acc / sum
            } else {
                cdf.len() as f64 / func.len() as f64
            });
        }
        *cdf.last_mut().unwrap() = 1.0;
        Distribution1D { cdf, func, sum }
    }

    /// A cell index and the position of `u` inside it, in [0, 1).
    fn sample(&self, u: f32) -> (usize, f32) {
        let n = self.func.len();
        let u = u as f64;
        // The last cell whose cdf start is <= u, skipping empty cells.
        let i = (self.cdf.partition_point(|&c| c <= u) - 1).min(n - 1);
        let (lo, hi) = (self.cdf[i], self.cdf[i + 1]);
        let du = if hi > lo { (u - lo) / (hi - lo) } else { 0.5 };
        (i, (du as f32).clamp(0.0, 1.0 - f32::EPSILON))
    }

    /// Probability of cell `i` times `n` (the density over [0, 1)).
    fn density(&self, i: usize) -> f32 {
        if self.sum > 0.0 {
            (self.func[i] as f64 * self.func.len() as f64 / self.sum) as f32
        } else {
            1.0
        }
    }
}

/// Marginal over rows, conditional over each row's columns.
#[derive(Clone, Debug)]
struct Distribution2D {
    rows: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    fn new(weights: &[f32], width: usize, height: usize) -> Self {
        let rows: Vec<Distribution1D> = weights
            .chunks_exact(width)
            .map(|r| Distribution1D::new(r.to_vec()))
            .collect();
        let marginal = Distribution1D::new(rows.iter().map(|r| r.sum as f32).collect());
        debug_assert_eq!(rows.len(), height);
        Distribution2D { rows, marginal }
    }
}

#[derive(Clone, Debug)]
enum Source {
    Constant(Vec3),
    Image {
        image: EnvImage,
        /// `None` when the whole image is black.
        dist: Option<Distribution2D>,
    },
}

/// An environment light, ready to evaluate and sample.
#[derive(Clone, Debug)]
pub struct Environment {
    source: Source,
    scale: f32,
    /// cos and sin of the rotation about +y.
    rot: (f32, f32),
    /// See [`EnvironmentDesc::importance`].
    pub importance: bool,
}

fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

impl Environment {
    /// A constant environment of radiance `radiance`.
    pub fn constant(radiance: Vec3) -> Self {
        Environment {
            source: Source::Constant(radiance),
            scale: 1.0,
            rot: (1.0, 0.0),
            importance: true,
        }
    }

    /// An image environment; `image` must be valid (see [`Environment::from_desc`]).
    pub fn image(image: EnvImage, scale: f32, rotation_degrees: f32) -> Self {
        let (w, h) = (image.width as usize, image.height as usize);
        let weights: Vec<f32> = image
            .texels
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let theta = PI * ((i / w) as f32 + 0.5) / h as f32;
                luminance(*t).max(0.0) * theta.sin()
            })
            .collect();
        let dist = weights
            .iter()
            .any(|&x| x > 0.0)
            .then(|| Distribution2D::new(&weights, w, h));
        let r = rotation_degrees.to_radians();
        Environment {
            source: Source::Image { image, dist },
            scale,
            rot: (r.cos(), r.sin()),
            importance: true,
        }
    }

    /// Validates a description; `images` holds the loaded file of `file`, by name.
    pub fn from_desc(
        d: &EnvironmentDesc,
        images: &std::collections::HashMap<String, EnvImage>,
    ) -> Result<Self, (String, String)> {
        let err = |f: &str, m: &str| Err((f.to_string(), m.to_string()));
        if !(d.intensity.is_finite() && d.intensity >= 0.0) {
            return err("intensity", "must be finite and non-negative");
        }
        if !d.rotation.is_finite() {
            return err("rotation", "must be finite (degrees)");
        }
        let mut env = match (&d.file, d.radiance) {
            (Some(_), Some(_)) => return err("radiance", "give either `file` or `radiance`"),
            (None, None) => return err("(section)", "needs `file` or `radiance`"),
            (None, Some(c)) => {
                if c.iter().any(|x| !x.is_finite() || *x < 0.0) {
                    return err("radiance", "must be finite and non-negative");
                }
                let mut e = Environment::constant(Vec3::from(c));
                e.scale = d.intensity;
                e.rot = {
                    let r = d.rotation.to_radians();
                    (r.cos(), r.sin())
                };
                e
            }
            (Some(file), None) => {
                let Some(img) = images.get(file) else {
                    return err(
                        "file",
                        &format!("environment image `{file}` was not loaded"),
                    );
                };
                validate_image(img).map_err(|m| ("file".to_string(), m))?;
                Environment::image(img.clone(), d.intensity, d.rotation)
            }
        };
        if env.max_radiance() > MAX_RADIANCE {
            return err(
                "intensity",
                "radiance times intensity must be at most 1e10 per channel",
            );
        }
        env.importance = d.importance;
        Ok(env)
    }

    fn max_radiance(&self) -> f32 {
        let m = match &self.source {
            Source::Constant(c) => c.max_element(),
            Source::Image { image, .. } => image
                .texels
                .iter()
                .fold(0.0f32, |a, t| a.max(t.max_element())),
        };
        m * self.scale
    }

    /// World direction → the environment's frame (undoing the rotation about +y).
    fn to_local(&self, d: Vec3) -> Vec3 {
        let (c, s) = self.rot;
        Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
    }

    fn to_world(&self, d: Vec3) -> Vec3 {
        let (c, s) = self.rot;
        Vec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
    }

    /// (u, v) in [0, 1)² of a local unit direction, and sin θ.
    fn uv(d: Vec3) -> (Vec2, f32) {
        // sin θ and θ from the horizontal components: accurate near the poles, where
        // 1 − y² loses its digits.
        let sin_t = (d.x * d.x + d.z * d.z).sqrt();
        let u = (d.x.atan2(-d.z) / (2.0 * PI)).rem_euclid(1.0);
        let v = sin_t.atan2(d.y) / PI;
        (Vec2::new(u, v), sin_t)
    }

    fn texel_index(image: &EnvImage, uv: Vec2) -> (usize, usize) {
        let (w, h) = (image.width as usize, image.height as usize);
        let x = ((uv.x * w as f32) as usize).min(w - 1);
        let y = ((uv.y * h as f32) as usize).min(h - 1);
        (x, y)
    }

    /// The radiance table for the GPU: (width, height, texels times the intensity scale), a
    /// 1×1 table for a constant colour, and (cos, sin) of the rotation about +y. A lookup
    /// of the texel [`Environment::radiance`] picks reproduces it.
    pub fn gpu_table(&self) -> (u32, u32, Vec<Vec3>, (f32, f32)) {
        match &self.source {
            Source::Constant(c) => (1, 1, vec![*c * self.scale], self.rot),
            Source::Image { image, .. } => (
                image.width,
                image.height,
                image.texels.iter().map(|t| *t * self.scale).collect(),
                self.rot,
            ),
        }
    }

    /// The light of `self` and `other` together, as one environment: the constant sum of
    /// two constants; else an image on the grid of `self`'s image (of `other`'s when `self`
    /// is constant) in its frame, each texel its own radiance plus the other's along the
    /// texel's centre direction (the other's nearest texel: exact for a constant, resampled
    /// for a second image).
    pub fn sum(&self, other: &Environment) -> Environment {
        let (base, add) = match (&self.source, &other.source) {
            (Source::Constant(_), Source::Image { .. }) => (other, self),
            _ => (self, other),
        };
        let importance = self.importance && other.importance;
        let Source::Image { image, .. } = &base.source else {
            let mut e = Environment::constant(self.radiance(Vec3::Y) + other.radiance(Vec3::Y));
            e.importance = importance;
            return e;
        };
        let (w, h) = (image.width as usize, image.height as usize);
        let texels = (0..w * h)
            .map(|i| {
                let u = ((i % w) as f32 + 0.5) / w as f32;
                let theta = PI * ((i / w) as f32 + 0.5) / h as f32;
                let phi = 2.0 * PI * u;
                let local = Vec3::new(
                    theta.sin() * phi.sin(),
                    theta.cos(),
                    -theta.sin() * phi.cos(),
                );
                image.texels[i] * base.scale + add.radiance(base.to_world(local))
            })
            .collect();
        let summed = EnvImage {
            width: image.width,
            height: image.height,
            texels,
        };
        let (c, s) = base.rot;
        let mut e = Environment::image(summed, 1.0, s.atan2(c).to_degrees());
        e.importance = importance;
        e
    }

    /// (cos, sin) of the rotation about +y.
    pub fn rotation(&self) -> (f32, f32) {
        self.rot
    }

    /// Radiance arriving from the unit world direction `d` (pointing away from the scene).
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        match &self.source {
            Source::Constant(c) => *c * self.scale,
            Source::Image { image, .. } => {
                let (uv, _) = Self::uv(self.to_local(d));
                let (x, y) = Self::texel_index(image, uv);
                image.texels[y * image.width as usize + x] * self.scale
            }
        }
    }

    /// Samples a direction by importance (uniform over the sphere for a constant colour);
    /// `None` for an all-black image.
    pub fn sample(&self, u: Vec2) -> Option<EnvSample> {
        match &self.source {
            Source::Constant(c) => Some(EnvSample {
                wi: uniform_sphere(u),
                radiance: *c * self.scale,
                pdf: 1.0 / (4.0 * PI),
            }),
            Source::Image { image, dist } => {
                let dist = dist.as_ref()?;
                let (y, dv) = dist.marginal.sample(u.y);
                let (x, du) = dist.rows[y].sample(u.x);
                let (w, h) = (image.width as f32, image.height as f32);
                let theta = PI * (y as f32 + dv) / h;
                let phi = 2.0 * PI * (x as f32 + du) / w;
                let sin_t = theta.sin();
                if sin_t <= 0.0 {
                    return None;
                }
                let local = Vec3::new(sin_t * phi.sin(), theta.cos(), -sin_t * phi.cos());
                let p_uv = dist.marginal.density(y) * dist.rows[y].density(x);
                Some(EnvSample {
                    wi: self.to_world(local).normalize(),
                    radiance: image.texels[y * image.width as usize + x] * self.scale,
                    pdf: p_uv / (2.0 * PI * PI * sin_t),
                })
            }
        }
    }

    /// Radiance integrated over the sphere of directions, ∫ L(ω) dω (W·m⁻² per channel
    /// crossing a unit disc from all sides: the irradiance a sphere's cross-section gets).
    pub fn integral(&self) -> Vec3 {
        match &self.source {
            Source::Constant(c) => *c * (self.scale * 4.0 * PI),
            Source::Image { image, .. } => {
                let (w, h) = (image.width as usize, image.height as usize);
                let mut sum = glam::DVec3::ZERO;
                for (i, t) in image.texels.iter().enumerate() {
                    let theta = std::f64::consts::PI * ((i / w) as f64 + 0.5) / h as f64;
                    let d_omega = 2.0 * std::f64::consts::PI * std::f64::consts::PI * theta.sin()
                        / (w * h) as f64;
                    sum += t.as_dvec3() * d_omega;
                }
                sum.as_vec3() * self.scale
            }
        }
    }

    /// Power entering the scene's bounding sphere `bounds` (W per channel): every direction's
    /// light through the disc facing it, πr²·∫L dω.
    pub fn power(&self, bounds: super::light::Bounds) -> Vec3 {
        self.integral() * (PI * bounds.radius * bounds.radius)
    }

    /// Emits one photon into the scene: a direction drawn by [`Environment::sample`], a
    /// point on the disc of `bounds` facing it; the power is the environment's over one
    /// photon (divide by the photon count).
    pub fn emit(
        &self,
        rng: &mut crate::sampling::Rng,
        bounds: super::light::Bounds,
    ) -> Option<super::light::Emission> {
        let s = self.sample(rng.next_2d())?;
        if s.pdf.is_nan() || s.pdf <= 0.0 {
            return None;
        }
        let (origin, area) = bounds.disc_point(s.wi, rng.next_2d());
        Some(super::light::Emission {
            origin,
            direction: -s.wi,
            power: s.radiance * (area / s.pdf),
        })
    }

    /// Density over solid angle with which [`Environment::sample`] returns the unit world
    /// direction `d`.
    pub fn pdf(&self, d: Vec3) -> f32 {
        match &self.source {
            Source::Constant(_) => 1.0 / (4.0 * PI),
            Source::Image { image, dist } => {
                let Some(dist) = dist else { return 0.0 };
                let (uv, sin_t) = Self::uv(self.to_local(d));
                if sin_t <= 0.0 {
                    return 0.0;
                }
                let (x, y) = Self::texel_index(image, uv);
                dist.marginal.density(y) * dist.rows[y].density(x) / (2.0 * PI * PI * sin_t)
            }
        }
    }
}

/// The 2D point `i` of `n` of a Fibonacci lattice in [0, 1)² moved by `offset` (mod 1):
/// stratified in both coordinates for any `n`.
fn lattice(i: u32, n: u32, offset: Vec2) -> Vec2 {
    let golden = 0.618_034f32;
    Vec2::new(
        ((i as f32 + 0.5) / n as f32 + offset.x).fract(),
        (i as f32 * golden + offset.y).fract(),
    )
}

/// A direction of the sky drawn for a rasterized direct light: a distant light of
/// `irradiance` L(ω)/(n·p(ω)) arriving from `towards` (unit, pointing to the sky).
#[derive(Clone, Copy, Debug)]
pub struct SkyDirection {
    pub towards: Vec3,
    pub irradiance: Vec3,
    /// The solid angle it stands for, 1/(n·p(ω)) (sr).
    pub solid_angle: f32,
}

impl Environment {
    /// `n` directions, each at a point of a Fibonacci lattice moved by a random offset from
    /// `seed` (stratified): uniformly over the sphere for a constant colour or without
    /// `importance`; for an image drawn by importance, half of them uniformly and half by
    /// [`Environment::sample`], each weighted by the mixture of both densities (so that every
    /// hemisphere gets directions, and bright regions more). Σ f·|cos θ|·E over them is an
    /// unbiased estimate of the environment's direct light.
    pub fn directions(&self, n: u32, seed: u64) -> Vec<SkyDirection> {
        let mut rng = crate::sampling::Rng::new(seed, 0x5C1E_D12E, 0);
        let offset = rng.next_2d();
        let image = matches!(self.source, Source::Image { dist: Some(_), .. });
        let n_env = if self.importance && image { n / 2 } else { 0 };
        let n_uniform = n - n_env;
        let uniform_pdf = 1.0 / (4.0 * PI);
        let mixture =
            |d: Vec3| (n_uniform as f32 * uniform_pdf + n_env as f32 * self.pdf(d)) / n as f32;
        let uniform = (0..n_uniform).map(|i| uniform_sphere(lattice(i, n_uniform, offset)));
        let drawn = (0..n_env).filter_map(|i| self.sample(lattice(i, n_env, offset)).map(|s| s.wi));
        uniform
            .chain(drawn)
            .filter_map(|towards| {
                let pdf = mixture(towards);
                (pdf > 0.0 && pdf.is_finite()).then(|| SkyDirection {
                    towards,
                    irradiance: self.radiance(towards) / (n as f32 * pdf),
                    solid_angle: 1.0 / (n as f32 * pdf),
                })
            })
            .collect()
    }

    /// The irradiance E(n) = ∫ L(ω)·max(0, n·ω) dω on a surface facing `n`, tabulated over
    /// the environment's own frame as a `w`×`h` table: column x at longitude 2π(x + ½)/w (the
    /// radiance table's), row y at colatitude π·y/(h − 1), so that the first and last rows
    /// are the poles themselves (a normal at a pole needs no longitude: interpolating
    /// between rows a half-row off the pole would mix in its neighbours' tilt, 6% too
    /// bright on a floor under a sun 45° up in a 16-row table). Rotate `n` into that frame
    /// to look it up. Exact for a constant colour (πL); for an image, the convolution of its
    /// texels averaged down to at most 64×32 cells.
    pub fn irradiance_table(&self, w: u32, h: u32) -> Vec<Vec3> {
        let (w, h) = (w.max(1) as usize, h.max(2) as usize);
        let coarse: Vec<(Vec3, Vec3)> = match &self.source {
            Source::Constant(c) => return vec![*c * (self.scale * PI); w * h],
            Source::Image { image, .. } => coarse_radiance(image, self.scale),
        };
        let mut out = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let n = pole_table_direction(x, y, w, h);
                let e: glam::DVec3 = coarse
                    .iter()
                    .map(|(d, l)| (l.as_dvec3()) * n.dot(*d).max(0.0) as f64)
                    .sum();
                out.push(e.as_vec3());
            }
        }
        out
    }
}

/// The unit direction (environment frame) of column `x` and row `y` of the `w`×`h`
/// irradiance table: rows from pole to pole (see [`Environment::irradiance_table`]).
fn pole_table_direction(x: usize, y: usize, w: usize, h: usize) -> Vec3 {
    let theta = PI * y as f32 / (h - 1) as f32;
    let phi = 2.0 * PI * (x as f32 + 0.5) / w as f32;
    let s = theta.sin();
    Vec3::new(s * phi.sin(), theta.cos(), -s * phi.cos())
}

/// The unit direction (environment frame) of texel centre (`x`, `y`) of a `w`×`h`
/// equirectangular table.
fn table_direction(x: usize, y: usize, w: usize, h: usize) -> Vec3 {
    let theta = PI * (y as f32 + 0.5) / h as f32;
    let phi = 2.0 * PI * (x as f32 + 0.5) / w as f32;
    let s = theta.sin();
    Vec3::new(s * phi.sin(), theta.cos(), -s * phi.cos())
}

/// An image environment averaged down to at most 64×32 cells: per cell its central
/// direction and its radiance integrated over its solid angle (times `scale`).
fn coarse_radiance(image: &EnvImage, scale: f32) -> Vec<(Vec3, Vec3)> {
    let (w, h) = (image.width as usize, image.height as usize);
    let (cw, ch) = (w.min(64), h.min(32));
    let mut sums = vec![glam::DVec3::ZERO; cw * ch];
    for y in 0..h {
        let theta = std::f64::consts::PI * (y as f64 + 0.5) / h as f64;
        let d_omega =
            2.0 * std::f64::consts::PI * std::f64::consts::PI * theta.sin() / (w * h) as f64;
        let cy = y * ch / h;
        for x in 0..w {
            let cx = x * cw / w;
            sums[cy * cw + cx] += image.texels[y * w + x].as_dvec3() * d_omega;
        }
    }
    sums.iter()
        .enumerate()
        .map(|(i, s)| {
            let d = table_direction(i % cw, i / cw, cw, ch);
            (d, s.as_vec3() * scale)
        })
        .collect()
}

/// Checks an image handed in by the loader: size and finite, non-negative texels.
pub fn validate_image(img: &EnvImage) -> Result<(), String> {
    if img.width == 0 || img.height == 0 || img.width > MAX_SIDE || img.height > MAX_SIDE {
        return Err(format!(
            "image must be 1..={MAX_SIDE} texels per side, got {}x{}",
            img.width, img.height
        ));
    }
    if img.texels.len() != img.width as usize * img.height as usize {
        return Err("texel count does not match width x height".into());
    }
    if let Some(i) = img
        .texels
        .iter()
        .position(|t| !t.is_finite() || t.min_element() < 0.0)
    {
        let w = img.width as usize;
        return Err(format!(
            "texel (row {}, column {}) is not finite and non-negative: {:?}",
            i / w,
            i % w,
            img.texels[i].to_array()
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
