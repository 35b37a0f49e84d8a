// Mitsuba's exact material models in `bidir`'s lighting pass (issue 42) at the pixel x3:
// its G-buffer sample's material index (`emission.w`) names a `ModelMaterial` record
// (group 1, binding 5 of the direct passes, raster/exact_models.rs; flags 0 where the uber
// parameters are exact or a texture varies them), loaded once a pixel (exact_models.wgsl
// `exact_load`), and the pixel's BSDF in the VPLs' light, the bundles' connections and the
// sky's light is models.wgsl's `model_diffuse` + `model_glossy` in place of the uber
// stand-in the G-buffer holds. The VPLs x1 and the bundles' hits x2 still shade the uber
// stand-in (their light reaches the camera through another surface; branch
// `bidirexact-vplwip` names their models too, but lavapipe then took minutes to compile the
// pass).
//
// The roughness clamp (§5, roughness_clamp.wgsl) widens the pixel model's glossy lobe to the
// same roughness as the uber one's and scales it by the model's own E(α, μ)/E(α', μ) per
// channel, E the lobe's directional albedo with its Fresnel term: the uber's GGX_ENERGY
// table (height-correlated GGX, F = 1) does not fit Mitsuba's separable masking, Beckmann's
// distribution nor a dielectric coating's Fresnel term (up to 64% off at grazing angles,
// `scripts/data/model_energy_tables.py --check`). E is the split sum F0·A + B of a
// Schlick-shaped Fresnel term (tables of A and B per distribution, separable masking), F0
// the model's own reflectance at normal incidence (a conductor's complex-index one, a
// coating's dielectric one).
// Bias, stated: as the uber clamp's, the widened lobe blurs glossy reflections; its albedo
// is kept up to the Fresnel curve's departure from Schlick's shape (k within 13% of the
// exact ratio for a coating of index 1.5 at μ = 0.2 and clamps up to α 0.1 → 0.5, within
// 4% for Cu, Au and Al; exact at F = 1), the tables' bilinear interpolation, and, for an
// uber lobe with Beckmann's distribution (height-correlated masking), the separable
// table's masking.

// Whether the pass shades exact models at all (raster/vpl.rs: off where no scene material
// is one; the code is then left out of the pass).
override MODELS: bool = true;

// A, B of the split sum at roughness r = √α = i/15 (rows) and μ = cos θo = (j + 0.5)/16
// (columns): GGX's A, GGX's B, Beckmann's A, Beckmann's B, 256 entries each
// (raster/model_energy.rs, `scripts/data/model_energy_tables.py`; a storage buffer, not a
// private array: a private array is copied per invocation).
@group(0) @binding(13) var<storage, read> model_energy: array<f32>;

// Bilinear lookup of table `t` (0: GGX A, 1: GGX B, 2: Beckmann A, 3: Beckmann B).
fn model_energy_table(t: u32, roughness: f32, mu: f32) -> f32 {
    let e = energy_tap(roughness, mu);
    let k = t * 256u + e.k;
    let a = mix(model_energy[k], model_energy[k + 1u], e.fy);
    let b = mix(model_energy[k + 16u], model_energy[k + 17u], e.fy);
    return mix(a, b, e.fx);
}

// The directional albedo of the pixel model's glossy lobe at roughness `roughness` seen at
// cosine `mu`, per channel, by the split sum (up to the specular tint, which the clamp's
// ratio cancels; Schlick's F of the uber lobe keeps it: F0 = its specular colour).
fn model_lobe_energy(roughness: f32, mu: f32) -> vec3<f32> {
    let t = select(0u, 2u, has_flag(exact_model, MODEL_BECKMANN));
    let a = model_energy_table(t, roughness, mu);
    let b = model_energy_table(t + 1u, roughness, mu);
    if has_flag(exact_model, MODEL_COATED) {
        return vec3<f32>(fresnel_dielectric(1.0, exact_model.coat_eta).x * a + b);
    }
    if has_flag(exact_model, MODEL_CONDUCTOR) {
        return fresnel_conductor(1.0, exact_model.conductor_eta, exact_model.conductor_k) * a + b;
    }
    if has_flag(exact_model, MODEL_FRESNEL) {
        return exact_model.specular * a + b;
    }
    return vec3<f32>(a + b);
}

// Loads the record of a G-buffer sample's material (its `emission.w`: index + 1) for the
// `exact_*` functions and `clamped_model`; 1 where it is shaded exactly, 0 elsewhere.
fn pixel_model(index: f32) -> u32 {
    if !MODELS {
        return 0u;
    }
    exact_load(index);
    return select(0u, 1u, exact_on);
}

// `clamped` (roughness_clamp.wgsl) for the pixel's material `m` (`model` 1 where its exact
// model is loaded, 0: `m` itself): the model's roughness raised as the uber lobe's would be,
// and its own energy factor.
fn clamped_model(m_in: Material, model: u32, dhat: f32, cos_o: f32) -> Clamped {
    if !MODELS || model == 0u {
        return clamped(m_in, dhat, cos_o);
    }
    var m = m_in;
    m.roughness = exact_model.roughness;
    var c = clamped(m, dhat, cos_o);
    c.model = model;
    if c.m.roughness > exact_model.roughness {
        let mu = abs(cos_o);
        let widened = model_lobe_energy(c.m.roughness, mu);
        c.km = model_lobe_energy(exact_model.roughness, mu) / max(widened, vec3<f32>(1e-3));
    }
    return c;
}

// f(wo, wi) of the pixel's clamped model: its diffuse part as is (a coating's base under
// the coating of its own roughness), its glossy lobe at the widened roughness times `km`.
fn eval_clamped_model(c: Clamped, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let fd = model_diffuse(exact_model, n, wo, wi);
    var g = exact_model;
    g.roughness = c.m.roughness;
    return fd + c.km * model_glossy(g, n, wo, wi);
}

// The diffuse lobe at the pixel (the sky's control variate): the model's where exact.
fn pixel_diffuse(m: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if MODELS && exact_on {
        return model_diffuse(exact_model, n, wo, wi);
    }
    return diffuse_lobe(m, n, wo, wi);
}
