// The glossy (GGX) lobe's light from the environment for the deferred direct light
// (direct_shade.wgsl `sampled_light`), as the ratio estimator: its unshadowed light by a
// per-pixel quadrature of the lobe (`env_glossy_unshadowed`) times the shadowed share of
// the sky directions' glossy light (`env_glossy_visibility`).
//
// The frame's sky directions (16, drawn for the whole image) meet a glossy lobe of
// α = 0.04 (≈ 10⁻³ of the sphere) rarely: their plain sum left the glossy reflection of
// the sky out (Khronos' DamagedHelmet −64%). The quadrature takes ENV_GLOSSY_TAPS
// half-vectors from the GGX distribution (Hammersley points, the same for every pixel:
// stable, no noise), each weighted by f·cos/pdf = F(wi·h)·G2·(wo·h)/(cos θo·cos θh), the
// same GGX, height-correlated Smith G2 and Schlick Fresnel as bsdf.wgsl and the CPU's
// `Material::eval`; the environment is read at each reflected direction (nearest texel).
// Bias: none for a constant sky beyond the quadrature's (the weight is smooth: measured
// within 1% of `path` on a glossy sphere); on an image, a lobe wider than the taps'
// spacing aliases sharp features (a sun drawn in the image); the shadow of the lobe's
// light is the sky directions' (hard, 16 of them), or where none of them lies in the lobe,
// the cosine-weighted visibility of all of them (ambient-occlusion-like).

const ENV_GLOSSY_TAPS: u32 = 16u;

// A roughness read back from the G-buffer (16-bit float): the glossy clamp of textured
// roughness (1e-3, `TEX_MIRROR_ROUGHNESS`: a glossy material stays glossy where its map is
// black) comes back as 0.99945e-3 on lavapipe (rounded towards zero), which the BSDF then
// took for a perfect mirror and `direct` rendered black (NormalTangentMirrorTest's gold
// tiles; a sphere of roughness 0.001 under a sky: −100%). Values within that rounding are
// the clamp; a mirror (roughness 0, or below 0.999e-3 on the CPU too) stays a mirror.
fn gbuffer_roughness(r: f32) -> f32 {
    return select(r, MIRROR_ROUGHNESS, r >= 0.999e-3 && r < MIRROR_ROUGHNESS);
}

// Van der Corput radical inverse in base 2 of `i`.
fn env_glossy_radical_inverse(i: u32) -> f32 {
    return f32(reverseBits(i)) * 2.3283064365386963e-10;
}

// An orthonormal tangent of unit `n`.
fn env_glossy_tangent(n: vec3<f32>) -> vec3<f32> {
    let a = select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), abs(n.x) > 0.9);
    return normalize(cross(a, n));
}

// ∫ f_s(wo, wi)·|cos θi|·L(wi) dωi over the glossy lobe of `m` (unshadowed), two-sided as
// `bsdf_eval`; directions below the geometric surface (`ng`) seen from `wo` are left out.
fn env_glossy_unshadowed(m: Material, ns: vec3<f32>, ng: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if max3(m.specular) <= 0.0 || m.roughness < MIRROR_ROUGHNESS {
        return vec3<f32>(0.0);
    }
    let n = ns * sign(dot(ns, wo));
    let co = dot(n, wo);
    if co <= 0.0 {
        return vec3<f32>(0.0);
    }
    let alpha = m.roughness * m.roughness;
    let a2 = alpha * alpha;
    let t = env_glossy_tangent(n);
    let b = cross(n, t);
    let side = dot(wo, ng);
    let lambda_o = smith_lambda(co, alpha);
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < ENV_GLOSSY_TAPS; k++) {
        // GGX half-vector: cos²θh = (1 − u)/(1 + (α² − 1)·u), density D·cos θh.
        let u = (f32(k) + 0.5) / f32(ENV_GLOSSY_TAPS);
        let phi = 2.0 * PI * env_glossy_radical_inverse(k);
        let c2 = (1.0 - u) / (1.0 + (a2 - 1.0) * u);
        let ch = sqrt(c2);
        let sh = sqrt(max(1.0 - c2, 0.0));
        let h = t * (sh * cos(phi)) + b * (sh * sin(phi)) + n * ch;
        let oh = dot(wo, h);
        if oh <= 0.0 {
            continue;
        }
        let wi = 2.0 * oh * h - wo;
        let ci = dot(n, wi);
        if ci <= 0.0 || dot(wi, ng) * side <= 0.0 {
            continue;
        }
        let g2 = 1.0 / (1.0 + lambda_o + smith_lambda(ci, alpha));
        sum += exact_glossy_tap(fresnel_spec(m, oh) * (g2 * oh / (co * ch)), n, wo, wi, alpha) * env_radiance(wi);
    }
    return sum / f32(ENV_GLOSSY_TAPS);
}

// The shadowed share of the glossy lobe's sky light: Σ f_s·cos·E·V / Σ f_s·cos·E over the
// frame's sky directions (`glossy_lit`, `glossy_unshadowed`), or where none lies in the lobe
// the cosine-weighted share Σ cos·E·V / Σ cos·E (`cos_lit`, `cos_unshadowed`).
fn env_glossy_visibility(glossy_lit: vec3<f32>, glossy_unshadowed: vec3<f32>, cos_lit: vec3<f32>, cos_unshadowed: vec3<f32>) -> vec3<f32> {
    if max3(glossy_unshadowed) > 0.0 {
        return visible_ratio(glossy_lit, glossy_unshadowed);
    }
    return visible_ratio(cos_lit, cos_unshadowed);
}

// The visibility ratio Σ f·G·V / Σ f·G per channel, 1 where no sample lit the point (nothing
// known of its visibility): the direct light's and bidir's shadowing of unshadowed sums.
fn visible_ratio(lit: vec3<f32>, unshadowed: vec3<f32>) -> vec3<f32> {
    return select(vec3<f32>(1.0), lit / max(unshadowed, vec3<f32>(1e-30)), unshadowed > vec3<f32>(0.0));
}
