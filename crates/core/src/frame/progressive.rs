//! Progressive mode: probabilistic progressive photon mapping (Knaus & Zwicker 2011).
//!
//! Each frame of a progressive [`Renderer`](super::Renderer) is a pass: an independent
//! estimate of the whole image with fresh random numbers (photons, bounce-map jitter,
//! sub-pixel positions, light samples), whose photon kernels are all scaled by a global
//! radius factor rᵢ that shrinks as r²ᵢ₊₁ = r²ᵢ (i + α)/(i + 1). The image is the running
//! mean of the passes. Knaus and Zwicker show that the mean of such passes is consistent
//! (variance and bias both vanish) without per-pixel statistics, which is why this fits
//! ISPM's per-photon splat kernels: a pass needs no knowledge of the previous ones, so the
//! GPU estimators stay as they are and only the per-photon radius on the CPU changes.
//!
//! ISPM's rasterized direct light is the exception: its shadow maps (resolution, PCF
//! filtering, the normal offset against acne) are a bias that no pass removes, and
//! progressive `ispm` flattened at it. In progressive mode the direct light of the first
//! surface is therefore ray traced on the CPU ([`direct_image`]: next-event estimation with
//! the scene BVH at new jittered sub-pixel positions per pass), as `path` does, and
//! replaces the rasterized one in the pass.

use crate::cancel::StageProgress;
use crate::error::Result;
use crate::image::Image;
use crate::photon::{boundary, Photon};
use crate::raster::ispm::Z_RATIO;
use crate::raster::oct_decode;
use crate::render::{progressive_radius_scale, Progress, Settings};
use crate::sampling::Rng;
use crate::scene::Scene;
use crate::trace::path::direct_light;
use crate::trace::{Interaction, SceneBvh};
use glam::{DVec3, Vec2, Vec3, Vec4};
use rayon::prelude::*;

/// The running sum of the passes since the last change of scene, camera or size.
pub(super) struct Accumulation {
    pub passes: u64,
    sum: Vec<DVec3>,
    width: u32,
    height: u32,
}

impl Accumulation {
    pub fn new(like: &Image) -> Self {
        Accumulation {
            passes: 0,
            sum: vec![DVec3::ZERO; like.pixels.len()],
            width: like.width,
            height: like.height,
        }
    }

    /// Adds a pass and returns the mean so far.
    pub fn add(&mut self, pass: &Image) -> Image {
        if (pass.width, pass.height) != (self.width, self.height) {
            *self = Accumulation::new(pass);
        }
        for (s, p) in self.sum.iter_mut().zip(&pass.pixels) {
            // A non-finite sample would poison the mean for good: it counts as zero (the
            // methods don't produce them; this only guards the accumulation).
            if p.is_finite() {
                *s += p.as_dvec3();
            }
        }
        self.passes += 1;
        let n = self.passes as f64;
        let mut mean = Image::new(self.width, self.height);
        for (m, s) in mean.pixels.iter_mut().zip(&self.sum) {
            *m = (*s / n).as_vec3();
        }
        mean
    }
}

/// SplitMix64 finalizer.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The settings of progressive pass `pass` (0-based): the base seed (`seed`, else the
/// settings') for the first pass, then a new one per pass, and the kernel radius scale of
/// the pass times the settings' own.
pub(super) fn pass_settings(settings: &Settings, seed: Option<u64>, pass: u64) -> Settings {
    let base = seed.unwrap_or(settings.seed);
    Settings {
        seed: if pass == 0 {
            base
        } else {
            base ^ mix(pass.wrapping_add(0x5851_F42D_4C95_7F2D))
        },
        radius_scale: settings.radius_scale
            * progressive_radius_scale(pass, settings.progressive_alpha),
        ..settings.clone()
    }
}

/// The sub-pixel offset of the GPU methods' sample positions in pass `pass` (a
/// Cranley–Patterson rotation, new per pass; zero outside progressive mode and in the first
/// pass, so that pass is the ordinary frame).
pub(super) fn sample_offset(settings: &Settings, pass: u64) -> Vec2 {
    if !settings.progressive || pass == 0 {
        return Vec2::ZERO;
    }
    let h = mix(settings.seed ^ mix(pass));
    Vec2::new(
        (h >> 40) as f32 / (1u64 << 24) as f32,
        ((h >> 16) & 0xFF_FFFF) as f32 / (1u64 << 24) as f32,
    )
}

/// Query-side boundary normalisation of progressive `ispm`'s indirect light: per pixel,
/// the fraction of a kernel disc of radius `r` around the pixel's G-buffer sample (in its
/// tangent plane, weighted like the kernel) that lies on surfaces the splat shades
/// ([`boundary::coverage`], the probes of the photon-side compensation placed around the
/// pixel instead of the photon), at least [`boundary::MIN_COVERAGE`]; 1 for pixels
/// without a surface. `position` and `normals` are the read-back G-buffer textures.
///
/// Why: the photon-side compensation divides each photon's power by its own coverage, which
/// conserves energy but not the density at the edge: a pixel on a crease gathers only
/// photons from its side, each brightened by less than the 2× its missing half needs, and
/// the pixels beside it get the surplus. Measured on cornell 64x64 (128 passes): the
/// indirect light 8% too dark on the crease pixels, 18% of the image holding 69% of the
/// squared error; at 64 passes kernels 4× smaller only took it from 9.5% to 6.1% (the
/// error band narrows with the radius, the error in it does not). Dividing the uncompensated splat at the pixel by the
/// kernel's coverage there is exact for a density that is constant across the disc.
pub(super) fn query_coverage(
    scene: &Scene,
    bvh: &SceneBvh,
    position: &[Vec4],
    normals: &[Vec4],
    r: f32,
    seed: u64,
) -> Vec<f32> {
    let eye = scene.camera.position;
    position
        .par_iter()
        .zip(normals)
        .enumerate()
        .map(|(i, (p, n))| {
            if p.w <= 0.0 || r.is_nan() || r <= 0.0 {
                return 1.0;
            }
            let at = p.truncate();
            let ng = oct_decode(Vec2::new(n.z, n.w));
            let ng = if ng.dot(eye - at) < 0.0 { -ng } else { ng };
            let probe = Photon {
                position: at.into(),
                normal: ng.into(),
                ..Photon::default()
            };
            let mut rng = Rng::new(seed, 0xC0BE, i as u64);
            boundary::coverage(scene, bvh, &probe, r, Z_RATIO, &mut rng).max(boundary::MIN_COVERAGE)
        })
        .collect()
}

/// The kernel's moments over its covered part around each pixel's G-buffer sample
/// ([`boundary::coverage_moments`], placed like [`query_coverage`]'s probes): `FULL` for
/// pixels without a surface and for pixels whose kernel lies on one surface.
pub(super) fn query_moments(
    scene: &Scene,
    bvh: &SceneBvh,
    position: &[Vec4],
    normals: &[Vec4],
    r: f32,
    seed: u64,
) -> Vec<boundary::CoveredMoments> {
    let eye = scene.camera.position;
    position
        .par_iter()
        .zip(normals)
        .enumerate()
        .map(|(i, (p, n))| {
            if p.w <= 0.0 || r.is_nan() || r <= 0.0 {
                return boundary::CoveredMoments::FULL;
            }
            let probe = Photon {
                position: p.truncate().into(),
                normal: facing_normal(*p, *n, eye).into(),
                ..Photon::default()
            };
            let mut rng = Rng::new(seed, 0xC0BE, i as u64);
            boundary::coverage_moments(scene, bvh, &probe, r, Z_RATIO, &mut rng)
        })
        .collect()
}

/// The geometric normal of a G-buffer sample, turned towards the eye.
fn facing_normal(p: Vec4, n: Vec4, eye: Vec3) -> Vec3 {
    let ng = oct_decode(Vec2::new(n.z, n.w));
    if ng.dot(eye - p.truncate()) < 0.0 {
        -ng
    } else {
        ng
    }
}

/// Smallest m0 − m1ᵀM₂⁻¹m1 over m0 for which [`crease_estimate`] extrapolates (a half disc
/// has 0.31); below it, and for a near-singular M₂, the pixel keeps the zeroth-order estimate.
const MIN_LINEAR_DENOMINATOR: f32 = 0.05;

/// How [`crease_estimate`] estimates the indirect light near creases and edges.
#[derive(Clone, Copy, Debug)]
pub(super) struct CreaseFit {
    /// Kernel radii at those pixels over the splat's.
    pub bandwidth: f32,
    /// Local-linear intercept (else the zeroth-order S0/m0).
    pub linear: bool,
}

/// Progressive `ispm`'s indirect light at the pixels within a kernel radius of a crease or
/// an edge (`near`): per channel, the factor that turns the GPU's splat at the pixel into
/// an estimate with kernels `fit.bandwidth` times narrower, normalised by their covered part
/// (`moments`, [`query_moments`] at the narrower radius) and, with `fit.linear`, the
/// intercept of a kernel-weighted local-linear fit, E = (S0 − m1ᵀM₂⁻¹S1)/(m0 − m1ᵀM₂⁻¹m1).
/// S0 = Σ κΦ and S1 = Σ κΦu are summed here on the CPU over the photons whose (narrowed)
/// volume holds the pixel's sample (the splat's tests; u the photon's offset in the pixel's
/// tangent plane over its radius); the factor is that estimate over the same sum at the
/// splat's radii. With a BSDF that is constant over the photons (Lambertian surfaces) the
/// splat is the BSDF times that sum, so the factor carries over exactly; glossy surfaces get
/// the factor of the unweighted sums. Other pixels get 1.
pub(super) fn crease_estimate(
    scene: &Scene,
    position: &[Vec4],
    normals: &[Vec4],
    near: &[bool],
    moments: &[boundary::CoveredMoments],
    photons: &[Photon],
    r_max: f32,
    fit: CreaseFit,
) -> Vec<Vec3> {
    let eye = scene.camera.position;
    let radius = |p: &Photon| p.footprint_radius.min(r_max);
    let cell = photons.iter().map(radius).fold(0.0f32, f32::max);
    if photons.is_empty() || !(cell > 0.0 && cell.is_finite()) {
        return vec![Vec3::ONE; position.len()];
    }
    let key = |x: Vec3| (x / cell).floor().as_ivec3();
    let mut grid: std::collections::HashMap<glam::IVec3, Vec<u32>> = Default::default();
    for (i, p) in photons.iter().enumerate() {
        grid.entry(key(p.position())).or_default().push(i as u32);
    }
    let kernel = |d2: f32, h: f32, r: f32| {
        let rz = r * Z_RATIO;
        if d2 / (r * r) + h * h / (rz * rz) >= 1.0 {
            0.0
        } else {
            2.0 / (std::f32::consts::PI * r * r) * (1.0 - d2 / (r * r))
        }
    };
    position
        .par_iter()
        .zip(normals)
        .zip(moments)
        .zip(near)
        .map(|(((p, n), m), &near)| {
            if p.w <= 0.0 || !near || m.m0 <= 0.0 {
                return Vec3::ONE;
            }
            let x = p.truncate();
            let ns = oct_decode(Vec2::new(n.x, n.y));
            let frame = crate::sampling::Frame::new(facing_normal(*p, *n, eye));
            let (mut full, mut s0, mut s1x, mut s1y) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
            let c = key(x);
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let Some(list) = grid.get(&(c + glam::IVec3::new(dx, dy, dz))) else {
                            continue;
                        };
                        for &k in list {
                            let ph = &photons[k as usize];
                            let pn = ph.normal();
                            if ns.dot(pn) <= crate::photon::estimate::NORMAL_AGREEMENT {
                                continue;
                            }
                            let r = radius(ph);
                            let d = ph.position() - x;
                            let h = d.dot(pn);
                            let d2 = (d.length_squared() - h * h).max(0.0);
                            full += ph.power() * kernel(d2, h, r);
                            let rb = r * fit.bandwidth;
                            let w = ph.power() * kernel(d2, h, rb);
                            let u = Vec2::new(d.dot(frame.t), d.dot(frame.b)) / rb;
                            s0 += w;
                            s1x += w * u.x;
                            s1y += w * u.y;
                        }
                    }
                }
            }
            let zeroth = s0 / m.m0.max(boundary::MIN_COVERAGE);
            let mut estimate = zeroth;
            let [a, b, cc] = m.m2;
            let det = a * cc - b * b;
            if fit.linear && m.m0 < 1.0 && det > 0.05 * m.m0 * m.m0 / 36.0 {
                // v = M₂⁻¹ m1.
                let v = Vec2::new(cc * m.m1.x - b * m.m1.y, a * m.m1.y - b * m.m1.x) / det;
                let den = m.m0 - v.dot(m.m1);
                if den > MIN_LINEAR_DENOMINATOR * m.m0 {
                    estimate = (s0 - v.x * s1x - v.y * s1y) / den;
                }
            }
            let ratio = |e: f32, f: f32| if f > 0.0 { e / f } else { 1.0 };
            Vec3::new(
                ratio(estimate.x, full.x),
                ratio(estimate.y, full.y),
                ratio(estimate.z, full.z),
            )
        })
        .collect()
}

/// Stream of the direct light's sub-pixel samples (apart from the specular paths').
const DIRECT_STREAM: u64 = 0xD1EC_7000_0000_0000;

/// The direct light of the first surface seen through each pixel (the part ISPM
/// rasterizes with shadow maps: next-event estimation of every point and spot light on the
/// surface's non-delta lobes, nothing on misses), ray traced on the CPU as `path` does at
/// its first vertex: the mean of k×k camera rays per pixel (k = ⌈√spp⌉, at least 2), one
/// at a uniformly random point of each stratum drawn from `settings.seed`, so that the
/// mean over passes of new seeds converges to the pixel's exact direct light.
pub(super) fn direct_image(
    scene: &Scene,
    bvh: &SceneBvh,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<Image> {
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    // k×k strata per pixel, one random point in each: at least 2×2 (a few ms per pass at
    // 128x128), since one random point per pass had 3× the variance of the shadow-mapped
    // direct light at mirror-shadow's shadow edges (relMSE 6.5e-4 vs 2.1e-4 after 16 passes).
    let k = (settings.spp.max(1) as f32).sqrt().ceil().max(2.0) as u32;
    let spp = k * k;
    let mut image = Image::new(w, h);
    let stage = StageProgress::new(progress, "direct light", h as u64);
    image
        .pixels
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(y, row)| {
            if stage.stopped() {
                return;
            }
            for (x, px) in row.iter_mut().enumerate() {
                let pixel = y as u64 * w as u64 + x as u64;
                let mut sum = Vec3::ZERO;
                for s in 0..spp {
                    let mut rng = Rng::new(settings.seed, pixel, DIRECT_STREAM + s as u64);
                    let j = rng.next_2d();
                    let (sx, sy) = ((s % k) as f32, (s / k) as f32);
                    let dir = cam.direction(
                        x as f32 + (sx + j.x) / k as f32,
                        y as f32 + (sy + j.y) / k as f32,
                    );
                    if let Some(hit) = bvh.intersect(cam.position, dir, f32::INFINITY) {
                        let it = Interaction::new(scene, &hit, dir);
                        sum += direct_light(scene, bvh, &it, -dir);
                    }
                }
                *px = sum / spp as f32;
            }
            stage.advance(1);
        });
    stage.finish()?;
    Ok(image)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_sequence_follows_knaus_zwicker() {
        // r²₂ = r²₁ (1 + α)/2, r²₃ = r²₂ (2 + α)/3.
        let a = 0.7f32;
        let s1 = progressive_radius_scale(1, a);
        let s2 = progressive_radius_scale(2, a);
        assert!((s1 * s1 - 0.85).abs() < 1e-6);
        assert!((s2 * s2 - 0.85 * 2.7 / 3.0).abs() < 1e-6);
        assert_eq!(progressive_radius_scale(0, a), 1.0);
        // r²ᵢ ~ i^(α−1): at pass 1000 between 0.1 and 0.2 of the first for α = 0.7.
        let s = progressive_radius_scale(1000, a);
        assert!(s * s > 0.1 && s * s < 0.2, "{}", s * s);
    }

    /// Photons on the Cornell floor beside the left wall (x = −1) with an irradiance that
    /// grows linearly away from it, E(x) = 1 + 4(x + 1), on a fine jittered grid (power =
    /// E × the cell's area), and floor pixels 0.005, 0.03 and 0.06 from the wall with a kernel
    /// of radius 0.1. The zeroth-order estimate S0/m0 (the splat over the kernel's coverage)
    /// reads E at the covered part's centroid, off the wall: measured 12.3%, 6.3% and 2.1% too
    /// bright. The local-linear intercept recovers E to within 0.3% (the moments match a
    /// numerical integral to 3 digits: m0 0.5422 against 0.5424 at the first pixel). Bound:
    /// 1%, and a quarter of the zeroth-order error.
    #[test]
    fn local_linear_removes_the_first_order_crease_bias() {
        let scene = crate::scene::builtin::load("cornell").unwrap();
        let bvh = SceneBvh::build(&scene);
        let r = 0.1f32;
        let e = |x: f32| 1.0 + 4.0 * (x + 1.0);
        let step = 0.0025f32;
        let mut rng = Rng::new(3, 0, 0);
        let mut photons = Vec::new();
        for i in 0..(0.4 / step) as u32 {
            for j in 0..(0.4 / step) as u32 {
                let j2 = rng.next_2d();
                let x = -1.0 + (i as f32 + j2.x) * step;
                let z = 0.1 + (j as f32 + j2.y) * step;
                photons.push(Photon {
                    position: [x, 0.0, z],
                    normal: [0.0, 1.0, 0.0],
                    power: [e(x) * step * step; 3],
                    footprint_radius: r,
                    ..Photon::default()
                });
            }
        }
        let xs = [-0.995f32, -0.97, -0.94];
        let position: Vec<Vec4> = xs.iter().map(|&x| Vec4::new(x, 0.0, 0.3, 1.0)).collect();
        let normals = vec![Vec4::new(0.0, 1.0, 0.0, 1.0); xs.len()];
        let moments = query_moments(&scene, &bvh, &position, &normals, r, 11);
        let near = vec![true; xs.len()];
        let fit = CreaseFit {
            bandwidth: 1.0,
            linear: true,
        };
        let factors = crease_estimate(&scene, &position, &normals, &near, &moments, &photons, 1.0, fit);
        for ((x, m), f) in xs.iter().zip(&moments).zip(&factors) {
            // S0 as the splat sums it.
            let s0: f32 = photons
                .iter()
                .map(|p| {
                    let d2 = (p.position() - Vec3::new(*x, 0.0, 0.3)).length_squared() / (r * r);
                    if d2 < 1.0 {
                        p.power[0] * 2.0 / (std::f32::consts::PI * r * r) * (1.0 - d2)
                    } else {
                        0.0
                    }
                })
                .sum();
            let zeroth = s0 / m.m0;
            let linear = s0 * f.x;
            let exact = e(*x);
            println!("x {x}: {m:?} zeroth {zeroth:.4} linear {linear:.4} exact {exact:.4}");
            assert!(m.m0 < 0.95, "{m:?}");
            let (e0, e1) = ((zeroth / exact - 1.0).abs(), (linear / exact - 1.0).abs());
            assert!(e1 < 0.01 && e1 < 0.25 * e0, "{linear} {zeroth} {exact}");
        }
    }

    #[test]
    fn running_mean_and_seeds() {
        let mut img = Image::new(2, 1);
        img.pixels[0] = glam::Vec3::splat(1.0);
        let mut acc = Accumulation::new(&img);
        acc.add(&img);
        img.pixels[0] = glam::Vec3::splat(3.0);
        img.pixels[1] = glam::Vec3::splat(f32::NAN);
        let m = acc.add(&img);
        assert_eq!(m.pixels[0], glam::Vec3::splat(2.0));
        assert_eq!(m.pixels[1], glam::Vec3::ZERO);
        let s = Settings {
            progressive: true,
            ..Settings::default()
        };
        let seeds: std::collections::HashSet<u64> =
            (0..100).map(|p| pass_settings(&s, None, p).seed).collect();
        assert_eq!(seeds.len(), 100);
        assert_eq!(sample_offset(&s, 0), Vec2::ZERO);
        let o = sample_offset(&s, 3);
        assert!(o.x >= 0.0 && o.x < 1.0 && o.y >= 0.0 && o.y < 1.0 && o != Vec2::ZERO);
    }
}
