//! The reference path tracer: next-event estimation from every source
//! ([`super::direct`]), BSDF importance sampling and Russian roulette. Emitters, suns'
//! discs and the environment are found both by next-event estimation and by the paths' own
//! BSDF rays (camera rays included), the two combined by multiple importance sampling
//! (power heuristic). A camera path can never reach a point light or a parallel sun through
//! a delta (mirror or glass) scattering, and reaches small emitters that way only by
//! chance, so paths whose first bounce from a light, an emitter or a sun is specular are
//! left to the light tracer ([`super::light_tracer`]) when it runs (`light_traced`); the
//! sky's stay here.

use super::direct::{escaped, BsdfVertex, DirectLight, LightQuery, Nee};
use super::light_vertex::{self, Connection, LightVertices};
use super::{Interaction, SceneBvh};
use crate::image::Image;
use crate::sampling::Rng;
use crate::scene::{Environment, Scene};
use glam::Vec3;

/// Dimensions of a low-discrepancy sample that the camera draws (the pixel jitter) before
/// [`radiance`] draws its own.
pub const CAMERA_DIMENSIONS: u32 = 2;
/// Dimensions [`radiance`] sets apart for its light vertex ([`super::light_vertex`]), before
/// the bounces'.
pub const LIGHT_VERTEX_DIMENSIONS: u32 = light_vertex::DIMENSIONS;
/// Dimensions [`radiance`] sets apart for each bounce: light selection and a point on it
/// (3), the BSDF's lobe and direction (3), Russian roulette (1); a bounce that draws more
/// (several suns, the sky) goes on into the next bounce's, which then starts after it.
pub const BOUNCE_DIMENSIONS: u32 = 8;

/// Russian roulette lets a path go on with probability min(`RR_SURVIVAL_SCALE` · max β,
/// 0.95), β its throughput: a path is spared while its throughput is above a third. With the
/// classic max β (scale 1), a path in a bright closed room is ended at every bounce after
/// `rr_depth` with probability about 1 − albedo, and the survivors' weight 1/q costs more
/// variance than the shorter paths save time: at equal CPU time, scale 3 has 1.4× the
/// efficiency (1 / (time × relMSE)) of scale 1 on the Cornell box of
/// `docs/bench/path-vs-mitsuba.md`, 2.7× on the furnace, 1.4× on `cornell-glass` and the
/// same on the open `mirror-shadow` (table and command in that file).
pub const RR_SURVIVAL_SCALE: f32 = 3.0;

/// Path tracer settings.
#[derive(Clone, Copy, Debug)]
pub struct PathSettings {
    /// Maximum number of surface interactions per path (1 = direct light only).
    pub max_depth: u32,
    /// Interactions before Russian roulette may end a path.
    pub rr_depth: u32,
    /// The light tracer ([`super::light_tracer`]) renders the paths whose first scattering
    /// after an emitter or a sun is a delta lobe and whose first scattering seen from the
    /// camera is not: the path tracer leaves them out.
    pub light_traced: bool,
    /// How emitters, suns' discs and the sky are found.
    pub strategy: Strategy,
    /// Whether the light of point and spot lights that reflects once before a camera
    /// path's vertex is also found by connecting that vertex to a light vertex
    /// ([`super::light_vertex`]).
    pub light_vertex: Connection,
    /// Whether the first ray counts the suns' discs it escapes to (`false` where the
    /// caller's next-event estimation at the ray's origin took the directional lights along
    /// their axes at full weight).
    pub first_ray_suns: bool,
}

/// How the path tracer finds the light of emitters, suns' discs and the sky: both ways
/// combined (the renderer's), or one alone (for tests: each converges to the same image).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Strategy {
    /// Next-event estimation and BSDF rays, by multiple importance sampling.
    #[default]
    Mis,
    /// Next-event estimation only (BSDF rays after a non-delta scattering count nothing).
    Light,
    /// BSDF rays only (next-event estimation of point, spot and parallel lights only).
    Bsdf,
}

/// What the camera ray sees first, for the auxiliary images.
#[derive(Clone, Copy, Debug, Default)]
pub struct FirstHit {
    pub albedo: Vec3,
    pub normal: Vec3,
    pub position: Vec3,
    /// Distance along the camera's forward axis (view-space z), 0 on a miss.
    pub depth: f32,
}

/// The first-hit images of a frame (the AOVs of the CPU methods), `width × height`.
#[derive(Clone, Debug)]
pub struct FirstHitImages {
    pub albedo: Image,
    pub normal: Image,
    pub position: Image,
    pub depth: Vec<f32>,
}

impl FirstHitImages {
    /// The images of `hits`, one per pixel in row order.
    pub fn of(width: u32, height: u32, hits: impl IntoIterator<Item = FirstHit>) -> Self {
        let mut out = FirstHitImages {
            albedo: Image::new(width, height),
            normal: Image::new(width, height),
            position: Image::new(width, height),
            depth: vec![0.0; (width * height) as usize],
        };
        for (i, fh) in hits.into_iter().enumerate() {
            out.albedo.pixels[i] = fh.albedo;
            out.normal.pixels[i] = fh.normal;
            out.position.pixels[i] = fh.position;
            out.depth[i] = fh.depth;
        }
        out
    }
}

/// Light arriving at `it` from the point, spot and directional lights by direct paths, times
/// the BSDF towards `wo` (world space, pointing away from the surface): deterministic, a
/// directional light along its axis. [`super::direct::DirectLight::estimate`] covers every
/// source (emitters, suns' discs, the environment).
pub fn direct_light(scene: &Scene, bvh: &SceneBvh, it: &Interaction, wo: Vec3) -> Vec3 {
    if it.material.is_purely_specular() {
        return Vec3::ZERO;
    }
    scene
        .lights
        .iter()
        .map(|light| super::direct::analytic_light(light, bvh, it, wo))
        .sum()
}

/// Power heuristic (β = 2) weight of a strategy of density `a` against one of density `b`.
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 && a2.is_finite() {
        a2 / (a2 + b2)
    } else if a2.is_infinite() {
        1.0
    } else {
        0.0
    }
}

/// Environment light arriving at `it` from one direction sampled by importance, times the
/// BSDF towards `wo`; with `mis`, weighted against BSDF sampling (the path's BSDF-sampled
/// continuation, which may also escape to the environment) by the power heuristic.
pub fn environment_light(env: &Environment, q: LightQuery, rng: &mut Rng) -> Vec3 {
    let LightQuery { bvh, it, wo, mis } = q;
    let u = rng.next_2d();
    let m = it.material;
    if m.is_purely_specular() {
        return Vec3::ZERO;
    }
    let Some(s) = env.sample(u) else {
        return Vec3::ZERO;
    };
    if s.pdf <= 0.0 || s.radiance == Vec3::ZERO || !super::direct::reaches(it, wo, s.wi) {
        return Vec3::ZERO;
    }
    let (wo_l, wi_l) = (it.frame.to_local(wo), it.frame.to_local(s.wi));
    let f = m.eval(wo_l, wi_l);
    if f == Vec3::ZERO || bvh.occluded(it.spawn(s.wi), s.wi, f32::INFINITY) {
        return Vec3::ZERO;
    }
    let w = if mis {
        power_heuristic(s.pdf, m.pdf(wo_l, wi_l))
    } else {
        1.0
    };
    f * wi_l.z.abs() * s.radiance * (w / s.pdf)
}

/// What the ray `origin + t·dir` hits first.
pub fn first_hit(scene: &Scene, bvh: &SceneBvh, origin: Vec3, dir: Vec3) -> FirstHit {
    let Some(hit) = bvh.intersect(origin, dir, f32::INFINITY) else {
        return FirstHit::default();
    };
    let it = Interaction::new(scene, &hit, dir);
    let wo = -dir;
    let n = if it.frame.n.dot(wo) < 0.0 {
        -it.frame.n
    } else {
        it.frame.n
    };
    FirstHit {
        albedo: it.material.scatter_probability(it.frame.to_local(wo)),
        normal: n,
        position: it.position,
        depth: (it.position - scene.camera.position).dot(scene.camera.forward),
    }
}

/// The non-delta BSDF samples that led to a surface: the vertex the ray to it left, and the
/// vertex that one was reached from (`None` for camera rays and delta scatterings).
#[derive(Clone, Copy)]
struct BsdfRays {
    from: Option<BsdfVertex>,
    prev_from: Option<BsdfVertex>,
}

/// The weight of the light of the emitter the path reached at `it`: 1 for a camera ray or
/// after a delta scattering, 0 when only next-event estimation finds emitters, else the
/// multiple-importance weight against next-event estimation and, where the ray left a
/// vertex a non-delta sample reached, the light vertices' connection.
fn emission_weight(
    lights: &DirectLight,
    light_vertices: Option<&LightVertices>,
    rays: BsdfRays,
    it: &Interaction,
    s: &PathSettings,
) -> f32 {
    match (rays.from, s.strategy) {
        (None, _) => 1.0,
        (Some(_), Strategy::Light) => 0.0,
        (Some(f), strategy) => {
            // Light vertices find this emitter's light too where the ray left a
            // vertex that a non-delta sample reached.
            let other = match (light_vertices, rays.prev_from) {
                (Some(lv), Some(x)) => {
                    lv.emitter_hit_pdf((&x, &f), (it.position, it.triangle), s.light_vertex)
                }
                _ => 0.0,
            };
            let hit = (it.triangle, it.position, it.ng);
            lights.emitter_weight(&f, hit, strategy == Strategy::Mis, other)
        }
    }
}

/// Radiance arriving at `origin` from direction `-dir`.
pub fn radiance(
    scene: &Scene,
    bvh: &SceneBvh,
    lights: &DirectLight,
    ray: (Vec3, Vec3),
    rng: &mut Rng,
    s: &PathSettings,
) -> Vec3 {
    radiance_from(scene, bvh, lights, ray, rng, s, false)
}

/// [`radiance`] of a ray that leaves a delta scattering which followed a non-delta one
/// (`bidir`'s camera paths through glass seen from a lit surface): the emitters and suns'
/// discs it meets while every scattering since has been a delta one are left out (the
/// delta-chain light tracer of `light_tracer::LightTraceSettings::chain_only` carries
/// them); the sky is kept.
pub fn radiance_past_delta_chain(
    (scene, bvh, lights): (&Scene, &SceneBvh, &DirectLight),
    ray: (Vec3, Vec3),
    rng: &mut Rng,
    s: &PathSettings,
) -> Vec3 {
    radiance_from(scene, bvh, lights, ray, rng, s, true)
}

/// [`radiance`], with `chain`: the ray leaves a delta chain whose emitter and sun hits are
/// left out ([`radiance_past_delta_chain`]).
fn radiance_from(
    scene: &Scene,
    bvh: &SceneBvh,
    lights: &DirectLight,
    (origin, dir): (Vec3, Vec3),
    rng: &mut Rng,
    s: &PathSettings,
    mut chain: bool,
) -> Vec3 {
    let mut l = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    let (mut o, mut d) = (origin, dir);
    // The vertex the current ray left by a non-delta BSDF sample (multiple importance
    // sampling applies to what it hits); `None` for camera rays and delta scatterings.
    let mut from: Option<BsdfVertex> = None;
    // The same for the ray before (the vertex `from` was reached from by a non-delta
    // sample), for the light vertices' weights.
    let mut prev_from: Option<BsdfVertex> = None;
    // Whether the path's first scattering (at the camera's first surface) was non-delta,
    // and whether the current ray left a delta scattering.
    let (mut first_non_delta, mut after_delta) = (false, false);
    // The light vertex of this path (drawn at its first vertex), where it has one.
    let mut vertex = None;
    let light_vertices = lights
        .light_vertices
        .as_ref()
        .filter(|_| s.light_vertex != Connection::Off && s.max_depth >= 2);
    // The path goes one step beyond its last scattering: a BSDF sample from the last
    // vertex still finds emitters, suns' discs and the sky (so that `max_depth` 1 is direct
    // light for both sampling strategies).
    for depth in 0..=s.max_depth {
        // Light reached through a delta scattering after a non-delta first one belongs to
        // the light tracer (its paths start at the source, scatter through that delta lobe
        // first and connect to the camera from the first surface).
        let light_traced = (s.light_traced && after_delta && first_non_delta) || chain;
        let pdf = from.map(|f| f.pdf);
        let Some(hit) = bvh.intersect(o, d, f32::INFINITY) else {
            if !(s.strategy == Strategy::Light && from.is_some()) {
                let pdf = pdf.filter(|_| s.strategy == Strategy::Mis);
                let suns = !light_traced && (depth > 0 || s.first_ray_suns);
                l += beta * escaped(scene, d, pdf, suns);
            }
            break;
        };
        let it = Interaction::new(scene, &hit, d);
        let wo = -d;
        if it.material.emits() && !light_traced {
            let rays = BsdfRays { from, prev_from };
            let w = emission_weight(lights, light_vertices, rays, &it, s);
            l += beta * it.material.emitted(it.ng, wo) * w;
        }
        if depth == s.max_depth {
            break;
        }
        if depth == 0 {
            if let Some(lv) = light_vertices {
                rng.start_dimension(CAMERA_DIMENSIONS);
                vertex = lv.sample(scene, bvh, rng);
            }
        }
        // The light vertex's light reflected here (the path tracer finds the same light
        // with one more vertex, next-event estimation there).
        if let Some(v) = vertex.as_ref().filter(|_| depth + 2 <= s.max_depth) {
            let lv = light_vertices.expect("a vertex comes from light vertices");
            let c = lv.connect(scene, (bvh, lights), &it, wo, v, s.light_vertex, s.strategy);
            l += beta * c;
        }
        // A low-discrepancy generator ([`Rng::sobol`]) gives every bounce its own dimensions
        // (after the camera's and the light vertex's), so that bounce `depth` of all samples
        // of a pixel is one stratified point set.
        rng.start_dimension(
            CAMERA_DIMENSIONS + LIGHT_VERTEX_DIMENSIONS + depth * BOUNCE_DIMENSIONS,
        );
        // Next-event estimation; after a non-delta BSDF sample, of the point and spot
        // lights' light the share that the previous vertex's light-vertex connection
        // leaves.
        let nee = match s.strategy {
            Strategy::Mis => Nee::Mis,
            Strategy::Light => Nee::Alone,
            Strategy::Bsdf => Nee::DeltaOnly,
        };
        l += beta
            * match (light_vertices, from) {
                (Some(lv), Some(f)) => {
                    let shared = lv.sharing(scene, f, s.light_vertex);
                    lights.estimate(scene, bvh, &it, wo, rng, nee, Some(&shared))
                }
                _ => lights.estimate(scene, bvh, &it, wo, rng, nee, None),
            };
        if depth + 1 == s.max_depth && !lights.found_by_rays {
            // The last BSDF ray could only find emitters, suns' discs or the sky.
            break;
        }
        // Continue the path by sampling the BSDF.
        let wo_l = it.frame.to_local(wo);
        let Some(bs) = it.material.sample(wo_l, rng) else {
            break;
        };
        let wi = it.frame.to_world(bs.wi);
        // The sample must agree with the geometry: reflections stay on the viewer's side,
        // refractions cross.
        let same_side = wi.dot(it.ng) * wo.dot(it.ng) > 0.0;
        if same_side == bs.lobe.crosses() {
            break;
        }
        beta *= bs.weight;
        let delta = bs.lobe.is_delta();
        if depth == 0 {
            first_non_delta = !delta;
        }
        after_delta = delta;
        chain &= delta;
        prev_from = from;
        from = (!delta).then_some(BsdfVertex {
            position: it.position,
            normal: super::direct::sampling_normal(&it),
            ng: it.ng,
            pdf: bs.pdf,
        });
        // Possibly terminate the path with Russian roulette.
        if depth + 1 >= s.rr_depth {
            let q = (beta.max_element() * RR_SURVIVAL_SCALE).min(0.95);
            if q <= 0.0 || rng.next_f32() >= q {
                break;
            }
            beta /= q;
        }
        o = it.spawn(wi);
        d = wi;
    }
    l
}
