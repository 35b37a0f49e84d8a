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
//! surface is therefore ray traced on the CPU ([`direct_image`]: the surface's emission and
//! next-event estimation of every light, emitter and the sky with the scene BVH at new
//! jittered sub-pixel positions per pass; the environment where the ray escapes), and
//! replaces the rasterized one in the pass.

use super::options::Common;
use super::FrameParams;
use crate::cancel::Progress;
use crate::cancel::StageProgress;
use crate::error::Result;
use crate::image::Image;
use crate::photon::radius::Z_RATIO;
use crate::photon::{boundary, Photon};
use crate::raster::oct_decode;
use crate::sampling::Rng;
use crate::scene::emitters::Emitters;
use crate::scene::{Light, Scene};
use crate::trace::{Interaction, SceneBvh};
use glam::{DVec3, Vec2, Vec3, Vec4};
use rayon::prelude::*;

/// Kernel radius scale of progressive pass `pass` (0-based) relative to the first:
/// r²ᵢ₊₁ = r²ᵢ (i + α)/(i + 1) with i counted from 1 (Knaus & Zwicker 2011, eq. 13).
pub fn progressive_radius_scale(pass: u64, alpha: f32) -> f32 {
    let alpha = alpha as f64;
    let mut r2 = 1.0f64;
    for i in 1..=pass {
        r2 *= (i as f64 + alpha) / (i as f64 + 1.0);
    }
    r2.sqrt() as f32
}

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

/// The frame parameters of progressive pass `pass` (0-based): the base seed (`seed`, else
/// the options') for the first pass, then a new one per pass, and the kernel radius scale
/// of the pass.
pub(super) fn pass_params(common: &Common, seed: Option<u64>, pass: u64) -> FrameParams {
    let base = seed.unwrap_or(common.seed);
    FrameParams {
        seed: if pass == 0 {
            base
        } else {
            base ^ mix(pass.wrapping_add(0x5851_F42D_4C95_7F2D))
        },
        radius_scale: progressive_radius_scale(pass, common.progressive_alpha),
        first_hit_aovs: true,
        progressive: true,
    }
}

/// The sub-pixel offset of the GPU methods' sample positions in pass `pass` (a
/// Cranley–Patterson rotation, new per pass; zero outside progressive mode and in the first
/// pass, so that pass is the ordinary frame).
pub(super) fn sample_offset(common: &Common, pass: u64) -> Vec2 {
    if !common.progressive || pass == 0 {
        return Vec2::ZERO;
    }
    let h = mix(common.seed ^ mix(pass));
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
///
/// The coverage is traced ([`boundary::coverage_moments`]: where the surface ends along 8
/// directions and where the cover leaves the rim, integrated in closed form), not counted
/// from 8 random probes ([`boundary::coverage`]): the splat is divided by it, and the mean of
/// 1/ĉ over noisy estimates ĉ is biased high (Jensen): +6% and +8% 0.05 r and 0.3 r from a
/// crease, and the quick ring test's misses made it −6% at 0.6 r (test
/// `traced_coverage_is_unbiased_at_a_crease`). On cornell 64x64 (64 passes) the
/// indirect light on the ceiling was 8–10% too bright within 0.06 of the side walls and
/// 3–4% too dark just beyond; with the traced coverage within ±2.5%, relMSE 7.8e-4 → 6.3e-4
/// and FLIP 0.0452 → 0.0429. It costs 5–30 ms per pass at 64x64–128x128 (3–10 ms before),
/// docs/bench/progressive.md.
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
            let probe = Photon {
                position: p.truncate().into(),
                normal: facing_normal(*p, *n, eye).into(),
                ..Photon::default()
            };
            let mut rng = Rng::new(seed, 0xC0BE, i as u64);
            boundary::coverage_moments(scene, bvh, &probe, r, Z_RATIO, &mut rng)
                .m0
                .max(boundary::MIN_COVERAGE)
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

/// Stream of the direct light's sub-pixel samples (apart from the specular paths').
const DIRECT_STREAM: u64 = 0xD1EC_7000_0000_0000;

/// The direct light of the first surface seen through each pixel (the part ISPM
/// rasterizes with shadow maps: the surface's emission and next-event estimation of every
/// light on its non-delta lobes, [`first_surface_light`]; the environment where the ray
/// escapes), ray traced on the CPU as `path` does at its first vertex: the mean of k×k
/// camera rays per pixel (k = ⌈√spp⌉, at least 2), one at a uniformly random point of each
/// stratum drawn from `seed`, so that the mean over passes of new seeds converges to the
/// pixel's exact direct light.
pub(super) fn direct_image(
    scene: &Scene,
    bvh: &SceneBvh,
    spp: u32,
    seed: u64,
    progress: &dyn Progress,
) -> Result<Image> {
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    // k×k strata per pixel, one random point in each: at least 2×2 (a few ms per pass at
    // 128x128), since one random point per pass had 3× the variance of the shadow-mapped
    // direct light at mirror-shadow's shadow edges (relMSE 6.5e-4 vs 2.1e-4 after 16 passes).
    let k = (spp.max(1) as f32).sqrt().ceil().max(2.0) as u32;
    let spp = k * k;
    let emitters = Emitters::of(scene);
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
                    let mut rng = Rng::new(seed, pixel, DIRECT_STREAM + s as u64);
                    let j = rng.next_2d();
                    let (sx, sy) = ((s % k) as f32, (s / k) as f32);
                    let dir = cam.direction(
                        x as f32 + (sx + j.x) / k as f32,
                        y as f32 + (sy + j.y) / k as f32,
                    );
                    match bvh.intersect(cam.position, dir, f32::INFINITY) {
                        Some(hit) => {
                            let it = Interaction::new(scene, &hit, dir);
                            let e = &emitters;
                            sum += first_surface_light(scene, bvh, e, &it, -dir, &mut rng);
                        }
                        None => {
                            if let Some(env) = &scene.environment {
                                sum += env.radiance(dir);
                            }
                        }
                    }
                }
                *px = sum / spp as f32;
            }
            stage.advance(1);
        });
    stage.finish()?;
    Ok(image)
}

/// The light leaving the first surface `it` towards `wo` (world, away from the surface)
/// without a later bounce: its emission, and next-event estimation of every source without
/// multiple importance sampling (this image traces no BSDF-sampled continuation): each point
/// and spot light; each directional light along a direction drawn uniformly from its disc
/// (f·|cos θ|·E: its radiance times the disc's solid angle); one point drawn on the emitters
/// by power (f·|cos θ|·L·|cos θ'| / (d²·p_A)); one direction drawn from the environment
/// (f·|cos θ|·L / p). Unbiased; reflection only (the light on the viewer's side of the
/// geometry), as the rasterized direct light.
pub(super) fn first_surface_light(
    scene: &Scene,
    bvh: &SceneBvh,
    emitters: &Emitters,
    it: &Interaction,
    wo: Vec3,
    rng: &mut Rng,
) -> Vec3 {
    let mut sum = it.material.emitted(it.ng, wo);
    let m = it.material;
    // Rough glass is the specular image's: its camera paths follow the glass's lobes and
    // find this light by meeting it (as the GPU's direct light sees the smooth stand-in).
    if m.is_purely_specular() || m.rough_glass {
        return sum;
    }
    let wo_l = it.frame.to_local(wo);
    // f·|cos θ| towards `wi` times `li`, if unoccluded up to `dist`.
    let mut add = |wi: Vec3, li: Vec3, dist: f32| {
        if wi.dot(it.ng) * wo.dot(it.ng) <= 0.0 || li.max_element() <= 0.0 || !li.is_finite() {
            return;
        }
        let wi_l = it.frame.to_local(wi);
        let f = m.eval(wo_l, wi_l);
        if f == Vec3::ZERO {
            return;
        }
        let origin = it.spawn(wi);
        if !bvh.occluded(origin, wi, dist) {
            sum += f * wi_l.z.abs() * li;
        }
    };
    for light in &scene.lights {
        if let Light::Directional { irradiance, .. } = *light {
            let dir = crate::scene::light_views::distant_direction(light, Some(rng.next_2d()));
            add(-dir, irradiance, f32::INFINITY);
            continue;
        }
        let to_light = light.position() - it.position;
        let dist = to_light.length();
        let wi = to_light / dist;
        let li = light.intensity_towards(-wi) / (dist * dist);
        add(wi, li, dist * (1.0 - 1e-4));
    }
    if let Some(s) = emitters.sample(scene, rng.next_f32(), rng.next_2d()) {
        let to = s.point - it.position;
        let d2 = to.length_squared();
        let wi = to / d2.sqrt();
        let cos_e = s.normal.dot(-wi).abs();
        let le = emitters.radiance(scene, &s, -wi);
        if d2 > 0.0 && s.pdf_area > 0.0 {
            add(
                wi,
                le * (cos_e / (d2 * s.pdf_area)),
                d2.sqrt() * (1.0 - 1e-4),
            );
        }
    }
    if let Some(env) = &scene.environment {
        if let Some(s) = env.sample(rng.next_2d()) {
            if s.pdf > 0.0 {
                add(s.wi, s.radiance / s.pdf, f32::INFINITY);
            }
        }
    }
    sum
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

    /// Floor pixels of cornell 0.005, 0.03 and 0.06 from the left wall (a crease) with a
    /// kernel of radius 0.1: the splat is divided by the coverage, so what matters is the
    /// mean of 1/coverage over passes (seeds) against 1/c of the exact coverage c (a numerical
    /// integral of the Epanechnikov kernel over the half-plane: 0.5424, 0.7433, 0.9228). The
    /// 8-probe estimate of `boundary::coverage` that query_coverage used is unbiased itself
    /// but its reciprocal is not (Jensen), and its quick test (4 probes at 0.8 r all on the
    /// surface: whole) misses a cut 0.6 r away one time in ten: measured +6.1%, +7.6% and
    /// −6.3%. The traced coverage: within 0.1%. Bound 0.5%, and the old estimator must be
    /// off by more than 1% (so the test sees what it guards).
    #[test]
    fn traced_coverage_is_unbiased_at_a_crease() {
        let scene = crate::scene::builtin::load("cornell").unwrap();
        let bvh = SceneBvh::build(&scene);
        let r = 0.1f32;
        let exact = [0.5424f32, 0.7433, 0.9228];
        let xs = [-0.995f32, -0.97, -0.94];
        let position: Vec<Vec4> = xs.iter().map(|&x| Vec4::new(x, 0.0, 0.3, 1.0)).collect();
        let normals = vec![Vec4::new(0.0, 1.0, 0.0, 1.0); xs.len()];
        let seeds = 400;
        let mut traced = [0.0f64; 3];
        let mut probed = [0.0f64; 3];
        for seed in 0..seeds {
            let c = query_coverage(&scene, &bvh, &position, &normals, r, seed);
            for (k, p) in position.iter().enumerate() {
                traced[k] += 1.0 / c[k] as f64 / seeds as f64;
                let probe = Photon {
                    position: p.truncate().into(),
                    normal: [0.0, 1.0, 0.0],
                    ..Photon::default()
                };
                let mut rng = Rng::new(seed, 0xC0BE, k as u64);
                let old = boundary::coverage(&scene, &bvh, &probe, r, Z_RATIO, &mut rng)
                    .max(boundary::MIN_COVERAGE);
                probed[k] += 1.0 / old as f64 / seeds as f64;
            }
        }
        for k in 0..3 {
            let (t, o) = (
                traced[k] * exact[k] as f64 - 1.0,
                probed[k] * exact[k] as f64 - 1.0,
            );
            println!("x {}: traced {t:+.4} probed {o:+.4}", xs[k]);
            assert!(t.abs() < 0.005, "{t}");
            assert!(o.abs() > 0.01, "{o}");
        }
        // The moments beside it, against the same integral at the first pixel: m1 0.1687
        // (pointing away from the wall, +x here), m2 0.0834 across and 0.0918 along it.
        let m = boundary::coverage_moments(
            &scene,
            &bvh,
            &Photon {
                position: [xs[0], 0.0, 0.3],
                normal: [0.0, 1.0, 0.0],
                ..Photon::default()
            },
            r,
            Z_RATIO,
            &mut Rng::new(1, 2, 3),
        );
        assert!(
            (m.m1.x - 0.1687).abs() < 0.003 && m.m1.y.abs() < 0.003,
            "{m:?}"
        );
        assert!(
            (m.m2[0] - 0.0834).abs() < 0.003 && (m.m2[2] - 0.0918).abs() < 0.003,
            "{m:?}"
        );
        assert!(m.m2[1].abs() < 0.003, "{m:?}");
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
        let s = super::super::RenderOptions::defaults(super::super::Method::Gather)
            .progressive()
            .common;
        let seeds: std::collections::HashSet<u64> =
            (0..100).map(|p| pass_params(&s, None, p).seed).collect();
        assert_eq!(seeds.len(), 100);
        assert_eq!(sample_offset(&s, 0), Vec2::ZERO);
        let o = sample_offset(&s, 3);
        assert!(o.x >= 0.0 && o.x < 1.0 && o.y >= 0.0 && o.y < 1.0 && o != Vec2::ZERO);
    }
}
