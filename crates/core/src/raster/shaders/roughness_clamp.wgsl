// Roughness clamping of `bidir` (Tokuyoshi & Ogaki 2012 §5), energy-kept (issue 48): the
// GGX α of the BSDF at a path vertex is raised so that the distribution's peak stays under
// what the samples' density d̂ there resolves, and the widened lobe is scaled by
// E(α, μ)/E(α', μ) (E: the lobe's directional albedo with F = 1, `GGX_ENERGY`), so that it
// reflects as much light as the lobe it replaces. Before, the widened lobe lost what GGX
// loses to its shadowing term at large α: bidir's rough conductor spheres (α 0.2, the sky
// reflected through the bundles, whose d̂ raised α to 1) were 14–19% dark.
//
// Bias, stated: the clamp blurs glossy reflections (the lobe's shape changes); the albedo
// is kept up to Fresnel (E is taken at F = 1; with Schlick's F the ratio holds at F0 = 1
// and is within a few percent below) and the table's bilinear interpolation.

// A material with its specular lobe widened (`m`) and the factor `k` on that lobe; where the
// material is one of Mitsuba's models (`model`: its record's index + 1, 0 for the uber `m`),
// the model's lobe widened to the same roughness, its own factor per channel taken where it
// is evaluated at the cosine `mu` (bidir_models.wgsl `eval_clamped_model`).
struct Clamped {
    m: Material,
    k: f32,
    model: u32,
    mu: f32,
}

// E(α, μ) at roughness r = √α = i/15 (rows) and μ = cos θo = (j + 0.5)/16 (columns), from
// `scripts/data/ggx_energy_table.py`.
var<private> GGX_ENERGY: array<f32, 256> = array<f32, 256>(
    1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000,
    0.9865, 0.9984, 0.9994, 0.9996, 0.9999, 0.9999, 0.9999, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000, 1.0000,
    0.9001, 0.9767, 0.9913, 0.9955, 0.9972, 0.9981, 0.9986, 0.9989, 0.9992, 0.9993, 0.9994, 0.9995, 0.9997, 0.9999, 1.0000, 1.0000,
    0.8883, 0.9209, 0.9603, 0.9780, 0.9864, 0.9908, 0.9933, 0.9949, 0.9960, 0.9968, 0.9973, 0.9978, 0.9980, 0.9983, 0.9985, 0.9984,
    0.9122, 0.8853, 0.9144, 0.9419, 0.9600, 0.9715, 0.9788, 0.9836, 0.9868, 0.9891, 0.9907, 0.9917, 0.9921, 0.9927, 0.9936, 0.9943,
    0.9311, 0.8829, 0.8840, 0.9023, 0.9219, 0.9381, 0.9503, 0.9592, 0.9654, 0.9699, 0.9743, 0.9777, 0.9802, 0.9818, 0.9836, 0.9848,
    0.9424, 0.8916, 0.8727, 0.8738, 0.8839, 0.8965, 0.9085, 0.9208, 0.9314, 0.9398, 0.9464, 0.9522, 0.9568, 0.9607, 0.9639, 0.9665,
    0.9480, 0.8980, 0.8679, 0.8540, 0.8510, 0.8565, 0.8663, 0.8765, 0.8864, 0.8962, 0.9049, 0.9127, 0.9195, 0.9254, 0.9306, 0.9351,
    0.9493, 0.8977, 0.8603, 0.8359, 0.8254, 0.8227, 0.8241, 0.8293, 0.8360, 0.8438, 0.8518, 0.8597, 0.8673, 0.8744, 0.8811, 0.8871,
    0.9473, 0.8907, 0.8468, 0.8182, 0.8005, 0.7891, 0.7835, 0.7818, 0.7830, 0.7863, 0.7910, 0.7965, 0.8025, 0.8088, 0.8152, 0.8215,
    0.9427, 0.8779, 0.8282, 0.7963, 0.7716, 0.7540, 0.7416, 0.7334, 0.7283, 0.7259, 0.7255, 0.7267, 0.7290, 0.7323, 0.7362, 0.7406,
    0.9360, 0.8604, 0.8073, 0.7685, 0.7387, 0.7153, 0.6970, 0.6828, 0.6718, 0.6636, 0.6576, 0.6535, 0.6509, 0.6497, 0.6495, 0.6501,
    0.9276, 0.8396, 0.7814, 0.7367, 0.7014, 0.6727, 0.6492, 0.6297, 0.6135, 0.6000, 0.5888, 0.5795, 0.5719, 0.5657, 0.5607, 0.5568,
    0.9177, 0.8169, 0.7518, 0.7012, 0.6606, 0.6270, 0.5988, 0.5748, 0.5541, 0.5362, 0.5206, 0.5069, 0.4949, 0.4843, 0.4750, 0.4668,
    0.9065, 0.7943, 0.7204, 0.6634, 0.6176, 0.5795, 0.5471, 0.5193, 0.4950, 0.4736, 0.4546, 0.4376, 0.4224, 0.4086, 0.3961, 0.3847,
    0.8943, 0.7699, 0.6872, 0.6243, 0.5735, 0.5314, 0.4956, 0.4646, 0.4376, 0.4137, 0.3925, 0.3734, 0.3561, 0.3404, 0.3261, 0.3130
);

// The bilinear tap of a 16×16 energy table (rows: roughness i/15, columns: μ = (j + 0.5)/16)
// at (`roughness`, `mu`): the entry of its lower corner and the weights towards the next
// row and column.
struct EnergyTap {
    k: u32,
    fx: f32,
    fy: f32,
}

fn energy_tap(roughness: f32, mu: f32) -> EnergyTap {
    let x = clamp(roughness, 0.0, 1.0) * 15.0;
    let y = clamp(mu * 16.0 - 0.5, 0.0, 15.0);
    let i = min(u32(x), 14u);
    let j = min(u32(y), 14u);
    return EnergyTap(i * 16u + j, x - f32(i), y - f32(j));
}

fn ggx_energy(roughness: f32, mu: f32) -> f32 {
    let t = energy_tap(roughness, mu);
    let a = mix(GGX_ENERGY[t.k], GGX_ENERGY[t.k + 1u], t.fy);
    let b = mix(GGX_ENERGY[t.k + 16u], GGX_ENERGY[t.k + 17u], t.fy);
    return mix(a, b, t.fx);
}

// `m` unchanged.
fn unclamped(m: Material) -> Clamped {
    return Clamped(m, 1.0, 0u, 1.0);
}

// §5: the material with its GGX α raised to √(m/(π·d̂)) (no change when off), where
// m = m'·f·cos/D with m' = 16: for the GGX lobe f·cos θi/D = F·G2/(4 cos θo), taken with
// G2 ≈ 1 and the mean Fresnel reflectance; `cos_o`: the cosine on the side the light leaves.
// The widened lobe keeps the albedo of the original one (its factor `k`).
fn clamped(m_in: Material, dhat: f32, cos_o: f32) -> Clamped {
    var m = m_in;
    // A mirror's delta lobe stays one (nothing here): its paths are traced on the CPU
    // (`frame/bidir/specular_paths.rs`).
    if params.clamp_roughness == 0u || max3(m.specular) <= 0.0 || !(dhat > 0.0)
        || m.roughness < MIRROR_ROUGHNESS {
        return unclamped(m);
    }
    let weight = 16.0 * avg3(fresnel_avg(m)) / (4.0 * max(abs(cos_o), 0.05));
    let alpha_min = sqrt(weight / (PI * dhat));
    let r = max(m.roughness, sqrt(min(alpha_min, 1.0)));
    if r <= m.roughness {
        return unclamped(m);
    }
    let mu = abs(cos_o);
    let k = ggx_energy(m.roughness, mu) / max(ggx_energy(r, mu), 1e-3);
    m.roughness = r;
    return Clamped(m, k, 0u, mu);
}

// f(wo, wi) of a clamped material: its diffuse part as is, its (widened) specular lobe
// times `k` (a model's: bidir_models.wgsl `eval_clamped_model`).
fn eval_clamped(c: Clamped, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if MODELS && c.model != 0u {
        return eval_clamped_model(c, n, wo, wi);
    }
    return eval_uber(c, n, wo, wi);
}

// `eval_clamped` of an uber material (`c.model` 0).
fn eval_uber(c: Clamped, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let f = bsdf_eval(c.m, n, wo, wi);
    if c.k == 1.0 {
        return f;
    }
    var d = c.m;
    d.roughness = 0.0;
    let fd = bsdf_eval(d, n, wo, wi);
    return fd + c.k * (f - fd);
}
