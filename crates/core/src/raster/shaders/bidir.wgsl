// Indirect light of method `bidir` (Tokuyoshi & Ogaki 2012 §4) at every G-buffer pixel x3:
//
// - one bounce through a VPL x1 (light subpath, §4.1), for every VPL:
//     Φ1 · f(x1; ω1,3, ω1,0) · f(x3; ω3,4, ω3,1) · |n3·ω3,1| · |ng1·ω1,3| / ‖x1 − x3‖² · V
//   with V from the VPL's cube shadow map;
// - one bounce through a ray-bundle hit x2 (camera subpath, §3): per bundle the nearest
//   fragment along ±ω (the side of n3), lit by the lights with their shadow maps:
//     f(x3)·|n3·ω|·f(x2)·|n2·ω2,0|·I/‖x2 − x0‖²·V / p_r,   p_r = 1/2π;
// - both combined by MIS (§4.2, balance heuristic, β = 1) on the area densities of the
//   middle vertex: VPLs p1 = n1·I(ω0,j)·|ng_j·ω_j,0| / (‖x_j − x0‖²·W) (W: the light's
//   covered flux, VPLs drawn ∝ flux), bundles p2 = n2·p_r·|ng_j·ω_j,3| / ‖x_j − x3‖²;
// - two bounces x0 → x1 → x2 → x3 (§4.3): each bundle paired with one VPL of every light,
//   the VPL's shadow map testing (x1, x2); and more bounces (issue 29): the same bundle hit
//   x2 connected to every later vertex of a light subpath continued from that VPL on the
//   CPU (`subpaths.rs`), each vertex a VPL of its own (strategy A). Strategy B of the same
//   path lengths: every subpath vertex y_j (j ≥ 2) lights x3 as a VPL. A and B combined by
//   MIS (balance heuristic on the area density of the vertex next to x3: D(ω)·cos/d² from
//   the bundles, n1·`mis_density` from the subpaths (one from every VPL), `b_density`), so that no pair needs a
//   clamp; in modes 1 and 2 A alone, ‖x2 − y‖² clamped from below.
// - roughness clamping (§5): the GGX α of the BSDF at a path vertex is raised so that the
//   distribution's peak D(0) = 1/(πα²) stays under d̂/m (kernel radius estimation, eq. 9),
//   with d̂ the density of samples per unit solid angle there (eqs. 13–17, from the area
//   density A = n1·p1 + n2·p2 of the middle vertex: d = A·dist²/cos towards either end)
//   and m = 16 (the paper's m'); the widened lobe scaled to keep its albedo
//   (`roughness_clamp.wgsl`).
// - environment light (§6): a bundle direction with no fragment along it sees the
//   environment: f3·|n3·ω|·L_env(ω)/D(ω) for f3's diffuse lobe (its direct light; its
//   indirect light comes from the VPLs of `emitted.rs`); the glossy lobe's direct sky light
//   is env_glossy.wgsl's quadrature times the bundles' visibility share (`SkyShare`). With an image environment (and its `importance`), part of the bundles are
//   drawn by the sky's luminance (§3.3); D, the density of all the frame's bundle
//   directions (a multi-sample balance heuristic over the two ways of drawing them),
//   replaces n2·p_r everywhere.
// - area lights, the sun and the sky (issue 28): their VPLs (`emitted.rs`, one more group of
//   `vpls_per_light` after the lights') are the first hits of photons emitted on the CPU;
//   their one-bounce light is theirs alone (no bundle strategy), their later bounces as
//   every group's.
// `mode`: 0 MIS, 1 VPLs only, 2 bundles only (for the one-bounce light of point and spot
// lights).

struct Vpl {
    position: vec3<f32>,
    first_layer: u32,
    flux: vec3<f32>,
    // World size of one shadow texel at unit distance from the VPL.
    texel_scale: f32,
    // Unit direction from the VPL towards its light (ω1,0).
    to_light: vec3<f32>,
    fresnel: u32,
    // The exact model's record index + 1 (bidir_models.wgsl; 0: the uber parameters).
    model: u32,
    diffuse: vec3<f32>,
    roughness: f32,
    specular: vec3<f32>,
    // Area density of this VPL's point per VPL draw (I(ω)·cos / (d²·W)); negative for the
    // VPLs of area lights, the sun and the sky (`emitted.rs`), whose one-bounce light has no
    // bundle strategy (MIS weight 1, ‖x3 − y1‖² clamped at `alone_min_dist2`).
    pdf: f32,
    ns: vec3<f32>,
    // The covered flux W (sum of channels) of the VPL's light.
    light_flux: f32,
    ng: vec3<f32>,
    // Squared distance from the VPL to its light.
    light_dist2: f32,
}

struct Params {
    eye: vec3<f32>,
    // VPL slots: `vpls_per_light` per light, light by light.
    vpl_count: u32,
    vpls_per_light: u32,
    bundles: u32,
    mode: u32,
    // Indirect bounces (`max_depth` − 1): 0 none, 1 one bounce, 2 also two bounces with
    // the RSM's VPLs, j > 2 also the traced subpaths' vertices up to order j − 1.
    bounces: u32,
    // Lower bound of ‖x1 − x2‖² in the two-bounce term.
    min_dist2: f32,
    // Longest list walked (a guard: lists longer than this are cut).
    max_walk: u32,
    // Random offset in [0, 1) of the bundle-to-VPL pairing of the two-bounce term.
    pair_offset: f32,
    // Roughness clamping (§5) on (1) or off (0).
    clamp_roughness: u32,
    // Camera clip -> world (for the environment behind pixels the scene does not cover).
    inv_view_proj: mat4x4<f32>,
    // Environment light: 1 when the scene has one; (cos, sin) of its rotation about +y.
    has_env: u32,
    env_cos: f32,
    env_sin: f32,
    // Bundles drawn from the environment (§3.3) and uniformly: D(ω) =
    // n_uniform/2π + n_env·(p_env(ω) + p_env(−ω)), p_env(ω) ≈ lum(L_env(ω))·env_pdf_scale.
    bundles_env: f32,
    bundles_uniform: f32,
    env_pdf_scale: f32,
    // Lower bound of ‖x3 − y1‖² for the one-bounce light of VPLs without a bundle strategy.
    alone_min_dist2: f32,
    // Records of the light subpaths' vertices after the `vpl_count` first VPLs.
    sub_count: u32,
    // β of the sky's control variate (`frame/bidir/sky_share.rs`).
    sky_cv: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
// The VPL records, seven texels a row, a row per VPL (`VplRaw::texels`).
@group(0) @binding(1) var vpl_tex: texture_2d<f32>;
@group(0) @binding(2) var<storage, read> vpl_views: array<mat4x4<f32>>;
@group(0) @binding(3) var vpl_maps: texture_depth_2d_array;
@group(0) @binding(4) var shadow_sampler: sampler_comparison;
@group(0) @binding(5) var<storage, read> lights: array<Light>;
@group(0) @binding(6) var<storage, read> light_views: array<mat4x4<f32>>;
@group(0) @binding(7) var light_maps: texture_depth_2d_array;
@group(0) @binding(8) var<storage, read> bundle_views: array<BundleView>;
@group(0) @binding(9) var<storage, read> heads: array<u32>;
@group(0) @binding(10) var<storage, read> nodes: array<Node>;
// Radiance table of the environment (equirectangular; 1×1 for a constant colour).
@group(0) @binding(11) var env_table: texture_2d<f32>;
// Its irradiance table (`Environment::irradiance_table`: rows from pole to pole).
@group(0) @binding(12) var irradiance_table: texture_2d<f32>;
@group(1) @binding(0) var g_position: texture_2d<f32>;
@group(1) @binding(1) var g_normals: texture_2d<f32>;
@group(1) @binding(2) var g_diffuse: texture_2d<f32>;
@group(1) @binding(3) var g_specular: texture_2d<f32>;
// The sample's emission, its material index + 1 in `w` (bidir_models.wgsl `pixel_model`).
@group(1) @binding(4) var g_emission: texture_2d<f32>;

const TWO_PI: f32 = 6.28318530718;

fn spot(l: Light, cos_t: f32) -> f32 {
    if l.kind != 1u {
        return 1.0;
    }
    return cone_falloff(cos_t, l.cos_inner, l.cos_outer);
}

fn vpl_at(i: u32) -> Vpl {
    let t0 = textureLoad(vpl_tex, vec2<u32>(0u, i), 0);
    let t1 = textureLoad(vpl_tex, vec2<u32>(1u, i), 0);
    let t2 = textureLoad(vpl_tex, vec2<u32>(2u, i), 0);
    let t3 = textureLoad(vpl_tex, vec2<u32>(3u, i), 0);
    let t4 = textureLoad(vpl_tex, vec2<u32>(4u, i), 0);
    let t5 = textureLoad(vpl_tex, vec2<u32>(5u, i), 0);
    let t6 = textureLoad(vpl_tex, vec2<u32>(6u, i), 0);
    var v: Vpl;
    v.position = t0.xyz;
    v.first_layer = u32(t0.w + 0.5);
    v.flux = t1.xyz;
    v.texel_scale = t1.w;
    v.to_light = t2.xyz;
    // The material word: the Fresnel flag, the model's record index + 1 above it.
    let word = u32(t2.w + 0.5);
    v.fresnel = word & 1u;
    v.model = word_model(word);
    v.diffuse = t3.xyz;
    v.roughness = t3.w;
    v.specular = t4.xyz;
    v.pdf = t4.w;
    v.ns = t5.xyz;
    v.light_flux = t5.w;
    v.ng = t6.xyz;
    v.light_dist2 = t6.w;
    return v;
}

fn vpl_material(v: Vpl) -> Material {
    var m: Material;
    m.diffuse = v.diffuse;
    m.roughness = v.roughness;
    m.specular = v.specular;
    m.fresnel = v.fresnel;
    return m;
}

// Cube faces a layer of `vpl_maps` holds (a 2×2 atlas, `raster::vpl::FACES_A_LAYER`): face f
// lies in layer f / VPL_FACES_A_LAYER, its matrix mapping into its quarter.
const VPL_FACES_A_LAYER: u32 = 4u;

// Visibility of `p` (geometric normal `ng`, towards the VPL) from VPL `v`.
fn vpl_visibility(v: Vpl, p: vec3<f32>, ng: vec3<f32>) -> f32 {
    let d = v.position - p;
    let dist = length(d);
    let c = dot(d / dist, ng);
    let q = p + ng * (v.texel_scale * dist * (1.0 - c) + 1e-4 * dist);
    let face = shadow_layer_of(v.first_layer, 6u, q - v.position);
    return shadow_tap(vpl_maps, shadow_sampler, vpl_views[face], face / VPL_FACES_A_LAYER, q);
}

fn light_visibility(l: Light, p: vec3<f32>, ng: vec3<f32>) -> f32 {
    let d = l.position - p;
    let dist = length(d);
    let c = dot(d / dist, ng);
    let q = p + ng * (l.texel_scale * dist * (1.0 - c) + 1e-4 * dist);
    let layer = shadow_layer_of(l.first_layer, l.layers, q - l.position);
    return shadow_tap(light_maps, shadow_sampler, light_views[layer], layer, q);
}

// The light VPL `v` sends from x1 to a point `p` (normals `ns`, `ng`; material `m`, seen
// from `wo`), visibility included: Φ1·f1·f·|ns·ωp,1|·|ng1·ω1,p|/d².
fn vpl_light(v: Vpl, m1: Clamped, p: vec3<f32>, ns: vec3<f32>, ng: vec3<f32>, m: Clamped, wo: vec3<f32>, min_d2: f32) -> vec3<f32> {
    let to_vpl = v.position - p;
    let d2 = dot(to_vpl, to_vpl);
    let wi = to_vpl / sqrt(d2);
    let cos1 = -dot(wi, v.ng);
    if dot(wi, ng) <= 0.0 || cos1 <= 0.0 || max3(v.flux) <= 0.0 {
        return vec3<f32>(0.0);
    }
    let f = pair_f(m1, v.ns, -wi, v.to_light, m, ns, wo, wi);
    let t = v.flux * f * (abs(dot(ns, wi)) * cos1 / max(d2, min_d2));
    if max3(t) <= 0.0 {
        return vec3<f32>(0.0);
    }
    return t * vpl_visibility(v, p, ng);
}

// Strategy B's area density of the vertex x next to x3 when the subpath draws it from `y`
// (continuation `q`), scaled as the bundles' D(ω)·cos/d² is (both counted per first VPL:
// each of the n1 VPLs of a light is continued by one subpath, and picked by n2/n1 bundles):
// n1·q·|ns_y·ω|/π·|ng·ω|/d², as `subpaths::mis_density` stores it (without n1) in the
// records of the subpaths' vertices.
fn b_density(y: Vpl, q: f32, x: vec3<f32>, ng: vec3<f32>) -> f32 {
    let d = x - y.position;
    let d2 = max(dot(d, d), 1e-20);
    let w = d / sqrt(d2);
    return f32(params.vpls_per_light) * q * abs(dot(y.ns, w)) / PI * abs(dot(ng, w)) / d2;
}

// d̂ of eq. 13 from the two solid-angle densities.
fn avg3(v: vec3<f32>) -> f32 {
    return (v.x + v.y + v.z) / 3.0;
}

fn combine(d_a: f32, d_b: f32) -> f32 {
    return 1.0 / (1.0 / d_a + 1.0 / d_b);
}

// Radiance of the environment from world direction `d` (`Environment::radiance`).
fn env_radiance(d: vec3<f32>) -> vec3<f32> {
    let c = params.env_cos;
    let s = params.env_sin;
    let l = vec3<f32>(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
    let sin_t = sqrt(l.x * l.x + l.z * l.z);
    var u = atan2(l.x, -l.z) / TWO_PI;
    u = u - floor(u);
    let v = atan2(sin_t, l.y) / PI;
    let size = textureDimensions(env_table);
    let x = min(u32(u * f32(size.x)), size.x - 1u);
    let y = min(u32(v * f32(size.y)), size.y - 1u);
    return textureLoad(env_table, vec2<u32>(x, y), 0).xyz;
}

// The environment's irradiance on a surface facing world direction `n`, bilinear in the
// irradiance table (as `direct_shade.wgsl`'s `env_irradiance`).
fn env_irradiance(n: vec3<f32>) -> vec3<f32> {
    let c = params.env_cos;
    let s = params.env_sin;
    let l = vec3<f32>(c * n.x - s * n.z, n.y, s * n.x + c * n.z);
    let size = textureDimensions(irradiance_table);
    var u = atan2(l.x, -l.z) / TWO_PI;
    u = u - floor(u);
    let v = atan2(sqrt(l.x * l.x + l.z * l.z), l.y) / PI;
    let st = vec2<f32>(u * f32(size.x) - 0.5, v * f32(size.y - 1u));
    let base = floor(st);
    let f = st - base;
    let w = i32(size.x);
    let h = i32(size.y) - 1;
    let x0 = (i32(base.x) % w + w) % w;
    let x1 = (x0 + 1) % w;
    let y0 = clamp(i32(base.y), 0, h);
    let y1 = clamp(i32(base.y) + 1, 0, h);
    let a = mix(textureLoad(irradiance_table, vec2<i32>(x0, y0), 0).xyz, textureLoad(irradiance_table, vec2<i32>(x1, y0), 0).xyz, f.x);
    let b = mix(textureLoad(irradiance_table, vec2<i32>(x0, y1), 0).xyz, textureLoad(irradiance_table, vec2<i32>(x1, y1), 0).xyz, f.x);
    return mix(a, b, f.y);
}

// The diffuse lobe of `bsdf_eval` alone (Lambert with its Fresnel coupling), the
// integrand of the sky's control variate.
fn diffuse_lobe(m: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let co = dot(n, wo);
    let ci = dot(n, wi);
    if co * ci <= 0.0 || max3(m.diffuse) <= 0.0 {
        return vec3<f32>(0.0);
    }
    let one_minus_avg = vec3<f32>(1.0) - fresnel_avg(m);
    let num = (vec3<f32>(1.0) - fresnel_spec(m, abs(co))) * (vec3<f32>(1.0) - fresnel_spec(m, abs(ci)));
    let coupling = select(vec3<f32>(0.0), num / one_minus_avg, one_minus_avg > vec3<f32>(1e-6));
    return m.diffuse / PI * coupling;
}

// The control variate's expectation: the diffuse lobe's unshadowed sky light in closed form,
// ρ/π·(1 − F(cos θo))·E(ns) (the Fresnel coupling's mean over the incident cosines is
// 1 − F_avg: exact for a constant sky, as `direct_shade.wgsl`'s ratio estimator takes it).
fn sky_diffuse_unshadowed(m: Material, ns: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let one_minus_avg = vec3<f32>(1.0) - fresnel_avg(m);
    if max3(m.diffuse) <= 0.0 && !exact_on {
        return vec3<f32>(0.0);
    }
    let coupling = select(vec3<f32>(0.0), vec3<f32>(1.0) - fresnel_spec(m, abs(dot(ns, wo))), one_minus_avg > vec3<f32>(1e-6));
    return exact_env_diffuse(m.diffuse / PI * coupling, ns, wo) * env_irradiance(ns);
}

// The sky's glossy light at a pixel (issue 47), as the `direct` frame's ratio estimator
// (env_glossy.wgsl): the lobe's unshadowed light by its per-pixel quadrature
// (`env_glossy_unshadowed`, no noise) times the shadowed share of the lobe's light over the
// frame's bundle directions, Σ f_s·cos·L·[miss] / Σ f_s·cos·L (`glit`, `gun`), or where
// none lies in the lobe the cosine-weighted share Σ cos·L·[miss] / Σ cos·L (`clit`, `cun`).
// Before, the bundles' misses summed the glossy lobe's light as they sum the diffuse lobe's,
// and 16 directions met a narrow lobe rarely: Khronos' NormalTangentMirrorTest −10.4% of
// `path`. Bias, stated: the lobe's shadow is the bundle directions' (16 of them, hard), and
// an image sky's features sharper than the quadrature's taps alias (env_glossy.wgsl).
struct SkyShare {
    glit: vec3<f32>,
    gun: vec3<f32>,
    clit: vec3<f32>,
    cun: vec3<f32>,
}

// One bundle direction's glossy light `fs` and cosine-weighted sky light `e` (both
// unshadowed), `missed` when nothing lies along it.
fn sky_share_add(s: ptr<function, SkyShare>, fs: vec3<f32>, e: vec3<f32>, missed: bool) {
    let fs_pos = max(fs, vec3<f32>(0.0));
    (*s).gun += fs_pos;
    (*s).cun += e;
    if missed {
        (*s).glit += fs_pos;
        (*s).clit += e;
    }
}

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// The frame's density of bundle directions over a hemisphere at a point, towards `d`
// (the sum over bundles; n2/2π when all are uniform). Used in the MIS weights and the
// clamping densities; a bundle's own sample is divided by its exact value (`inv_density`).
fn bundle_density(d: vec3<f32>) -> f32 {
    var dens = params.bundles_uniform / TWO_PI;
    if params.bundles_env > 0.0 {
        let l = luminance(env_radiance(d)) + luminance(env_radiance(-d));
        dens += params.bundles_env * l * params.env_pdf_scale;
    }
    return dens;
}

struct Hit {
    found: bool,
    t: f32,
    node: Node,
}

fn node_position(n: Node) -> vec3<f32> {
    return vec3<f32>(n.x, n.y, n.z);
}

// The nearest fragment of bundle `bv` from `p` along `dir` = ±ω: the smallest distance along
// `dir` beyond `eps`, skipping fragments whose plane passes within `plane_eps` of `p` (p's
// own surface, and its neighbouring triangles on a finely tessellated curve).
fn trace_bundle(bv: BundleView, p: vec3<f32>, dir: vec3<f32>, eps: f32, plane_eps: f32) -> Hit {
    var hit: Hit;
    hit.found = false;
    let clip = bv.view_proj * vec4<f32>(p, 1.0);
    let uv = clip.xy * vec2<f32>(0.5, -0.5) + 0.5;
    if any(uv < vec2<f32>(0.0)) || any(uv >= vec2<f32>(1.0)) {
        return hit;
    }
    let px = vec2<u32>(uv * f32(bv.res));
    var best = 3.4e38;
    var next = heads[bv.index * bv.res * bv.res + px.y * bv.res + px.x];
    var steps = 0u;
    while next != 0u && steps < params.max_walk {
        let n = nodes[next - 1u];
        let q = node_position(n) - p;
        let t = dot(q, dir);
        if t > eps && t < best {
            let ng = oct_decode(unpack2x16snorm(n.ng));
            if abs(dot(q, ng)) > plane_eps {
                best = t;
                hit.node = n;
                hit.found = true;
            }
        }
        next = n.next;
        steps++;
    }
    hit.t = best;
    return hit;
}

// The record index + 1 of a bundle fragment's exact model (0: its uber parameters).
fn node_model(n: Node) -> u32 {
    return word_model(n.m3 >> 16u);
}

fn node_material(n: Node) -> Material {
    let a = unpack2x16float(n.m0);
    let b = unpack2x16float(n.m1);
    let c = unpack2x16float(n.m2);
    let d = unpack2x16float(n.m3);
    var m: Material;
    m.diffuse = vec3<f32>(a, b.x);
    // Negative: a one-sided material (bundles.wgsl), black met from behind (`one_sided_back`).
    m.roughness = gbuffer_roughness(abs(b.y));
    m.two_sided = select(0u, MATERIAL_ONE_SIDED, b.y < 0.0);
    m.specular = vec3<f32>(c, d.x);
    // The high half of m3: the Fresnel flag, the model's record index + 1 above it
    // (`node_model`).
    m.fresnel = (n.m3 >> 16u) & 1u;
    return m;
}

// Strategy B at x3 = `p` for subpath slot `i`: the vertex as a VPL, weighted by MIS against
// the bundles' strategy A.
fn subpath_vertex_light(i: u32, p: vec3<f32>, ns: vec3<f32>, ng: vec3<f32>, m: Material, model: u32, wo: vec3<f32>, n1: f32, tiny_d2: f32) -> vec3<f32> {
    // The flux first (one texel): empty slots and specular vertices cost no more.
    if max3(textureLoad(vpl_tex, vec2<u32>(1u, i), 0).xyz) <= 0.0 {
        return vec3<f32>(0.0);
    }
    let v = vpl_at(i);
    let to_v = v.position - p;
    let d2 = max(dot(to_v, to_v), 1e-20);
    let cos_v = abs(dot(to_v, v.ng)) / sqrt(d2);
    let pa = bundle_density(to_v / sqrt(d2)) * cos_v / d2;
    let pb = n1 * v.pdf;
    let d3 = (pa + pb) * d2 / max(cos_v, 1e-6);
    let mv = clamped_model(vpl_material(v), v.model, d3, cos_v);
    let t = vpl_light(v, mv, p, ns, ng, clamped_model(m, model, d3, dot(ns, wo)), wo, tiny_d2);
    return t * (pb / (pa + pb));
}

// Interleaved sampling of the deep subpath vertices (issue 48's cost; Keller & Heidrich
// 2001): the slots from `start` on (the vertices of order 3 and more: the first `vpl_count`
// subpath slots hold the y2 of every subpath) light one pixel of each
// INTERLEAVE×INTERLEAVE block each, weighted INTERLEAVE², the pixel chosen by the slot and a
// per-frame offset (uniform over the block's cells: each pixel's estimate stays unbiased).
// A pixel walks every INTERLEAVE²-th slot (its loop a quarter as long at 2: lavapipe, like a
// GPU, runs neighbouring pixels together, and only a shorter loop, not a skipped iteration,
// saves their time); `frame/bidir/interleave.rs` spreads each pixel's light over the block's
// pixels of the same depth. Only where both sides of the image are multiples of INTERLEAVE.
// Returns the pixel's first slot and the step (1: every slot).
const INTERLEAVE: u32 = 2u;

fn interleave(px: vec2<i32>, start: u32) -> vec2<u32> {
    let size = textureDimensions(g_position);
    if size.x % INTERLEAVE != 0u || size.y % INTERLEAVE != 0u {
        return vec2<u32>(start, 1u);
    }
    let n = INTERLEAVE * INTERLEAVE;
    let q = vec2<u32>(px) % INTERLEAVE;
    let cell = (q.x + INTERLEAVE * q.y + u32(params.pair_offset * f32(n))) % n;
    return vec2<u32>(start + (cell + n - start % n) % n, n);
}

// The pixel's offset of the bundle-to-VPL pairing (issue 48): the frame's offset u plus
// the pixel's entry of a 4×4 Bayer matrix over 16, mod 1. Each pixel's offset is uniform
// over [0, 1) (its estimate unbiased, as with u alone), and every 2×2 block takes u + {0,
// ¼, ½, ¾}, every 4×4 block u + j/16: at n1/n2 = 4 a 2×2 block's pixels pair the bundles
// with all the VPLs and their subpaths instead of the same quarter of them. With one offset
// for the whole image, strategy A connected every pixel to the same n2 of the n1 subpaths,
// and which n2 they were moved the frame's image mean by 0.74% (σ, `cornell`).
fn pixel_pair_offset(px: vec2<i32>) -> f32 {
    let q = vec2<u32>(px) % 4u;
    let bayer = array<u32, 16>(0u, 8u, 2u, 10u, 12u, 4u, 14u, 6u, 3u, 11u, 1u, 9u, 15u, 7u, 13u, 5u);
    return fract(params.pair_offset + f32(bayer[q.y * 4u + q.x]) / 16.0);
}

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let px = vec2<i32>(frag.xy);
    let pos = textureLoad(g_position, px, 0);
    if pos.w == 0.0 {
        if params.has_env == 0u {
            return vec4<f32>(0.0);
        }
        // The environment seen through the pixel centre.
        let size = vec2<f32>(textureDimensions(g_position));
        let ndc = vec2<f32>(frag.x / size.x * 2.0 - 1.0, 1.0 - frag.y / size.y * 2.0);
        let w = params.inv_view_proj * vec4<f32>(ndc, 1.0, 1.0);
        // (Alpha 0: no surface, for the hot-spot control of `frame/bidir/spikes.rs`.)
        return vec4<f32>(env_radiance(normalize(w.xyz / w.w - params.eye)), 0.0);
    }
    let p = pos.xyz;
    let nn = textureLoad(g_normals, px, 0);
    let ns = oct_decode(nn.xy);
    let ng = oct_decode(nn.zw);
    let d = textureLoad(g_diffuse, px, 0);
    let s = textureLoad(g_specular, px, 0);
    var m: Material;
    m.diffuse = d.xyz;
    m.roughness = gbuffer_roughness(d.w);
    m.specular = s.xyz;
    m.fresnel = u32(s.w > 0.5);
    let model = pixel_model(textureLoad(g_emission, px, 0).w, m.diffuse);
    let wo = normalize(params.eye - p);
    let n1 = f32(params.vpls_per_light);
    let n2 = f32(params.bundles);
    let pair_u = pixel_pair_offset(px);
    var sum = vec3<f32>(0.0);

    // One bounce through the VPLs (in mode 2 only those without a bundle strategy).
    let vpl_one = select(0u, params.vpl_count, params.bounces >= 1u);
    for (var i = 0u; i < vpl_one; i++) {
        let v = vpl_at(i);
        let alone = v.pdf < 0.0;
        if params.mode == 2u && !alone {
            continue;
        }
        let to_vpl = v.position - p;
        let d2 = dot(to_vpl, to_vpl);
        let cos13 = abs(dot(to_vpl, v.ng)) / sqrt(d2);
        // Area densities of x1: drawn as a VPL, and as a bundle hit from x3.
        let p1 = n1 * max(v.pdf, 0.0);
        let p2 = bundle_density(to_vpl / sqrt(d2)) * cos13 / d2;
        let area = p1 + select(p2, 0.0, params.mode == 1u);
        let d13 = area * d2 / max(cos13, 1e-6);
        let d10 = area * v.light_dist2 / max(abs(dot(v.ng, v.to_light)), 1e-6);
        let m1 = clamped_model(vpl_material(v), v.model, combine(d10, d13), cos13);
        let min_d2 = select(0.0, params.alone_min_dist2, alone);
        var t = vpl_light(v, m1, p, ns, ng, clamped_model(m, model, d13, dot(ns, wo)), wo, min_d2);
        if max3(t) <= 0.0 {
            continue;
        }
        if params.mode == 0u && params.bundles > 0u && !alone {
            t *= p1 / (p1 + p2);
        }
        sum += t;
    }

    // Three and more bounces, strategy B: the light subpaths' vertices y_j (j ≥ 2) as VPLs
    // at x3; n1 subpaths a light, one from each first VPL (each carrying its VPL's share).
    let mis = params.mode == 0u;
    let tiny_d2 = params.min_dist2 * 1e-6;
    if mis && params.bundles > 0u && params.bounces >= 2u {
        let end = params.vpl_count + params.sub_count;
        let deep = min(2u * params.vpl_count, end);
        // The vertices of order 3 and more, interleaved over pixel blocks (below); one loop
        // and one call site, so the exact models' code is inlined once.
        let il = interleave(px, deep);
        let near = deep - params.vpl_count;
        let far = select(0u, (end - il.x + il.y - 1u) / il.y, il.x < end);
        for (var k = 0u; k < near + far; k++) {
            var i = params.vpl_count + k;
            var w = 1.0;
            if k >= near {
                i = il.x + (k - near) * il.y;
                w = f32(il.y);
            }
            sum += subpath_vertex_light(i, p, ns, ng, m, model, wo, n1, tiny_d2) * w;
        }
    }

    // The sky's direct light through the bundles' misses has a control variate (issue 48):
    // its diffuse lobe's unshadowed light in closed form plus, per bundle, that lobe's
    // sampled unshadowed light subtracted (below), so that the bundles estimate only the
    // part the scene occludes. Unbiased up to the irradiance table's interpolation of an
    // image sky (exact for a constant one) and a shading normal off the geometric one; an
    // open scene's frame then no longer varies with how its few bundle directions fall on
    // the sky (`docs/bench/bidir-depth.md`).
    if params.has_env != 0u && params.bundles > 0u {
        sum += params.sky_cv * sky_diffuse_unshadowed(m, ns, wo);
    }

    // The glossy lobe's share of the sky's light (issue 47), from the bundles' directions.
    var sky = SkyShare(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));

    // Camera subpaths through the ray bundles.
    let bundle_one = params.mode != 1u && params.bounces >= 1u;
    if params.bundles > 0u && (bundle_one || params.bounces >= 2u || params.has_env != 0u) {
        for (var b = 0u; b < params.bundles; b++) {
            let bv = bundle_views[b];
            let c = dot(ng, bv.dir);
            if c == 0.0 {
                continue;
            }
            let sgn = select(-1.0, 1.0, c > 0.0);
            let dir = bv.dir * sgn;
            if max3(bsdf_eval(m, ns, wo, dir)) <= 0.0 {
                continue;
            }
            let texel = bv.depth_range / f32(bv.res);
            // Fragments whose plane passes within a quarter texel of x3 are its own surface
            // (or, on a tessellated curve, a neighbouring triangle of it; the pixel-centre
            // samples lie up to 0.71 texels off the ray): skipped, at the cost of hits in the
            // last quarter texel of a corner.
            let hit = trace_bundle(bv, p, dir, 0.02 * texel, 0.25 * texel);
            // The pixel's BSDF towards ω at the bundles' d̂ (eq. 14: n2·p_r), for the sky's
            // glossy share and the two-bounce light (one call site for both).
            var f3b = vec3<f32>(0.0);
            if params.has_env != 0u || (hit.found && params.bounces >= 2u) {
                f3b = eval_clamped(clamped_model(m, model, 1.0 / bv.inv_density, dot(ns, wo)), ns, wo, dir);
            }
            if params.has_env != 0u {
                // §6: nothing along ±ω, the environment is seen (the only strategy for it),
                // less the control variate's sample (every bundle's, hit or not: its diffuse
                // lobe's unshadowed light, whose expectation is added per pixel below).
                // The glossy lobe's part is not summed here: `env_glossy_unshadowed` below,
                // times the visibility these directions give it (`sky_share_add`).
                let l_env = env_radiance(dir) * (abs(dot(ns, dir)) * bv.inv_density);
                let fd = pixel_diffuse(m, ns, wo, dir);
                sum -= params.sky_cv * fd * l_env;
                if !hit.found {
                    sum += fd * l_env;
                }
                sky_share_add(&sky, (f3b - fd) * l_env, l_env, !hit.found);
            }
            if !hit.found {
                continue;
            }
            // The fragment's own point (on its surface, up to 0.71 texels off the ray).
            let x2 = node_position(hit.node);
            var ns2 = oct_decode(unpack2x16snorm(hit.node.ns));
            var ng2 = oct_decode(unpack2x16snorm(hit.node.ng));
            if dot(ng2, dir) > 0.0 {
                ng2 = -ng2;
            }
            if dot(ns2, ng2) < 0.0 {
                ns2 = -ns2;
            }
            var m2 = node_material(hit.node);
            var model2 = node_model(hit.node);
            if one_sided_back(m2, oct_decode(unpack2x16snorm(hit.node.ng)), -dir) {
                m2 = without_lobes(m2);
                model2 = 0u;
            }
            // Per bundle sample: |n3·ω|/p_r / n2, times f3 (clamped per path below).
            let weight = abs(dot(ns, dir)) * bv.inv_density;
            let cos23 = -dot(ng2, dir);
            let d23 = x2 - p;
            let d23_2 = dot(d23, d23);
            // One bounce: the lights' direct light at x2.
            if bundle_one {
                for (var j = 0u; j < arrayLength(&lights); j++) {
                    let l = lights[j];
                    if l.kind == 2u {
                        continue;
                    }
                    let to_l = l.position - x2;
                    let dl2 = dot(to_l, to_l);
                    let wl = to_l / sqrt(dl2);
                    let cos2l = dot(wl, ng2);
                    if cos2l <= 0.0 {
                        continue;
                    }
                    let falloff = spot(l, dot(-wl, l.direction));
                    // Area densities of x2: drawn as a VPL of light j, and as this hit.
                    let w = vpl_at(j * params.vpls_per_light).light_flux;
                    let i_sum = (l.intensity.x + l.intensity.y + l.intensity.z) * falloff;
                    var p1 = 0.0;
                    if w > 0.0 && params.mode != 2u {
                        p1 = n1 * i_sum * cos2l / (dl2 * w);
                    }
                    let p2 = max(cos23, 0.0) / (bv.inv_density * d23_2);
                    let d23s = (p1 + p2) * d23_2 / max(cos23, 1e-6);
                    let d20 = (p1 + p2) * dl2 / cos2l;
                    let m3c = clamped_model(m, model, d23s, dot(ns, wo));
                    let m2c = clamped_model(m2, model2, combine(d20, d23s), cos23);
                    let f23 = pair_f(m3c, ns, wo, dir, m2c, ns2, -dir, wl);
                    var t = f23 * weight * abs(dot(ns2, wl)) * l.intensity * (falloff / dl2);
                    if max3(t) <= 0.0 {
                        continue;
                    }
                    t *= light_visibility(l, x2, ng2);
                    if params.mode == 0u {
                        t *= p2 / (p1 + p2);
                    }
                    sum += t;
                }
            }
            // Two bounces: one VPL of every light lights x2, bundle b taking VPL
            // ⌊(b + u)·n1/n2⌋, u the pixel's offset (`pixel_pair_offset`; the VPLs are in
            // stratified order over the RSM, so every part of it is paired; each VPL is
            // picked n2/n1 times in expectation).
            if params.bounces >= 2u && params.vpls_per_light > 0u {
                let k = min(u32((f32(b) + pair_u) * n1 / n2), params.vpls_per_light - 1u);
                // Strategy A's area density of x2 (MIS against B; no clamp with MIS).
                let pa = max(cos23, 0.0) / (bv.inv_density * d23_2);
                let min_d2 = select(params.min_dist2, tiny_d2, mis);
                for (var j = 0u; j * params.vpls_per_light < params.vpl_count; j++) {
                    // The VPL y1 (o = 1), then (three or more bounces) the vertices y2, y3, …
                    // of the light subpath continued from it for this bundle (`subpaths.rs`),
                    // linked by their records' `light_dist2` (0 ends the subpath;
                    // `light_flux` holds the vertex's continuation q for the MIS weight; y1
                    // continues without roulette, q = 1). One loop: one call site.
                    let first = j * params.vpls_per_light + k;
                    var row = first;
                    for (var o = 1u; o < params.bounces; o++) {
                        let y = vpl_at(row);
                        let my = unclamped_model(vpl_material(y), y.model);
                        var t = vpl_light(y, my, x2, ns2, ng2, unclamped_model(m2, model2), -dir, min_d2);
                        if mis && max3(t) > 0.0 {
                            let q = select(y.light_flux, 1.0, o == 1u);
                            t *= pa / (pa + b_density(y, q, x2, ng2));
                        }
                        sum += f3b * weight * t * n1;
                        row = select(u32(y.light_dist2 + 0.5), params.vpl_count + first, o == 1u);
                        if row == 0u {
                            break;
                        }
                    }
                }
            }
        }
    }
    if params.has_env != 0u && params.bundles > 0u {
        sum += env_glossy_unshadowed(m, ns, ng, wo) * env_glossy_visibility(sky.glit, sky.gun, sky.clit, sky.cun);
    }
    // Alpha: 1 + the pixel's distance from the eye (over 0.5: a surface, for `spikes.rs`;
    // the distance for the interleaved vertices' filter, `interleave.rs`).
    return vec4<f32>(sum, 1.0 + length(params.eye - p));
}
