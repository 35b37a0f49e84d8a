// The glossy lobe of the emitter polygon groups in closed form (after direct_shade.wgsl,
// exact_models.wgsl, env_glossy.wgsl and ltc.wgsl: uses their bindings and helpers). Its
// one call site is `sampled_light`'s group loop, compiled only where SAMPLED_LIGHTS and
// GLOSSY are (a point-lit scene compiles none of it).
//
// Per group: the unshadowed light of the uber GGX lobe Σ L·∫_P f·cos dω by linearly
// transformed cosines (Schlick's Fresnel through the table's moment), times the ratio
// estimator's visibility Σ f_s·G·V / Σ f_s·G over the points drawn on the group (Heitz,
// Hill & McGuire 2018; the diffuse lobe's ratio where no point lights the glossy lobe).
// Mitsuba's exact models (`exact_on`) keep the points' sum: the table is the uber GGX's.

// Σ L·(x, y) of `ltc_glossy` over the polygons [`first`, `end`) of `emitter_polygons`, per
// channel: the Fresnel-1 integral and the Schlick moment's.
struct LtcSums {
    x: vec3<f32>,
    y: vec3<f32>,
}

fn ltc_polygons(p: vec3<f32>, ns: vec3<f32>, wo: vec3<f32>, roughness: f32, first: u32, end: u32) -> LtcSums {
    var out = LtcSums(vec3<f32>(0.0), vec3<f32>(0.0));
    for (var t = first; t < end; t++) {
        let t0 = textureLoad(emitter_polygons, vec2<u32>(0u, t), 0);
        let t1 = textureLoad(emitter_polygons, vec2<u32>(1u, t), 0);
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
        let g = ltc_glossy(ns, wo, roughness, a, b, c, d);
        let l = textureLoad(emitter_polygons, vec2<u32>(3u, t), 0).xyz;
        out.x += l * g.x;
        out.y += l * g.y;
    }
    return out;
}

// The glossy light of group `range` (points [x, y), polygons [z, w)) at `p`, given its
// points' shadowed and unshadowed glossy sums (`glit`, `gun`) and diffuse ones (`dlit`,
// `dun`).
fn ltc_group_glossy(p: vec3<f32>, ns: vec3<f32>, m: Material, wo: vec3<f32>, range: vec4<u32>, glit: vec3<f32>, gun: vec3<f32>, dlit: vec3<f32>, dun: vec3<f32>) -> vec3<f32> {
    if exact_on || max3(m.specular) <= 0.0 || m.roughness < MIRROR_ROUGHNESS {
        return glit;
    }
    let s = ltc_polygons(p, ns, wo, m.roughness, range.z, range.w);
    var u = m.specular * s.x;
    if m.fresnel != 0u {
        u += (vec3<f32>(1.0) - m.specular) * s.y;
    }
    let ratio = select(visible_ratio(dlit, dun), visible_ratio(glit, gun), max3(gun) > 0.0);
    return u * ratio;
}
