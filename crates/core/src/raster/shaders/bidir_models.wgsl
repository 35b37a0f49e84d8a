// Mitsuba's exact material models in `bidir`'s lighting pass (issue 42): every vertex the
// pass shades names a `ModelMaterial` record (group 1, binding 5 of the direct passes,
// raster/exact_models.rs; index + 1, 0 where the uber parameters are exact or a texture
// varies them): the pixel x3 by its G-buffer sample's material index (`emission.w`), the
// VPLs x1 and the light subpaths' vertices by their records' material word
// (`VplRaw::fresnel`'s bits 1…, `raster::exact_models::material_word`), the ray bundles'
// hits x2 by their nodes' `m3` high half (bits 1…, bundles.wgsl). Each is shaded by
// models.wgsl's `model_diffuse` + `model_glossy` in place of the uber stand-in it carries.
//
// Compile time (lavapipe inlines every call): the model code is reached from few call
// sites. Both BSDFs of a connection (a VPL's and its receiver's, a bundle hit's and the
// pixel's) go through `pair_f`, whose loop over the two vertices has a trip count the
// compiler cannot see (so it is not unrolled: one copy of the model code per `pair_f` call);
// the clamp's energy factor is taken there too (`eval_clamped_model`), not where the clamp
// is decided (`clamped_model`, which reads one word of the record).
//
// The roughness clamp (§5, roughness_clamp.wgsl) widens a model's glossy lobe to the
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

// The directional albedo of record `r`'s glossy lobe at roughness `roughness` seen at
// cosine `mu`, per channel, by the split sum (up to the specular tint, which the clamp's
// ratio cancels; Schlick's F of the uber lobe keeps it: F0 = its specular colour).
fn model_lobe_energy(r: ModelMaterial, roughness: f32, mu: f32) -> vec3<f32> {
    let t = select(0u, 2u, has_flag(r, MODEL_BECKMANN));
    let a = model_energy_table(t, roughness, mu);
    let b = model_energy_table(t + 1u, roughness, mu);
    if has_flag(r, MODEL_COATED) {
        return vec3<f32>(fresnel_dielectric(1.0, r.coat_eta).x * a + b);
    }
    if has_flag(r, MODEL_CONDUCTOR) {
        return fresnel_conductor(1.0, r.conductor_eta, r.conductor_k) * a + b;
    }
    if has_flag(r, MODEL_FRESNEL) {
        return r.specular * a + b;
    }
    return vec3<f32>(a + b);
}

// Loads the record of a G-buffer sample's material (its `emission.w`: index + 1) for the
// pixel's `exact_*` functions (the sky's light), `diffuse` the sample's stand-in albedo
// (a diffuse map's texel: `model_textured`); returns the record's index + 1 where it is
// shaded exactly, 0 elsewhere.
fn pixel_model(index: f32, diffuse: vec3<f32>) -> u32 {
    if !MODELS {
        return 0u;
    }
    exact_load(index, diffuse);
    return select(0u, u32(index + 0.5), exact_on);
}

// The record index + 1 of a VPL record's or bundle node's material word (the Fresnel flag
// in bit 0, the record's index + 1 above it) where that record is shaded exactly, 0 else.
fn word_model(word: u32) -> u32 {
    let i = word >> 1u;
    if !MODELS || i == 0u || i > arrayLength(&model_materials) {
        return 0u;
    }
    return select(0u, i, (model_materials[i - 1u].flags & EXACT_MODEL_FLAGS) != 0u);
}

// `clamped` (roughness_clamp.wgsl) for the material `m` whose exact model is record
// `model` (index + 1; 0: `m` itself): the model's roughness raised as the uber lobe's would
// be (its energy factor: `eval_clamped_model`).
fn clamped_model(m_in: Material, model: u32, dhat: f32, cos_o: f32) -> Clamped {
    if !MODELS || model == 0u {
        return clamped(m_in, dhat, cos_o);
    }
    var m = m_in;
    m.roughness = model_materials[model - 1u].roughness;
    var c = clamped(m, dhat, cos_o);
    c.model = model;
    c.mu = abs(cos_o);
    return c;
}

// `unclamped` for the material `m` whose exact model is record `model` (0: `m` itself).
fn unclamped_model(m: Material, model: u32) -> Clamped {
    var c = unclamped(m);
    if MODELS && model != 0u {
        c.m.roughness = model_materials[model - 1u].roughness;
        c.model = model;
    }
    return c;
}

// f(wo, wi) of a clamped model: its diffuse part as is (a coating's base under the coating
// of its own roughness), its glossy lobe at the widened roughness times the model's own
// E(α, μ)/E(α', μ).
// The record's diffuse map texel is the vertex's stand-in albedo over the record's
// (`model_textured`: the G-buffer's, the RSM's and the VPL records' are the stand-in's
// times the texel, `raster::exact_models::record_stand_in`).
fn eval_clamped_model(c: Clamped, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    var r = model_textured(model_materials[c.model - 1u], c.m.diffuse);
    var km = vec3<f32>(1.0);
    if c.m.roughness > r.roughness {
        let widened = model_lobe_energy(r, c.m.roughness, c.mu);
        km = model_lobe_energy(r, r.roughness, c.mu) / max(widened, vec3<f32>(1e-3));
    }
    let fd = model_diffuse(r, n, wo, wi);
    r.roughness = c.m.roughness;
    return fd + km * model_glossy(r, n, wo, wi);
}

// 2, in a form the compiler cannot fold (`params.mode` is 0, 1 or 2): `pair_f`'s trip
// count, so that its loop is kept and its body (the model code) compiled once.
fn two_opaque() -> u32 {
    return 2u + (params.mode >> 16u);
}

// f_a(wo_a, wi_a)·f_b(wo_b, wi_b): the BSDFs of both vertices of a connection (each an uber
// material or a model: `eval_clamped`), evaluated by one call site of `eval_clamped`.
fn pair_f(a: Clamped, na: vec3<f32>, woa: vec3<f32>, wia: vec3<f32>, b: Clamped, nb: vec3<f32>, wob: vec3<f32>, wib: vec3<f32>) -> vec3<f32> {
    if !MODELS {
        return eval_clamped(a, na, woa, wia) * eval_clamped(b, nb, wob, wib);
    }
    var f = vec3<f32>(1.0);
    for (var s = 0u; s < two_opaque(); s++) {
        var c = a;
        var n = na;
        var wo = woa;
        var wi = wia;
        if s == 1u {
            c = b;
            n = nb;
            wo = wob;
            wi = wib;
        }
        f *= eval_clamped(c, n, wo, wi);
        if s == 0u && max3(f) <= 0.0 {
            break;
        }
    }
    return f;
}

// The diffuse lobe at the pixel (the sky's control variate): the model's where exact.
fn pixel_diffuse(m: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if MODELS && exact_on {
        return model_diffuse(exact_model, n, wo, wi);
    }
    return diffuse_lobe(m, n, wo, wi);
}
