//! The "uber" BSDF (after G3D's SuperBSDF used by the ISPM paper): Lambertian + glossy GGX
//! specular with optional Schlick Fresnel (a perfect mirror at roughness 0) + smooth glass.
//!
//! Lobes and their energy, for a viewing direction with cosine `c` and `F = F_s(c)`:
//! - specular: reflectance `F` (Schlick with `F0 = specular`, or constant `specular` when
//!   `fresnel` is off); a delta mirror at roughness 0, GGX with height-correlated Smith
//!   masking otherwise;
//! - diffuse: `ρL/π · (1 - F_s(ci))(1 - F_s(co)) / (1 - F_avg)`, which is reciprocal and
//!   reflects exactly `(1 - F)·ρL` ([`fresnel::schlick_average`] gives `F_avg` in closed form);
//! - glass: `(1 - F)·T`, split between delta reflection and refraction by the dielectric
//!   Fresnel term of index `ior`.
//!
//! With `diffuse + transmission <= 1` the albedo is at most 1 for every direction (tested).
//! Directions are local to the shading frame (+z = normal), both pointing away from the
//! surface: `wo` towards the viewer (or the previous photon vertex), `wi` towards the light.
//! The same formulas are implemented in WGSL for the GPU passes.

pub mod coated;
pub mod fresnel;
pub mod microfacet;
pub mod rough_dielectric;

pub use coated::Coating;
pub use microfacet::Distribution;

use crate::sampling::{cosine_hemisphere, Rng};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Roughness below which the specular lobe is treated as a perfect mirror.
pub const MIRROR_ROUGHNESS: f32 = 1e-3;

/// Parameters of the uber BSDF. All colours are linear RGB reflectances in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Lambertian albedo ρL.
    pub diffuse: Vec3,
    /// Specular reflectance at normal incidence ρS (F0).
    pub specular: Vec3,
    /// Perceptual roughness in [0, 1]; GGX α = roughness². 0 is a perfect mirror.
    pub roughness: f32,
    /// Whether the specular reflectance rises towards grazing angles (Schlick).
    pub fresnel: bool,
    /// Transmittance T of the smooth glass lobe.
    pub transmission: Vec3,
    /// Index of refraction of the glass lobe (inside over outside).
    pub ior: f32,
    /// Radiance emitted (W·sr⁻¹·m⁻² per channel) from the front face, the side the
    /// triangle's geometric normal faces: the surface is an area light. Zero: none.
    pub emission: Vec3,
    /// Whether the back face emits `emission` too.
    pub two_sided: bool,
    /// The microfacet distribution of the rough lobes.
    pub distribution: Distribution,
    /// Mitsuba's plastic/roughplastic: `diffuse` under this dielectric coating, whose
    /// reflection `specular` multiplies ([`coated`]). Replaces the uber's lobes.
    pub coating: Option<Coating>,
    /// A conductor's Fresnel term in place of Schlick's: `specular` multiplies it.
    pub conductor: Option<Conductor>,
    /// Mitsuba's roughdielectric: the glass of index `ior` is rough (`roughness`,
    /// `distribution`), `specular` multiplying its reflection and `transmission` its
    /// transmission ([`rough_dielectric`]). Replaces the uber's lobes.
    pub rough_glass: bool,
    /// Mitsuba's thindielectric: the smooth glass lobe is a thin slab of index `ior`
    /// ([`thin_reflectance`]: reflection R' = 2R/(1 + R), times these factors; the rest,
    /// times `transmission`, passes straight through, not bent).
    pub thin: Option<Vec3>,
    /// Mitsuba's BSDFs without `twosided`: the back face (the side away from the winding's
    /// normal) reflects and transmits nothing. A ray that meets it there sees
    /// [`Material::seen_from`]'s black material (`emission` still applies).
    pub one_sided: bool,
}

/// The reflectance of a thin slab of index `ior` seen at cosine `cos`: R' = R + T²R/(1 − R²)
/// = 2R/(1 + R), R the dielectric Fresnel reflectance and T = 1 − R (the light reflected
/// inside the slab any number of times; Mitsuba's thindielectric).
pub fn thin_reflectance(cos: f32, ior: f32) -> f32 {
    let r = fresnel::dielectric(cos.abs(), ior).0;
    2.0 * r / (1.0 + r)
}

/// The complex index of refraction `eta + i·k` (relative to the outside, per channel) of a
/// conductor, with its Fresnel term's cosine-weighted mean.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    pub eta: Vec3,
    pub k: Vec3,
    /// `2∫F(μ)μ dμ`.
    pub average: Vec3,
}

impl Conductor {
    pub fn new(eta: Vec3, k: Vec3) -> Conductor {
        Conductor {
            eta,
            k,
            average: fresnel::conductor_average(eta, k),
        }
    }
}

impl Default for Material {
    fn default() -> Self {
        Material {
            diffuse: Vec3::splat(0.8),
            specular: Vec3::ZERO,
            roughness: 0.0,
            fresnel: false,
            transmission: Vec3::ZERO,
            ior: 1.5,
            emission: Vec3::ZERO,
            two_sided: false,
            distribution: Distribution::Ggx,
            coating: None,
            conductor: None,
            rough_glass: false,
            thin: None,
            one_sided: false,
        }
    }
}

/// Which lobe produced a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lobe {
    Diffuse,
    Glossy,
    Mirror,
    GlassReflect,
    GlassRefract,
    /// Refraction through rough glass (non-delta).
    RoughRefract,
}

impl Lobe {
    /// Delta lobes can't be evaluated or reached by next-event estimation.
    pub fn is_delta(self) -> bool {
        matches!(self, Lobe::Mirror | Lobe::GlassReflect | Lobe::GlassRefract)
    }
    /// Whether the sampled direction crosses the surface (the other side of the geometry).
    pub fn crosses(self) -> bool {
        matches!(self, Lobe::GlassRefract | Lobe::RoughRefract)
    }
}

/// A sampled scattering direction.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// The new direction, local frame.
    pub wi: Vec3,
    /// `f·|cos θi| / pdf`, or the delta lobe's weight.
    pub weight: Vec3,
    /// Density of `wi` over solid angle for non-delta lobes (all non-delta lobes combined);
    /// the discrete probability of the lobe for delta ones.
    pub pdf: f32,
    pub lobe: Lobe,
}

fn avg(v: Vec3) -> f32 {
    (v.x + v.y + v.z) / 3.0
}

impl Material {
    pub fn alpha(&self) -> f32 {
        self.roughness * self.roughness
    }
    pub fn is_mirror(&self) -> bool {
        self.roughness < MIRROR_ROUGHNESS
    }
    /// ρL/π when [`Material::eval`] is that constant for every pair of directions on one
    /// side of the surface (and 0 across it): no specular lobe and no Fresnel coupling of
    /// the diffuse lobe.
    pub fn lambertian(&self) -> Option<Vec3> {
        (!self.has_specular() && !self.fresnel && self.coating.is_none() && !self.rough_glass)
            .then(|| self.diffuse * FRAC_1_PI)
    }

    /// Whether the rough lobes mask with Mitsuba's separable Smith G (its conductors and
    /// coatings) rather than the uber's height-correlated one.
    fn separable_masking(&self) -> bool {
        self.conductor.is_some() || self.coating.is_some()
    }

    /// The uber material that the GPU passes shade in place of this one (they carry the
    /// uber's parameters only): itself for uber materials; for a coating, Schlick's
    /// Fresnel of its index and the diffuse albedo of the same cosine-weighted mean
    /// ([`coated`]); for a conductor, Schlick's Fresnel from its exact normal-incidence
    /// reflectance; Beckmann's roughness as GGX's.
    pub fn uber_equivalent(&self) -> Material {
        let mut m = if let Some(c) = &self.coating {
            coated::uber_equivalent(self, c)
        } else if let Some(c) = &self.conductor {
            Material {
                specular: self.specular * fresnel::conductor(1.0, c.eta, c.k),
                fresnel: true,
                conductor: None,
                ..*self
            }
        } else if self.rough_glass {
            // Smooth glass of the same index and transmittance: the reflection's Fresnel
            // term is the glass lobe's own (the uber's specular lobe stays off).
            Material {
                specular: Vec3::ZERO,
                roughness: 0.0,
                rough_glass: false,
                ..*self
            }
        } else if self.thin.is_some() {
            // A thin slab: glass of index 1 passes light straight through (its reflection
            // is left out where a GPU pass samples the stand-in: the first scatter of the
            // bounce maps).
            Material {
                ior: 1.0,
                thin: None,
                ..*self
            }
        } else {
            *self
        };
        m.distribution = Distribution::Ggx;
        m
    }
    /// Diffuse reflection alone (no specular or glass lobe, a non-black albedo): what most
    /// surfaces of most scenes are. `sample`, `eval` and `pdf` then take a short path that
    /// gives bit for bit what the general one gives for these materials (the lobe
    /// probabilities are exactly [0, 1, 0] and the Fresnel coupling exactly 1; tested).
    #[inline]
    pub fn is_lambertian(&self) -> bool {
        self.lambertian().is_some() && !self.has_transmission() && self.diffuse.max_element() > 0.0
    }

    /// [`Material::sample`] for [`Material::is_lambertian`] materials: the same draws (the
    /// lobe choice's, unused, then the direction's) and the same arithmetic.
    #[inline]
    fn sample_lambertian(&self, sign: f32, rng: &mut Rng) -> Option<BsdfSample> {
        let _lobe_choice = rng.next_f32();
        let wi_up = cosine_hemisphere(rng.next_2d());
        if wi_up.z <= 0.0 {
            return None;
        }
        let pdf = wi_up.z * FRAC_1_PI;
        Some(BsdfSample {
            wi: wi_up * sign,
            weight: self.diffuse * FRAC_1_PI * wi_up.z / pdf,
            pdf,
            lobe: Lobe::Diffuse,
        })
    }

    pub fn has_specular(&self) -> bool {
        self.specular.max_element() > 0.0
    }
    /// Whether the material has the uber's smooth (delta) glass lobe.
    pub fn has_transmission(&self) -> bool {
        self.transmission.max_element() > 0.0 && !self.rough_glass
    }
    /// True when the material can scatter into a delta lobe (perfect mirror or smooth
    /// glass): what a rasterizer that shades the first surface cannot give.
    pub fn has_delta_lobe(&self) -> bool {
        (self.has_specular() && self.is_mirror()) || self.has_transmission()
    }

    /// Whether camera paths and photons are traced through it on the CPU where the GPU
    /// passes cannot shade it: a delta lobe, or rough glass (whose light arrives through
    /// the glass; the GPU passes see its smooth stand-in, [`Material::uber_equivalent`],
    /// which they leave black as they leave smooth glass).
    pub fn is_specular_traced(&self) -> bool {
        self.has_delta_lobe() || self.rough_glass
    }

    /// True when every lobe is a delta lobe (nothing for next-event estimation to evaluate).
    pub fn is_purely_specular(&self) -> bool {
        !self.rough_glass
            && self.diffuse.max_element() <= 0.0
            && (!self.has_specular() || self.is_mirror())
    }

    /// Whether photons arriving here are stored: the surface has a non-delta lobe that a
    /// density estimate can shade. Rough glass has none such: every camera path follows it
    /// by sampling its lobes (its light arrives through the glass, which no density
    /// estimate on its surface resolves), and its photons, stored on the inside of the
    /// glass with normals facing in, would count at the nearby floor beneath a sphere whose
    /// normal agrees (`photon` 2× too bright in front of the roughdielectric sphere).
    pub fn stores_photons(&self) -> bool {
        !self.is_purely_specular() && !self.rough_glass
    }

    /// The material that a ray travelling along `dir` meets on a surface whose winding's
    /// side is `n` (geometric or shading normal on that side): itself, or for a
    /// [`Material::one_sided`] material met from behind (`dir` along `n`) one that reflects
    /// and transmits nothing (Mitsuba's one-sided BSDFs are black seen or lit from behind),
    /// with its emission.
    pub fn seen_from(&self, n: Vec3, dir: Vec3) -> Material {
        if self.one_sided && dir.dot(n) > 0.0 {
            self.back()
        } else {
            *self
        }
    }

    /// A [`Material::one_sided`] material's back: no lobe, the same emission (its own uber
    /// equivalent, so no pass shades an exact model there).
    pub fn back(&self) -> Material {
        Material {
            diffuse: Vec3::ZERO,
            specular: Vec3::ZERO,
            // Schlick's term of a zero F0 still rises at grazing angles.
            fresnel: false,
            transmission: Vec3::ZERO,
            coating: None,
            conductor: None,
            rough_glass: false,
            thin: None,
            distribution: Distribution::Ggx,
            ..*self
        }
    }

    /// Whether the surface emits light.
    pub fn emits(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    /// Radiance emitted towards `wo` (pointing away from the surface) by a surface of
    /// geometric normal `ng`: `emission` on the front side (or both, when two-sided).
    pub fn emitted(&self, ng: Vec3, wo: Vec3) -> Vec3 {
        if self.two_sided || ng.dot(wo) > 0.0 {
            self.emission
        } else {
            Vec3::ZERO
        }
    }

    /// Specular Fresnel term F_s(cos).
    pub fn fresnel_spec(&self, cos: f32) -> Vec3 {
        if let Some(c) = &self.conductor {
            return self.specular * fresnel::conductor(cos, c.eta, c.k);
        }
        if self.fresnel {
            fresnel::schlick(self.specular, cos)
        } else {
            self.specular
        }
    }

    fn fresnel_avg(&self) -> Vec3 {
        if let Some(c) = &self.conductor {
            return self.specular * c.average;
        }
        if self.fresnel {
            fresnel::schlick_average(self.specular)
        } else {
            self.specular
        }
    }

    /// Probabilities of choosing (specular, diffuse, glass) given the viewing cosine.
    fn lobe_probabilities(&self, cos_o: f32) -> [f32; 3] {
        let f = self.fresnel_spec(cos_o);
        let ws = avg(f);
        let wd = avg((Vec3::ONE - f) * self.diffuse);
        let wg = avg((Vec3::ONE - f) * self.transmission);
        let total = ws + wd + wg;
        if total <= 0.0 {
            return [0.0; 3];
        }
        [ws / total, wd / total, wg / total]
    }

    /// The non-delta part of the BSDF, f(wo, wi). Two-sided: evaluated in the hemisphere of `wo`.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if self.rough_glass {
            return rough_dielectric::eval(self, wo, wi);
        }
        if wo.z * wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        if self.is_lambertian() {
            return self.diffuse * FRAC_1_PI;
        }
        self.eval_general(wo, wi)
    }

    /// [`Material::eval`] for every material, `wo` and `wi` on one side.
    fn eval_general(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let (wo, wi) = if wo.z < 0.0 { (-wo, -wi) } else { (wo, wi) };
        if let Some(c) = &self.coating {
            return coated::eval(self, c, wo, wi);
        }
        let mut f = Vec3::ZERO;
        let one_minus_avg = Vec3::ONE - self.fresnel_avg();
        if self.diffuse.max_element() > 0.0 {
            let num = (Vec3::ONE - self.fresnel_spec(wo.z)) * (Vec3::ONE - self.fresnel_spec(wi.z));
            let coupling = Vec3::select(
                one_minus_avg.cmpgt(Vec3::splat(1e-6)),
                num / one_minus_avg,
                Vec3::ZERO,
            );
            f += self.diffuse * FRAC_1_PI * coupling;
        }
        if self.has_specular() && !self.is_mirror() {
            let h = (wo + wi).normalize();
            let (alpha, dist) = (self.alpha(), self.distribution);
            let g = if self.separable_masking() {
                microfacet::g_separable(wo, wi, alpha, dist)
            } else {
                microfacet::g2(wo, wi, alpha, dist)
            };
            let dg = microfacet::d(h, alpha, dist) * g / (4.0 * wo.z * wi.z);
            f += self.fresnel_spec(wi.dot(h)) * dg;
        }
        f
    }

    /// Density of [`Material::sample`] producing the non-delta direction `wi`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if self.rough_glass {
            return rough_dielectric::pdf(self, wo, wi);
        }
        if wo.z * wi.z <= 0.0 {
            return 0.0;
        }
        if self.is_lambertian() {
            return wi.z.abs() * FRAC_1_PI;
        }
        self.pdf_general(wo, wi)
    }

    /// [`Material::pdf`] for every material, `wo` and `wi` on one side.
    fn pdf_general(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (wo, wi) = if wo.z < 0.0 { (-wo, -wi) } else { (wo, wi) };
        if let Some(c) = &self.coating {
            return coated::pdf(self, c, wo, wi);
        }
        let [ps, pd, _] = self.lobe_probabilities(wo.z);
        let mut pdf = pd * wi.z * FRAC_1_PI;
        if !self.is_mirror() && ps > 0.0 {
            let h = (wo + wi).normalize();
            pdf += ps * microfacet::pdf_reflected(wo, h, self.alpha(), self.distribution);
        }
        pdf
    }

    /// Importance-samples a direction. `None` when the sample is absorbed (no lobe has any
    /// energy, or a GGX sample fell below the horizon).
    pub fn sample(&self, wo: Vec3, rng: &mut Rng) -> Option<BsdfSample> {
        if self.rough_glass {
            return rough_dielectric::sample(self, wo, rng);
        }
        let flip = wo.z < 0.0;
        let sign = if flip { -1.0 } else { 1.0 };
        if self.is_lambertian() {
            return self.sample_lambertian(sign, rng);
        }
        self.sample_general(wo, sign, rng)
    }

    /// [`Material::sample`] for a particle carried from the light (photons, light
    /// subpaths): `wo` points back along the particle's path and the weight is the adjoint
    /// BSDF's, `f(wi, wo)·|cos θi|/pdf`. It differs from [`Material::sample`]'s only through
    /// rough glass (the η'² of [`rough_dielectric::importance_factor`]); the uber's smooth
    /// glass weighs both transports alike (radiance carried as L/η² inside the glass).
    pub fn sample_adjoint(&self, wo: Vec3, rng: &mut Rng) -> Option<BsdfSample> {
        let mut s = self.sample(wo, rng)?;
        if self.rough_glass {
            s.weight *= rough_dielectric::importance_factor(self, wo, s.wi);
        }
        Some(s)
    }

    /// [`Material::sample`] for every material.
    fn sample_general(&self, wo: Vec3, sign: f32, rng: &mut Rng) -> Option<BsdfSample> {
        let flip = sign < 0.0;
        let wo_up = wo * sign;
        if let Some(c) = &self.coating {
            return coated::sample(self, c, wo_up, sign, rng);
        }
        let [ps, pd, pg] = self.lobe_probabilities(wo_up.z);
        let u = rng.next_f32();
        let u2 = rng.next_2d();
        if u < ps + pd {
            if u < ps && self.is_mirror() {
                let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                let weight = self.fresnel_spec(wo_up.z) / ps;
                return Some(BsdfSample {
                    wi,
                    weight,
                    pdf: ps,
                    lobe: Lobe::Mirror,
                });
            }
            let (wi_up, lobe) = if u < ps {
                let h = microfacet::sample_h(u2, self.alpha(), self.distribution);
                let wi = 2.0 * wo_up.dot(h) * h - wo_up;
                (wi, Lobe::Glossy)
            } else {
                (cosine_hemisphere(u2), Lobe::Diffuse)
            };
            if wi_up.z <= 0.0 {
                return None;
            }
            let wi = wi_up * sign;
            let pdf = self.pdf(wo, wi);
            if pdf <= 0.0 {
                return None;
            }
            let weight = self.eval(wo, wi) * wi_up.z / pdf;
            return Some(BsdfSample {
                wi,
                weight,
                pdf,
                lobe,
            });
        }
        if pg <= 0.0 {
            return None;
        }
        if let Some(reflection) = self.thin {
            return Some(self.sample_thin(wo, reflection, pg, u2.x));
        }
        // Smooth glass: the geometric side decides whether we enter or leave.
        let tint = self.transmission * (Vec3::ONE - self.fresnel_spec(wo_up.z)) / pg;
        let eta = if flip { 1.0 / self.ior } else { self.ior };
        let (fr, cos_t) = fresnel::dielectric(wo_up.z, eta);
        if u2.x < fr {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            Some(BsdfSample {
                wi,
                weight: tint,
                pdf: pg * fr,
                lobe: Lobe::GlassReflect,
            })
        } else {
            // Refract: wi = -wo/eta + (cos_i/eta - cos_t) n, on the other side.
            let wt_up = -wo_up / eta + (wo_up.z / eta - cos_t) * Vec3::Z;
            let wi = (wt_up * sign).normalize();
            Some(BsdfSample {
                wi,
                weight: tint,
                pdf: pg * (1.0 - fr),
                lobe: Lobe::GlassRefract,
            })
        }
    }

    /// The thin slab's lobes ([`Material::thin`]), picked with probability `pg` (the glass
    /// lobe's): reflection with probability R' (`u` below it), else straight through.
    fn sample_thin(&self, wo: Vec3, reflection: Vec3, pg: f32, u: f32) -> BsdfSample {
        let r = thin_reflectance(wo.z, self.ior);
        if u < r {
            BsdfSample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: reflection / pg,
                pdf: pg * r,
                lobe: Lobe::GlassReflect,
            }
        } else {
            BsdfSample {
                wi: -wo,
                weight: self.transmission / pg,
                pdf: pg * (1.0 - r),
                lobe: Lobe::GlassRefract,
            }
        }
    }

    /// Every delta lobe `sample` can pick for `wo` (local frame), each with its expected
    /// weight: `pdf` is the probability that `sample` picks it and `weight` the mean of the
    /// sample weights it returns for it times that probability, so following every lobe
    /// with its `weight` (splitting) has the expectation of one `sample` call restricted
    /// to the delta lobes. Lobes of zero weight are left out.
    pub fn delta_lobes(&self, wo: Vec3) -> impl Iterator<Item = BsdfSample> {
        let flip = wo.z < 0.0;
        let sign = if flip { -1.0 } else { 1.0 };
        let wo_up = wo * sign;
        let coated = self
            .coating
            .and_then(|c| coated::delta_lobe(self, &c, wo_up, sign));
        let [ps, _, pg] = if self.coating.is_some() || self.rough_glass {
            [0.0; 3]
        } else {
            self.lobe_probabilities(wo_up.z)
        };
        let mirror_dir = Vec3::new(-wo.x, -wo.y, wo.z);
        let f = self.fresnel_spec(wo_up.z);
        let mirror = (ps > 0.0 && self.is_mirror()).then_some(BsdfSample {
            wi: mirror_dir,
            weight: f,
            pdf: ps,
            lobe: Lobe::Mirror,
        });
        let (mut reflect, mut refract) = (None, None);
        if let Some(reflection) = self.thin.filter(|_| pg > 0.0) {
            let r = thin_reflectance(wo.z, self.ior);
            reflect = Some(BsdfSample {
                weight: reflection * r,
                ..self.sample_thin(wo, reflection, pg, 0.0)
            });
            refract = Some(BsdfSample {
                weight: self.transmission * (1.0 - r),
                ..self.sample_thin(wo, reflection, pg, 1.0)
            });
        } else if pg > 0.0 {
            let tint = self.transmission * (Vec3::ONE - f);
            let eta = if flip { 1.0 / self.ior } else { self.ior };
            let (fr, cos_t) = fresnel::dielectric(wo_up.z, eta);
            if fr > 0.0 {
                reflect = Some(BsdfSample {
                    wi: mirror_dir,
                    weight: tint * fr,
                    pdf: pg * fr,
                    lobe: Lobe::GlassReflect,
                });
            }
            if fr < 1.0 {
                let wt_up = -wo_up / eta + (wo_up.z / eta - cos_t) * Vec3::Z;
                refract = Some(BsdfSample {
                    wi: (wt_up * sign).normalize(),
                    weight: tint * (1.0 - fr),
                    pdf: pg * (1.0 - fr),
                    lobe: Lobe::GlassRefract,
                });
            }
        }
        [coated, mirror, reflect, refract]
            .into_iter()
            .flatten()
            .filter(|s| s.weight.max_element() > 0.0)
    }

    /// The scatter probability ρs = ∫ f cos dωi for viewing direction `wo` (exact for the
    /// diffuse, mirror and glass lobes; the GGX lobe's is bounded by its Fresnel term).
    pub fn scatter_probability(&self, wo: Vec3) -> Vec3 {
        if self.rough_glass {
            return rough_dielectric::scatter_probability(self, wo);
        }
        if let Some(c) = &self.coating {
            return coated::scatter_probability(self, c, wo.z.abs());
        }
        if let Some(reflection) = self.thin {
            let r = thin_reflectance(wo.z, self.ior);
            return reflection * r + self.transmission * (1.0 - r);
        }
        let f = self.fresnel_spec(wo.z.abs());
        f + (Vec3::ONE - f) * (self.diffuse + self.transmission)
    }
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_models;
#[cfg(test)]
mod tests_rough_dielectric;
