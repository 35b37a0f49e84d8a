// The glossy lobe of the emitter polygon groups in closed form (after direct_shade.wgsl,
// exact_models.wgsl, env_glossy.wgsl and ltc.wgsl: uses their bindings and helpers). Its
// one call site is `sampled_light`'s group loop, compiled only where LTC_LIGHTS is (the
// scene has polygon groups and glossy materials: raster/direct_variant.rs).
//
// Per group: the unshadowed light of the uber GGX lobe (an exact model's GGX or Beckmann
// lobe) Σ L·∫_P f·cos dω by linearly transformed cosines (Schlick's Fresnel through the
// table's moment), times the ratio
// estimator's visibility Σ f_s·G·V / Σ f_s·G over the points drawn on the group (Heitz,
// Hill & McGuire 2018; the diffuse lobe's ratio where no point lights the glossy lobe).
// Round emitters (spheres, flat discs) by their disc's polygon (round_lights.wgsl).

// The LTC tables, GGX and Beckmann (raster/ltc.rs `texture`, made once per device).
@group(0) @binding(14) var ltc_table: texture_2d<f32>;

// Σ L·(x, y) of `ltc_glossy` over the polygons [`first`, `end`) of `emitter_polygons`, per
// channel: the Fresnel-1 integral and the Schlick moment's.
struct LtcSums {
    x: vec3<f32>,
    y: vec3<f32>,
}

// `table`: the lobe's (ltc.wgsl: 0 GGX, 1 Beckmann).
fn ltc_polygons(table: u32, p: vec3<f32>, ns: vec3<f32>, wo: vec3<f32>, roughness: f32, first: u32, end: u32) -> LtcSums {
    var out = LtcSums(vec3<f32>(0.0), vec3<f32>(0.0));
    for (var t = first; t < end; t++) {
        let t0 = textureLoad(emitter_polygons, vec2<u32>(0u, t), 0);
        let t1 = textureLoad(emitter_polygons, vec2<u32>(1u, t), 0);
        var g = vec2<f32>(0.0);
        if ROUND_LIGHTS && t1.w > 1.5 {
            g = ltc_round(table, ns, wo, roughness, p, t);
        } else {
            let t2 = textureLoad(emitter_polygons, vec2<u32>(2u, t), 0);
            let a = t0.xyz - p;
            let b = t1.xyz - p;
            let c = t2.xyz - p;
            // Front side only for a one-sided emitter; none in the polygon's plane (as
            // `polygons_diffuse`).
            let height = dot(a, cross(b - a, c - a));
            if (t0.w < 0.5 && height >= 0.0) || abs(height) <= t2.w {
                continue;
            }
            var d = c;
            if t1.w > 0.5 {
                d = textureLoad(emitter_polygons, vec2<u32>(4u, t), 0).xyz - p;
            }
            g = ltc_glossy(table, ns, wo, roughness, a, b, c, d);
        }
        let l = textureLoad(emitter_polygons, vec2<u32>(3u, t), 0).xyz;
        out.x += l * g.x;
        out.y += l * g.y;
    }
    return out;
}

// f·cos θi of the glossy lobe (Fresnel 1) towards `wi`, and the same with the Schlick
// weight (1 − wi·h)⁵: `ltc_glossy`'s integrand, of the uber GGX lobe (height-correlated
// masking) or, where `exact_on`, the model's (its distribution, separable masking for
// conductors and coatings: models.wgsl `model_glossy`).
fn ltc_integrand(n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, alpha: f32) -> vec2<f32> {
    let co = dot(n, wo);
    let ci = dot(n, wi);
    if co <= 0.0 || ci <= 0.0 {
        return vec2<f32>(0.0);
    }
    let beckmann = exact_on && has_flag(exact_model, MODEL_BECKMANN);
    let separable = exact_on && (has_flag(exact_model, MODEL_COATED) || has_flag(exact_model, MODEL_CONDUCTOR));
    let h = normalize(wo + wi);
    let lo = mf_lambda(co, alpha, beckmann);
    let li = mf_lambda(ci, alpha, beckmann);
    let g = select(1.0 / (1.0 + lo + li), 1.0 / ((1.0 + lo) * (1.0 + li)), separable);
    let f = mf_d(dot(n, h), alpha, beckmann) * g / (4.0 * co);
    return vec2<f32>(f, f * pow(1.0 - clamp(dot(wi, h), 0.0, 1.0), 5.0));
}

// The lobe's integral over a small disc (radius under the lobe's width): the 7-point rule
// of the disc (its centre weighted ¼, six points at √(2/3) of its radius ⅛ each; exact for
// cubics) over its solid angle. One loop for the seven, its count read from the record
// (`corners`/2 + 1), so that the integrand's code is not copied seven times.
fn round_quadrature(q: RoundPolygon, n: vec3<f32>, v: vec3<f32>, alpha: f32) -> vec2<f32> {
    var sum = vec2<f32>(0.0);
    // The polygon's axes are its scale over the disc's: the ring at √(2/3) of the disc.
    let ring = 0.81649658 * q.radius / length(q.u);
    var cs = vec2<f32>(0.0);
    for (var k = 0u; k <= q.corners / 2u; k++) {
        let w = normalize(q.centre + (q.u * cs.x + q.v * cs.y) * ring);
        sum += select(0.125, 0.25, k == 0u) * ltc_integrand(n, v, w, alpha);
        // The centre, then the ring by sixths of a turn.
        cs = select(vec2<f32>(0.5 * cs.x - 0.8660254 * cs.y, 0.8660254 * cs.x + 0.5 * cs.y), vec2<f32>(1.0, 0.0), k == 0u);
    }
    return sum * q.solid_angle;
}

// `ltc_glossy` of round emitter `t` (round_lights.wgsl: the polygon of its disc) at `p`.
// A disc small against the lobe (its angular radius ρ under α, the lobe's half width
// about 2α in directions) by quadrature of the lobe itself: LTC's clamped cosine is wider
// than a sharp GGX or Beckmann peak, and blurred small lights' highlights; a larger one by
// LTC, blended between ρ = α and 2α; a disc much larger than the lobe as a polygon of more
// corners (`round_sides`: a sharp highlight showed the 12-gon's straight edges).
fn ltc_round(table: u32, n: vec3<f32>, v: vec3<f32>, roughness: f32, p: vec3<f32>, t: u32) -> vec2<f32> {
    let disc = round_polygon(p, t);
    if !disc.ok {
        return vec2<f32>(0.0);
    }
    let alpha = roughness * roughness;
    let rho = disc.radius / length(disc.centre);
    let blend = clamp(rho / alpha - 1.0, 0.0, 1.0);
    var small = vec2<f32>(0.0);
    if blend < 1.0 {
        small = round_quadrature(disc, n, v, alpha);
        if blend <= 0.0 {
            return small;
        }
    }
    // A disc large against the lobe: more corners (`round_sides`).
    let q = round_sides(disc, rho / alpha);
    let cell = ltc_lookup(table, roughness, dot(n, v));
    let t1 = ltc_view_tangent(n, v);
    let t2 = cross(n, t1);
    var sum = 0.0;
    var exit = vec3<f32>(0.0);
    var entry = vec3<f32>(0.0);
    var cs = vec2<f32>(1.0, 0.0);
    var w = round_corner(q, cs);
    var a = ltc_apply(cell, vec3<f32>(dot(w, t1), dot(w, t2), dot(w, n)));
    for (var k = 0u; k < q.corners; k++) {
        cs = round_turn(q, cs);
        w = round_corner(q, cs);
        let b = ltc_apply(cell, vec3<f32>(dot(w, t1), dot(w, t2), dot(w, n)));
        ltc_clip_edge(a, b, &sum, &exit, &entry);
        a = b;
    }
    sum += ltc_edge_z(exit, entry);
    return mix(small, abs(sum) / 6.28318530718 * cell.moments, blend);
}

// The glossy light of group `range` (points [x, y), polygons [z, w)) at `p`, given its
// points' shadowed and unshadowed glossy sums (`glit`, `gun`) and diffuse ones (`dlit`,
// `dun`).
fn ltc_group_glossy(p: vec3<f32>, ns: vec3<f32>, m: Material, wo: vec3<f32>, range: vec4<u32>, glit: vec3<f32>, gun: vec3<f32>, dlit: vec3<f32>, dun: vec3<f32>) -> vec3<f32> {
    // Mitsuba's exact models: the table of the model's distribution (GGX or Beckmann) at
    // its roughness, weighted by the model's mirror reflectance at the view (its Fresnel
    // term at the half vector of a narrow lobe's mirror direction).
    var roughness = m.roughness;
    var specular = m.specular;
    var table = 0u;
    if exact_on {
        table = select(0u, 1u, has_flag(exact_model, MODEL_BECKMANN));
        roughness = exact_model.roughness;
        specular = exact_model.specular;
        if has_flag(exact_model, MODEL_COATED) && !has_flag(exact_model, MODEL_ROUGH_COAT) {
            return glit;
        }
    }
    if max3(specular) <= 0.0 || roughness < MIRROR_ROUGHNESS {
        return glit;
    }
    let s = ltc_polygons(table, p, ns, wo, roughness, range.z, range.w);
    var u = m.specular * s.x;
    if exact_on {
        u = exact_mirror(vec3<f32>(0.0), abs(dot(ns, wo))) * s.x;
    } else if m.fresnel != 0u {
        u += (vec3<f32>(1.0) - m.specular) * s.y;
    }
    let ratio = select(visible_ratio(dlit, dun), visible_ratio(glit, gun), max3(gun) > 0.0);
    return u * ratio;
}
