//! The camera half of the photon-map methods: per pixel sample, follow the camera ray
//! through delta lobes (mirror, glass) and ask an estimator for the radiance leaving each
//! non-delta surface it reaches; assemble the image and the first-hit AOVs.

use crate::cancel::{Progress, StageProgress};
use crate::error::Result;
use crate::image::Image;
use crate::sampling::Rng;
use crate::scene::Scene;
use crate::trace::path::{self, FirstHit, FirstHitImages};
use crate::trace::{Interaction, SceneBvh};
use glam::Vec3;
use rayon::prelude::*;

/// The camera samples of a frame of the photon-map methods: `spp` jittered rays per pixel
/// drawn from `seed`, each following delta lobes through up to `max_depth` scatterings
/// (Russian roulette beyond [`ROULETTE_DEPTH`]); with `first_hit_aovs`, one more ray through each
/// pixel centre for the first-hit images.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CameraSamples {
    pub spp: u32,
    pub seed: u64,
    pub max_depth: u32,
    pub first_hit_aovs: bool,
}

/// What a camera path gathers besides the estimates at the non-delta surfaces it reaches
/// through delta lobes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Collect {
    /// The whole image: the first surface's estimate too, and the light the path meets
    /// (emitting surfaces, the sky and suns' discs where it leaves the scene).
    Everything,
    /// The specular image: beyond the first surface only, the light the path meets there
    /// included (the rasterized passes see none of it through delta lobes).
    BeyondFirst,
    /// A final-gather ray's: the estimates at every non-delta surface it reaches (the first
    /// one included), none of the light it meets (next-event estimation at the surface it
    /// leaves, or the caustic photons there, count that).
    EstimatesOnly,
}

impl Collect {
    fn estimate_first(self) -> bool {
        self != Collect::BeyondFirst
    }
    /// Whether the light met at scattering depth `depth` counts.
    fn light_at(self, depth: u32) -> bool {
        match self {
            Collect::Everything => true,
            Collect::BeyondFirst => depth > 0,
            Collect::EstimatesOnly => false,
        }
    }
}

/// Scatterings after which a camera path is continued with probability `min(1, max β)`
/// (its throughput; unbiased). Until then every path is followed; after, paths that keep
/// their throughput (glass, ideal mirrors) go on to the method's `max_depth`. Light that
/// enters a glass sphere near its rim meets the inside close to the critical angle and is
/// reflected there many times: the former cap of 8 delta scatterings left the rim of the
/// roughdielectric sphere 7% dark in `photon` and `gather` (0.983 and 0.972 of Mitsuba's
/// image mean; 1.005 and 0.996 followed to 64).
pub const ROULETTE_DEPTH: u32 = 8;

/// Renders the image whose non-delta surfaces get their outgoing radiance from `estimate`
/// `(interaction, wo, rng, scratch)`, and the first-hit images (empty without
/// `first_hit_aovs`); `S` is per-thread scratch space. The camera paths see emitting
/// surfaces, the sky and suns' discs themselves, directly and through delta lobes.
pub fn render_image<S: Default + Send>(
    scene: &Scene,
    bvh: &SceneBvh,
    settings: &CameraSamples,
    progress: &dyn Progress,
    estimate: impl Fn(&Interaction, Vec3, &mut Rng, &mut S) -> Vec3 + Sync,
) -> Result<(Image, FirstHitImages)> {
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let stage = StageProgress::new(progress, "radiance estimate", h as u64);
    let rows: Vec<Vec<(Vec3, FirstHit)>> = (0..h)
        .into_par_iter()
        .map_init(S::default, |scratch, y| {
            if stage.stopped() {
                return Vec::new();
            }
            let row = (0..w)
                .map_while(|x| {
                    if stage.stopped() {
                        return None;
                    }
                    let l = pixel_radiance(
                        scene,
                        bvh,
                        settings,
                        (x, y),
                        Collect::Everything,
                        |it, wo, rng| estimate(it, wo, rng, scratch),
                    );
                    let centre = cam.direction(x as f32 + 0.5, y as f32 + 0.5);
                    let first = if settings.first_hit_aovs {
                        path::first_hit(scene, bvh, cam.position, centre)
                    } else {
                        FirstHit::default()
                    };
                    Some((l, first))
                })
                .collect();
            stage.advance(1);
            row
        })
        .collect();
    stage.finish()?;
    let mut radiance = Image::new(w, h);
    let mut hits = Vec::with_capacity((w * h) as usize);
    for (i, (l, fh)) in rows.into_iter().flatten().enumerate() {
        radiance.pixels[i] = l;
        hits.push(fh);
    }
    Ok((radiance, FirstHitImages::of(w, h, hits)))
}

/// The part of the image that reaches the camera through a delta lobe (mirror reflection,
/// refraction) of the first surface seen, `spp` jittered samples per pixel, as in
/// `render_image` but without the first surface's own non-delta lobes: what a rasterizer
/// that shades the first surface cannot give (ISPM section 4: "backwards recursive ray
/// tracing on the CPU, with recursive global illumination approximated by ... a
/// traditional photon map gather"). Pixels whose first surface has no delta lobe cost one
/// ray per sample and stay black. The light the paths meet beyond the first surface is
/// added (`Collect::BeyondFirst`).
pub fn delta_image<S: Default + Send>(
    scene: &Scene,
    bvh: &SceneBvh,
    settings: &CameraSamples,
    progress: &dyn Progress,
    estimate: impl Fn(&Interaction, Vec3, &mut Rng, &mut S) -> Vec3 + Sync,
) -> Result<Image> {
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let mut image = Image::new(w, h);
    if !scene.has_specular_traced() {
        return Ok(image);
    }
    let stage = StageProgress::new(progress, "specular paths", h as u64);
    image
        .pixels
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each_init(S::default, |scratch, (y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                if stage.stopped() {
                    return;
                }
                *px = pixel_radiance(
                    scene,
                    bvh,
                    settings,
                    (x as u32, y as u32),
                    Collect::BeyondFirst,
                    |it, wo, rng| estimate(it, wo, rng, scratch),
                );
            }
            stage.advance(1);
        });
    stage.finish()?;
    Ok(image)
}

/// The radiance a final-gather ray from `origin` along `dir` brings back: `estimate` at the
/// first non-delta surface it meets and at those it reaches from there through delta lobes
/// (mirrors, glass; up to `max_delta` scatterings, Russian roulette beyond
/// [`ROULETTE_DEPTH`]), none of the light it meets itself.
pub fn gather_ray(
    scene: &Scene,
    bvh: &SceneBvh,
    (origin, dir): (Vec3, Vec3),
    max_delta: u32,
    rng: &mut Rng,
    estimate: impl FnMut(&Interaction, Vec3, &mut Rng) -> Vec3,
) -> Vec3 {
    radiance(
        scene,
        bvh,
        origin,
        dir,
        max_delta,
        Collect::EstimatesOnly,
        rng,
        estimate,
    )
}

/// Mean radiance of `settings.spp` jittered camera samples through pixel (`x`, `y`),
/// gathering what `collect` says (see [`radiance`]).
fn pixel_radiance(
    scene: &Scene,
    bvh: &SceneBvh,
    settings: &CameraSamples,
    (x, y): (u32, u32),
    collect: Collect,
    mut estimate: impl FnMut(&Interaction, Vec3, &mut Rng) -> Vec3,
) -> Vec3 {
    let cam = &scene.camera;
    let max_delta = settings.max_depth;
    let pixel = y as u64 * cam.width as u64 + x as u64;
    let mut sum = Vec3::ZERO;
    for s in 0..settings.spp {
        let mut rng = Rng::new(settings.seed, pixel, s as u64);
        let j = rng.next_2d();
        let dir = cam.direction(x as f32 + j.x, y as f32 + j.y);
        sum += radiance(
            scene,
            bvh,
            cam.position,
            dir,
            max_delta,
            collect,
            &mut rng,
            &mut estimate,
        );
    }
    sum / settings.spp as f32
}

/// Radiance arriving at `origin` from `-dir`: estimates at every non-delta surface the ray
/// reaches through up to `max_delta` delta scatterings (the first surface only when
/// [`Collect::Everything`]). The estimate covers a surface's non-delta lobes; its delta lobe (if
/// any) is followed when `Material::sample` picks it, with the sample weight accounting for
/// that choice. Rough glass is followed through whatever lobe is sampled, never estimated.
/// The light the path meets (emitting surfaces, and the sky and suns' discs where it leaves
/// the scene) is added where `collect` says.
#[allow(clippy::too_many_arguments)]
fn radiance(
    scene: &Scene,
    bvh: &SceneBvh,
    origin: Vec3,
    dir: Vec3,
    max_delta: u32,
    collect: Collect,
    rng: &mut Rng,
    mut estimate: impl FnMut(&Interaction, Vec3, &mut Rng) -> Vec3,
) -> Vec3 {
    let mut l = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    let (mut o, mut d) = (origin, dir);
    for depth in 0..=max_delta {
        let Some(hit) = bvh.intersect(o, d, f32::INFINITY) else {
            if collect.light_at(depth) {
                l += beta * crate::trace::direct::escaped(scene, d, None, true);
            }
            break;
        };
        let it = Interaction::new(scene, &hit, d);
        let wo = -d;
        if collect.light_at(depth) {
            l += beta * it.material.emitted(it.ng, wo);
        }
        let estimate_first = collect.estimate_first();
        // Rough glass is followed like a delta lobe (its light arrives through the glass,
        // which neither the photons on its surface nor next-event estimation resolve: the
        // sky seen through it is no photon).
        let followed = it.material.rough_glass;
        if (depth > 0 || estimate_first) && !it.material.is_purely_specular() && !followed {
            l += beta * estimate(&it, wo, rng);
        }
        if depth == 0 && !estimate_first && !it.material.is_specular_traced() {
            break;
        }
        // Continue only through a delta lobe, geometrically consistent.
        let Some(bs) = it.material.sample(it.frame.to_local(wo), rng) else {
            break;
        };
        if !bs.lobe.is_delta() && !followed {
            break;
        }
        let wi = it.frame.to_world(bs.wi);
        let same_side = wi.dot(it.ng) * wo.dot(it.ng) > 0.0;
        if same_side == bs.lobe.crosses() {
            break;
        }
        beta *= bs.weight;
        if depth + 1 >= ROULETTE_DEPTH {
            let q = beta.max_element().min(1.0);
            if q.is_nan() || q <= 0.0 || rng.next_f32() >= q {
                break;
            }
            beta /= q;
        }
        o = it.spawn(wi);
        d = wi;
    }
    l
}
