// Light selection per shading point for the emitters of no polygon group (tessellated
// spheres, meshes; scene/emitters/tree.rs): each point descends a light BVH of those
// emitting triangles (Conty Estevez & Kulla 2018, as `scene::light_bvh` on the CPU), a child
// chosen with probability proportional to its importance at the point (power over squared
// distance, bounded by the cone of the emitters' normals and the receiver's cosine), draws
// a point uniformly on the triangle reached and evaluates the full BSDF there (diffuse and
// glossy lobes, so the highlights of small or distant emitters appear where the lobe meets
// them). `pixel_samples` descents, their leaf order stratified, averaged: unbiased for the
// unshadowed light (the near-field disc aside: cos θ′/(d² + A/π) per triangle of area A,
// ≈ A/(πd²) dark, negligible for triangles small against their distance). Shadows come
// from the frame's shadow-mapped points by the ratio estimator (direct_shade.wgsl).

// `scene::emitters::PixelTree`: nodes then triangles, `TREE_ENTRY_TEXELS` texels each,
// `TREE_ROW` entries a row.
@group(0) @binding(13) var emitter_tree: texture_2d<f32>;

// `TREE_ROW` of raster/direct.rs.
const TREE_ROW: u32 = 256u;
const TREE_ENTRY_TEXELS: u32 = 4u;
// The largest f32 below 1.
const ONE_MINUS_EPS: f32 = 0.99999994;

fn tree_texel(entry: u32, k: u32) -> vec4<f32> {
    let x = (entry % TREE_ROW) * TREE_ENTRY_TEXELS + k;
    return textureLoad(emitter_tree, vec2<u32>(x, entry / TREE_ROW), 0);
}

// cos(a − b), 1 where a < b; sin(a − b), 0 where a < b (`light_bvh.rs`).
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    return select(cos_a * cos_b + sin_a * sin_b, 1.0, cos_a > cos_b);
}

fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    return select(sin_a * cos_b - cos_a * sin_b, 0.0, cos_a > cos_b);
}

fn sqrt0(x: f32) -> f32 {
    return sqrt(max(x, 0.0));
}

// `LightBounds::importance` of node `e` at point `p` of a surface of normal `n`.
fn node_importance(e: u32, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let t0 = tree_texel(e, 0u);
    let t1 = tree_texel(e, 1u);
    let t2 = tree_texel(e, 2u);
    let two_sided = tree_texel(e, 3u).y > 0.5;
    let phi = t0.w;
    if phi <= 0.0 {
        return 0.0;
    }
    let pc = 0.5 * (t0.xyz + t1.xyz);
    let diag = t1.xyz - t0.xyz;
    let dist2 = dot(p - pc, p - pc);
    let d2 = max(dist2, 0.5 * length(diag));
    let wi = select(vec3<f32>(0.0), (p - pc) * inverseSqrt(dist2), dist2 > 0.0);
    var cos_w = dot(t2.xyz, wi);
    if two_sided {
        cos_w = abs(cos_w);
    }
    let sin_w = sqrt0(1.0 - cos_w * cos_w);
    let radius2 = 0.25 * dot(diag, diag);
    let cos_b = select(sqrt0(1.0 - radius2 / dist2), -1.0, dist2 < radius2 || dist2 <= 0.0);
    let sin_b = sqrt0(1.0 - cos_b * cos_b);
    let cos_o = t1.w;
    let sin_o = sqrt0(1.0 - cos_o * cos_o);
    let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, cos_o);
    let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, cos_o);
    let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    if cos_p <= t2.w {
        return 0.0;
    }
    let cos_i = abs(dot(wi, n));
    let sin_i = sqrt0(1.0 - cos_i * cos_i);
    let importance = phi * cos_p / d2 * cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
    // Not finite (or negative): none.
    return select(0.0, importance, importance > 0.0 && importance < 3.0e38);
}

// A triangle of the tree chosen for `p`, `n` from `u` in [0, 1) and its probability (0:
// no emitter reaches the point), as `LightBvh::sample`.
struct TreePick {
    triangle: u32,
    prob: f32,
}

fn tree_pick(p: vec3<f32>, n: vec3<f32>, u_in: f32) -> TreePick {
    var i = 0u;
    var prob = 1.0;
    var u = u_in;
    // The CPU tree's trail holds 64 levels.
    for (var depth = 0u; depth < 64u; depth++) {
        let t3 = tree_texel(i, 3u);
        if t3.x > 0.5 {
            // A leaf chosen below the root had importance > 0 there.
            if depth > 0u || node_importance(i, p, n) > 0.0 {
                return TreePick(u32(t3.z + 0.5), prob);
            }
            break;
        }
        let a = i + 1u;
        let b = u32(t3.z + 0.5);
        let ia = node_importance(a, p, n);
        let ib = node_importance(b, p, n);
        let total = ia + ib;
        if !(total > 0.0) {
            break;
        }
        let pa = ia / total;
        if u < pa {
            u = min(u / pa, ONE_MINUS_EPS);
            prob *= pa;
            i = a;
        } else {
            u = clamp((u - pa) / (1.0 - pa), 0.0, ONE_MINUS_EPS);
            prob *= 1.0 - pa;
            i = b;
        }
    }
    return TreePick(0u, 0.0);
}

// PCG hash (Jarzynski & Olano 2020).
fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The next uniform number in [0, 1) of the stream `state`.
fn next_unit(state: ptr<function, u32>) -> f32 {
    *state = pcg(*state);
    return min(f32(*state >> 8u) * (1.0 / 16777216.0), ONE_MINUS_EPS);
}

// A uniform point of a triangle as barycentrics of corners b and c (Heitz 2019, as
// `sampling::uniform_triangle`).
fn triangle_point(u: vec2<f32>) -> vec2<f32> {
    if u.y > u.x {
        let b0 = u.x * 0.5;
        let b1 = u.y - b0;
        return vec2<f32>(b1, 1.0 - b0 - b1);
    }
    let b1 = u.y * 0.5;
    let b0 = u.x - b1;
    return vec2<f32>(b1, 1.0 - b0 - b1);
}

// Glossy lobe `m` widened for a light sample standing for a disc of angular radius² `spread2`:
// GGX α² + spread2/4 (the half vector turns by half the incident direction's angle), so
// that a lobe narrower than the spacing of the samples on a large emitter shows its
// highlight as a smooth patch instead of a few samples' spikes. Bias: the highlight is
// blurred by about the samples' spacing, ≈ √(A/(n·π))/d for n samples over an emitter of
// area A (the GGX lobe stays normalized, so its energy is kept); it vanishes as n grows.
// Mirrors stay mirrors (delta lobes are not lit here).
fn widened(m: Material, spread2: f32) -> Material {
    var w = m;
    if m.roughness >= MIRROR_ROUGHNESS {
        let a = m.roughness * m.roughness;
        w.roughness = sqrt(sqrt(a * a + 0.25 * spread2));
    }
    return w;
}

// The unshadowed light of the tree's emitters scattered towards the eye at `p` (shading
// normal `ns`, geometric `ng`, material `m`, towards the eye `wo`): the mean of `count`
// samples (`pixel_samples`, or a sub-pixel sample's share of them), each
// L·f·|cos θi|·cos θ′/(d² + A/π) / p_A, p_A the triangle's probability over its area. The
// point's own random stream comes from its position and the frame's seed (a still view
// repeats its image; sub-pixel samples differ).
fn tree_light(p: vec3<f32>, ns: vec3<f32>, ng: vec3<f32>, m: Material, wo: vec3<f32>, count: u32) -> vec3<f32> {
    var state = pcg(bitcast<u32>(p.x) ^ pcg(bitcast<u32>(p.y) ^ pcg(bitcast<u32>(p.z) ^ direct_params.seed)));
    let shift = next_unit(&state);
    var sum = vec3<f32>(0.0);
    let has_glossy = max3(m.specular) > 0.0;
    var glossy = m;
    glossy.diffuse = vec3<f32>(0.0);
    for (var k = 0u; k < count; k++) {
        let u = min((f32(k) + shift) / f32(count), ONE_MINUS_EPS);
        let pick = tree_pick(p, ns, u);
        let uv = vec2<f32>(next_unit(&state), next_unit(&state));
        if pick.prob <= 0.0 {
            continue;
        }
        let e = direct_params.tree_nodes + pick.triangle;
        let t0 = tree_texel(e, 0u);
        let t1 = tree_texel(e, 1u);
        let t2 = tree_texel(e, 2u);
        let bc = triangle_point(uv);
        let x = t0.xyz * (1.0 - bc.x - bc.y) + t1.xyz * bc.x + t2.xyz * bc.y;
        let to_x = x - p;
        let d2 = dot(to_x, to_x);
        let wi = to_x * inverseSqrt(d2);
        if dot(wi, ng) <= 0.0 {
            continue;
        }
        let normal = normalize(cross(t1.xyz - t0.xyz, t2.xyz - t0.xyz));
        var cos_e = -dot(wi, normal);
        if t1.w > 0.5 {
            cos_e = abs(cos_e);
        }
        if cos_e <= 0.0 {
            continue;
        }
        let radiance = tree_texel(e, 3u).xyz;
        let g = abs(dot(ns, wi)) * cos_e / (d2 + t0.w) * t2.w / pick.prob;
        var f = diffuse_eval(m, ns, wo, wi);
        if has_glossy {
            // The area this sample stands for among the pixel's `pixel_samples`, A/(n·p),
            // seen as a disc of solid angle ≈ share/d² (its angular radius² share/(π d²)).
            let spread2 = t2.w / (pick.prob * f32(direct_params.pixel_samples) * PI * d2);
            f += exact_widened_glossy(widened(glossy, spread2), spread2, ns, wo, wi);
        }
        sum += f * radiance * g;
    }
    return sum / f32(max(count, 1u));
}
