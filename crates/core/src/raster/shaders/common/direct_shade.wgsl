// Deferred direct lighting of one G-buffer sample, shared by the full-screen passes
// (direct.wgsl) and the edge-sample compute passes (direct_edges.wgsl): the radiance the
// surface emits towards the eye, plus
// - per point or spot light f(wo, wi)·|cos θi|·I(−wi)/d² times the PCF shadow-map visibility;
// - per directional light (the sun) f·|cos θi|·E times its orthographic shadow map's
//   visibility, the penumbra widened by its disc of directions (percentage-closer soft
//   shadows) unless the record says parallel (`cos_inner` 1);
// - per point drawn on the emitters (`area_count` records, raster/direct.rs
//   `SampledLightRaw`), an oriented point light with a cosine lobe:
//   f·|cos θi|·I·cos θ'/(d² + r²) times one bilinear tap of its cube shadow map, where r² is
//   the radius² of the disc of the area the point stands for (the disc's on-axis form factor:
//   bounded where d → 0, exact for the disc there, ≈ r²/d² dark relative elsewhere); with
//   `ratio`, the diffuse lobe of the emitting objects held as `polygons` (untextured, few;
//   scene/emitters/groups.rs takes them by power, and draws the points stratified over
//   them and the other emitters) is the ratio estimator, per object (`groups`): its
//   unshadowed diffuse light in closed form (Lambert's formula for the irradiance of a
//   polygon clipped to the horizon, i.e. linearly transformed cosines for the diffuse lobe,
//   the Fresnel coupling taken at the object's mean direction) times Σ f_d·G·V / Σ f_d·G
//   over the points drawn on that object; the other emitters' points are summed as they
//   are, or with `ratio` and a per-pixel emitter tree (`tree_triangles`), by the ratio
//   estimator too: their unshadowed light (both lobes) from samples each shading point
//   draws by importance from a light BVH (emitter_tree.wgsl) times Σ f·G·V / Σ f·G over
//   their shadow-mapped points (one ratio for all of them: where one such emitter is hidden
//   and another not, the ratio mixes their visibilities by the points' weights);
// - per direction drawn from the sky (`sky_count` records), a distant light of irradiance
//   L/(n·p) with one tap of its orthographic shadow map (with `ratio`: its visibility over
//   the cone of directions it stands for, sky_cone.wgsl); with `ratio` the diffuse lobe is
//   the ratio estimator (Heitz, Hill & McGuire 2018): the unshadowed diffuse light from the
//   irradiance table times Σ f_d·cos·E·V / Σ f_d·cos·E over the directions (exact where
//   every direction is unoccluded), the glossy lobe the ratio estimator too
//   (env_glossy.wgsl: its unshadowed light by a quadrature of the lobe);
// - where no surface covers the sample, the environment seen along the view ray
//   (`background`).

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var<storage, read> shadow_views: array<mat4x4<f32>>;
@group(0) @binding(3) var shadow_maps: texture_depth_2d_array;
@group(0) @binding(4) var shadow_sampler: sampler_comparison;
// Sub-pixel visibility taps per axis where a pixel-centre sample lies in a shadow's
// penumbra (1: none).
@group(0) @binding(5) var<uniform> penumbra_taps: vec4<u32>;
// The sampled lights: emitter points then sky directions, `SAMPLE_TEXELS` texels a row.
@group(0) @binding(6) var sample_records: texture_2d<f32>;
// World -> clip of the sampled lights' shadow layers, one matrix (four column texels) a row.
@group(0) @binding(7) var sample_views: texture_2d<f32>;
@group(0) @binding(8) var sample_maps: texture_depth_2d_array;
// The environment's radiance table (equirectangular; 1×1 for a constant colour or none)
// and its irradiance table (same mapping).
@group(0) @binding(9) var env_table: texture_2d<f32>;
@group(0) @binding(10) var irradiance_table: texture_2d<f32>;
@group(0) @binding(11) var<uniform> direct_params: DirectParams;
// The emitting polygons (`polygons` of them), triangles or convex quads: three corners (w
// of the first: 1 when two-sided; of the second: 1 for a quad; of the third: the bound of
// the in-plane test below, `EmitterPolygon::in_plane_bound`), the radiance and a quad's
// fourth corner, five texels a row, group by group.
@group(0) @binding(12) var emitter_polygons: texture_2d<f32>;
@group(1) @binding(0) var g_position: texture_2d<f32>;
@group(1) @binding(1) var g_normals: texture_2d<f32>;
@group(1) @binding(2) var g_diffuse: texture_2d<f32>;
@group(1) @binding(3) var g_specular: texture_2d<f32>;
@group(1) @binding(4) var g_emission: texture_2d<f32>;

// `DirectParamsRaw` of raster/direct.rs.
struct DirectParams {
    area_count: u32,
    sky_count: u32,
    // 1: the environment is seen where no surface covers a sample.
    background: u32,
    // 1: the diffuse light of the sky and of the emitter polygons by the ratio estimator.
    ratio: u32,
    // (cos, sin) of the environment's rotation about +y.
    env_cos: f32,
    env_sin: f32,
    // Emitting polygons in `emitter_polygons` (0: their light is sampled only).
    polygons: u32,
    // The emitting objects (groups) the polygons form, at most `MAX_GROUPS`.
    groups: u32,
    // The per-pixel emitter tree (emitter_tree.wgsl): its nodes, its triangles (0: none),
    // the samples a shading point draws from it and their seed.
    tree_nodes: u32,
    tree_triangles: u32,
    pixel_samples: u32,
    seed: u32,
    // Per group its points [x, y) (the first records, group by group) and its polygons
    // [z, w).
    group_ranges: array<vec4<u32>, MAX_GROUPS>,
}

// Which kinds of light the pipeline is compiled for (raster/direct.rs `DirectVariant`):
// false leaves out the code of a kind the scene lacks. lavapipe runs both sides of a
// branch whose condition varies per lane and pays for code behind uniform branches too
// (registers, inlined loops): a scene with one point light paid ~2x for the sampled
// lights, the sun's soft shadows and the environment (docs/bench/lights-gpu.md).
// Points on the emitters or directions of the sky (`area_count`, `sky_count`).
override SAMPLED_LIGHTS: bool = true;
// Directional lights (`Light.kind` 2).
override DIRECTIONAL_LIGHTS: bool = true;
// The environment behind uncovered samples (`background`).
override BACKGROUND: bool = true;
// Some material emits (the G-buffer's emission target is read; else it is all zero).
override EMISSION: bool = true;
// Some material has a specular lobe or a Fresnel-weighted diffuse lobe (else every G-buffer
// sample has specular 0 and no Fresnel flag, and the BSDF is Lambert's alone).
override GLOSSY: bool = true;
// The polygon groups' glossy lobe in closed form (ltc_direct.wgsl; else their points' sum):
// the scene has polygon groups and glossy materials.
override LTC_LIGHTS: bool = true;
// Round emitters (spheres) among the polygon groups (round_lights.wgsl).
override ROUND_LIGHTS: bool = true;

// Most polygon groups (`MAX_GROUPS` of raster/direct.rs).
const MAX_GROUPS: u32 = 8u;

const SAMPLE_TEXELS: u32 = 4u;
const TWO_PI: f32 = 6.28318530718;

// One G-buffer sample: world position (w = coverage, 0 where no surface was hit),
// octahedral shading and geometric normals, diffuse + roughness, specular + Fresnel flag,
// the radiance emitted towards the eye; and for a sample without a surface, the unit
// direction of its view ray (set by the caller, for the environment behind it).
struct GSample {
    position: vec4<f32>,
    normals: vec4<f32>,
    diffuse: vec4<f32>,
    specular: vec4<f32>,
    emission: vec4<f32>,
    ray: vec3<f32>,
}

fn load_sample(px: vec2<i32>) -> GSample {
    var g: GSample;
    g.position = textureLoad(g_position, px, 0);
    g.normals = textureLoad(g_normals, px, 0);
    g.diffuse = textureLoad(g_diffuse, px, 0);
    g.specular = textureLoad(g_specular, px, 0);
    if EMISSION {
        g.emission = textureLoad(g_emission, px, 0);
    }
    return g;
}

// The unit direction of the view ray through window position `xy` (pixels) of the view
// (for the environment behind samples that no surface covers).
fn view_ray(xy: vec2<f32>) -> vec3<f32> {
    let size = vec2<f32>(textureDimensions(g_position));
    let ndc = vec2<f32>(xy.x / size.x * 2.0 - 1.0, 1.0 - xy.y / size.y * 2.0);
    let w = view.inv_view_proj * vec4<f32>(ndc, 1.0, 1.0);
    return normalize(w.xyz / w.w - view.eye);
}

// The environment's frame: world direction `d` rotated back about +y.
fn env_local(d: vec3<f32>) -> vec3<f32> {
    let c = direct_params.env_cos;
    let s = direct_params.env_sin;
    return vec3<f32>(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
}

// Texel coordinates (continuous, texel centres at + 0.5) of local direction `l` in a
// `size` equirectangular table (`Environment::uv`).
fn env_st(l: vec3<f32>, size: vec2<u32>) -> vec2<f32> {
    let sin_t = sqrt(l.x * l.x + l.z * l.z);
    var u = atan2(l.x, -l.z) / TWO_PI;
    u = u - floor(u);
    let v = atan2(sin_t, l.y) / PI;
    return vec2<f32>(u, v) * vec2<f32>(size);
}

// Radiance of the environment from world direction `d` (`Environment::radiance`: the texel
// it falls in).
fn env_radiance(d: vec3<f32>) -> vec3<f32> {
    let size = textureDimensions(env_table);
    let st = env_st(env_local(d), size);
    let x = min(u32(st.x), size.x - 1u);
    let y = min(u32(st.y), size.y - 1u);
    return textureLoad(env_table, vec2<u32>(x, y), 0).xyz;
}

// The environment's irradiance on a surface facing world direction `n`, bilinear in the
// table (`Environment::irradiance_table`: columns at the radiance table's longitudes,
// wrapping; rows from pole to pole).
fn env_irradiance(n: vec3<f32>) -> vec3<f32> {
    let size = textureDimensions(irradiance_table);
    let uv = env_st(env_local(n), vec2<u32>(1u, 1u));
    let st = vec2<f32>(uv.x * f32(size.x) - 0.5, uv.y * f32(size.y - 1u));
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

// A shadow-map layer and its world -> clip matrix.
struct ShadowView {
    layer: u32,
    m: mat4x4<f32>,
}

// The shadow view of light `l` that sees `p`: `known` when it is that layer (a pixel's
// points nearly always share their centre's cube face), else read from `shadow_views`.
// lavapipe reads storage buffers slowly where the index varies per pixel, and the penumbra
// test and its taps need up to 21 views a pixel.
fn view_at(l: Light, p: vec3<f32>, known: ShadowView) -> ShadowView {
    let layer = shadow_layer_of(l.first_layer, l.layers, p - l.position);
    if layer == known.layer {
        return known;
    }
    return ShadowView(layer, shadow_views[layer]);
}

// The shadow view of light `l` that sees `p`.
fn view_of(l: Light, p: vec3<f32>) -> ShadowView {
    let layer = shadow_layer_of(l.first_layer, l.layers, p - l.position);
    return ShadowView(layer, shadow_views[layer]);
}

// Shadow-map visibility of `p` in view `sv` (common/shadow_lookup.wgsl).
fn visibility(sv: ShadowView, p: vec3<f32>) -> f32 {
    return shadow_pcf(shadow_maps, shadow_sampler, sv.m, sv.layer, p);
}

// Whether `q` (a neighbour's position, w = coverage) lies on the tangent plane (geometric
// normal `ng`) of the surface point `p`: within ~6° of it, seen from `p`.
fn on_plane(p: vec3<f32>, ng: vec3<f32>, q: vec4<f32>) -> bool {
    let d = q.xyz - p;
    return q.w > 0.0 && abs(dot(d, ng)) <= 0.1 * length(d);
}

// Whether light `l`'s visibility varies over the pixel footprint (steps `dx`, `dy`) around
// `q`, whose PCF visibility is `v`: fractional there, or a single bilinear tap at a corner
// of the footprint that sees otherwise (a shadow edge sharper than a pixel).
// `sv` is the view of `q`.
fn penumbra(l: Light, sv: ShadowView, q: vec3<f32>, v: f32, dx: vec3<f32>, dy: vec3<f32>) -> bool {
    if v > 0.0 && v < 1.0 {
        return true;
    }
    for (var c = 0u; c < 4u; c++) {
        let u = vec2<f32>(f32(c & 1u), f32(c >> 1u)) - 0.5;
        let corner = q + u.x * dx + u.y * dy;
        let cv = view_at(l, corner, sv);
        if shadow_tap(shadow_maps, shadow_sampler, cv.m, cv.layer, corner) != v {
            return true;
        }
    }
    return false;
}

// A pixel's footprint on the tangent plane of its centre sample: one-pixel steps of the
// position and of the shading normal, and the sub-pixel taps per axis (1: the centre only).
struct Footprint {
    dx: vec3<f32>,
    dy: vec3<f32>,
    dndx: vec3<f32>,
    dndy: vec3<f32>,
    taps: u32,
}

// Whether `l` is a directional light (never in a pipeline compiled without them).
fn is_directional(l: Light) -> bool {
    return DIRECTIONAL_LIGHTS && l.kind == 2u;
}

// Direct radiance towards the eye from sample `g` (0 where it has no surface).
fn shade(g: GSample) -> vec3<f32> {
    var centre: Footprint;
    centre.taps = 1u;
    return shade_pixel(g, centre);
}

// Unshadowed light from `l` scattered towards the eye at `p` (shading normal `ns`,
// geometric `ng`): f(wo, wi)·|cos θi|·I(−wi)/d², 0 behind the geometry.
// A directional light's: f(wo, wi)·|cos θi|·E along its axis.
fn light_term(l: Light, m: Material, p: vec3<f32>, ns: vec3<f32>, ng: vec3<f32>) -> vec3<f32> {
    var wi = -l.direction;
    var li = l.intensity;
    if !is_directional(l) {
        let to_light = l.position - p;
        let dist2 = dot(to_light, to_light);
        wi = to_light * inverseSqrt(dist2);
        li = l.intensity / dist2;
        if l.kind == 1u {
            li *= cone_falloff(dot(-wi, l.direction), l.cos_inner, l.cos_outer);
        }
    }
    // Reflection only: the light must be on the viewer's side of the geometry.
    if dot(wi, ng) <= 0.0 {
        return vec3<f32>(0.0);
    }
    let wo = normalize(view.eye - p);
    return direct_bsdf(m, ns, wo, wi) * abs(dot(ns, wi)) * li;
}

// The pixel's BSDF (`exact_eval`: its exact model, or the uber BSDF), compiled as Lambert's
// lobe alone where no material has another (`GLOSSY` false: specular 0, no Fresnel flag and
// no exact model, so the coupling is exactly 1).
fn direct_bsdf(m: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if GLOSSY {
        return exact_eval(m, n, wo, wi);
    }
    if dot(n, wo) * dot(n, wi) <= 0.0 {
        return vec3<f32>(0.0);
    }
    return m.diffuse / PI;
}

// The unit direction from `p` towards light `l` and its distance (a directional light's
// along its axis, at the depth of its orthographic view).
fn towards_light(l: Light, p: vec3<f32>) -> vec4<f32> {
    if is_directional(l) {
        return vec4<f32>(-l.direction, l.depth_extent);
    }
    let to_light = l.position - p;
    let d = length(to_light);
    return vec4<f32>(to_light / d, d);
}

// The normal offset of `p` (geometric normal `ng`) before a shadow lookup towards light `l`:
// about one shadow texel at grazing light, against acne.
fn shadow_offset(l: Light, p: vec3<f32>, ng: vec3<f32>) -> vec3<f32> {
    let t = towards_light(l, p);
    let cos_g = dot(t.xyz, ng);
    if is_directional(l) {
        return ng * (l.texel_scale * (1.0 - cos_g) + 1e-4 * l.depth_extent);
    }
    return ng * (l.texel_scale * t.w * (1.0 - cos_g) + 1e-4 * t.w);
}

// A directional light's visibility at `q` in view `sv` with its penumbra widened by its
// disc of directions (half angle θ): percentage-closer soft shadows. The blockers are
// searched within the widest penumbra (the receiver's depth in the view times tan θ),
// their mean depth gives the penumbra's radius (receiver − blocker)·tan θ, and the
// visibility is the mean of 16 bilinear taps on a disc of that radius (at least the 3×3
// PCF's). Parallel light (`cos_inner` 1) or a penumbra under a texel: the PCF.
fn sun_visibility(l: Light, sv: ShadowView, q: vec3<f32>) -> f32 {
    let c = clamp(l.cos_inner, 0.0, 1.0);
    let pcf = shadow_pcf(shadow_maps, shadow_sampler, sv.m, sv.layer, q);
    if c >= 1.0 {
        return pcf;
    }
    let tan_t = sqrt(1.0 - c * c) / max(c, 1e-4);
    let clip = sv.m * vec4<f32>(q, 1.0);
    let uv = clip.xy * vec2<f32>(0.5, -0.5) + 0.5;
    let size = f32(textureDimensions(shadow_maps).x);
    // World units per texel and per unit of depth.
    let texel = l.texel_scale;
    let depth = l.depth_extent;
    let z = clip.z;
    let search = min(z * depth * tan_t / texel, 32.0);
    if search < 1.0 {
        return pcf;
    }
    // Blocker search: 16 depths on a 4×4 grid over the search square.
    var blockers = 0.0;
    var zb = 0.0;
    for (var j = 0u; j < 16u; j++) {
        let o = (vec2<f32>(f32(j % 4u), f32(j / 4u)) - 1.5) / 1.5 * search;
        let t = vec2<i32>(floor(uv * size + o));
        let d = textureLoad(shadow_maps, t, sv.layer, 0);
        if d < z {
            blockers += 1.0;
            zb += d;
        }
    }
    if blockers == 0.0 {
        return pcf;
    }
    zb /= blockers;
    let radius = min((z - zb) * depth * tan_t / texel, 32.0);
    if radius < 1.0 {
        return pcf;
    }
    // 16 bilinear taps on a Vogel disc of the penumbra's radius.
    var v = 0.0;
    for (var j = 0u; j < 16u; j++) {
        let r = sqrt((f32(j) + 0.5) / 16.0) * radius;
        let a = f32(j) * 2.39996323;
        let o = vec2<f32>(cos(a), sin(a)) * r / size;
        v += textureSampleCompareLevel(shadow_maps, shadow_sampler, uv + o, sv.layer, z);
    }
    return v / 16.0;
}

// Shadow-map visibility of light `l` at `q` in view `sv`.
fn light_visibility(l: Light, sv: ShadowView, q: vec3<f32>) -> f32 {
    if is_directional(l) {
        return sun_visibility(l, sv, q);
    }
    return visibility(sv, q);
}

// The point and shading normal of sub-pixel offset `u` (in pixels from the centre).
fn footprint_point(p: vec3<f32>, fp: Footprint, u: vec2<f32>) -> vec3<f32> {
    return p + u.x * fp.dx + u.y * fp.dy;
}

fn footprint_normal(ns: vec3<f32>, fp: Footprint, u: vec2<f32>) -> vec3<f32> {
    return normalize(ns + u.x * fp.dndx + u.y * fp.dndy);
}

fn tap_offset(j: u32, taps: u32) -> vec2<f32> {
    return (vec2<f32>(f32(j % taps), f32(j / taps)) + 0.5) / f32(taps) - 0.5;
}

// Whether light `l`'s unshadowed term is flat enough across footprint `fp` at `p` that the
// centre's value is its box filter: a Lambertian surface (no specular lobe, no Fresnel
// coupling), a footprint under 3% of the distance to the light and a shading normal turning
// under 0.03 rad across it, and for a spot light a point well inside the inner cone. The term is then cos θ·I/d²
// times a constant, whose box-filter error relative to the centre value is about
// (s/d)²/4 ≈ 2·10⁻⁴ (s: the footprint's size), below what the corners' rule resolves.
fn flat_across(l: Light, m: Material, p: vec3<f32>, fp: Footprint) -> bool {
    if GLOSSY && (max3(m.specular) > 0.0 || m.fresnel != 0u) {
        return false;
    }
    if length(fp.dndx) + length(fp.dndy) > 0.03 {
        return false;
    }
    // A directional light's term varies with the normal alone.
    if is_directional(l) {
        return true;
    }
    let to_light = l.position - p;
    let d = length(to_light);
    let s = length(fp.dx) + length(fp.dy);
    if s > 0.03 * d {
        return false;
    }
    return l.kind != 1u || dot(-to_light / d, l.direction) >= l.cos_inner + s / d;
}

// Direct radiance of the pixel of sample `g` with footprint `fp`: per light, the unshadowed
// term box-filtered over the footprint times the visibility. The term's mean is
// (2·centre + mean of the 4 corners)/3, exact for shading quadratic across the pixel,
// unless the corners reveal more curvature than that (a highlight, a light close by):
// then the mean of `taps`² stratified points. The visibility is the centre's PCF unless a
// shadow edge crosses the pixel or its PCF kernel (`penumbra`): then the mean over the
// same points. With one tap, the centre sample alone (a sub-pixel sample's own shading).
fn shade_pixel(g: GSample, fp: Footprint) -> vec3<f32> {
    if g.position.w == 0.0 {
        if BACKGROUND && direct_params.background != 0u {
            return env_radiance(g.ray);
        }
        return vec3<f32>(0.0);
    }
    let p = g.position.xyz;
    let ns = oct_decode(g.normals.xy);
    let ng = oct_decode(g.normals.zw);
    let m = sample_material(g);
    let wo = normalize(view.eye - p);
    var sum = g.emission.xyz;
    if SAMPLED_LIGHTS {
        // A sub-pixel sample (one tap) of a pixel of `taps`² samples draws its share of the
        // pixel's tree samples: the pixel's mean has as many as a pixel-centre sample's.
        let t = penumbra_taps.x;
        let count = direct_params.pixel_samples;
        sum += sampled_light(p, ns, ng, m, wo, select(count, max(count / (t * t), 1u), fp.taps == 1u));
    }
    let taps = fp.taps;
    for (var i = 0u; i < arrayLength(&lights); i++) {
        let l = lights[i];
        var term = light_term(l, m, p, ns, ng);
        if taps > 1u && !flat_across(l, m, p, fp) {
            var corners = vec3<f32>(0.0);
            for (var c = 0u; c < 4u; c++) {
                let u = vec2<f32>(f32(c & 1u), f32(c >> 1u)) - 0.5;
                corners += light_term(l, m, footprint_point(p, fp, u), footprint_normal(ns, fp, u), ng);
            }
            corners *= 0.25;
            if max3(abs(corners - term)) > 0.05 * max3(corners + term) {
                var mean = vec3<f32>(0.0);
                for (var j = 0u; j < taps * taps; j++) {
                    let u = tap_offset(j, taps);
                    mean += light_term(l, m, footprint_point(p, fp, u), footprint_normal(ns, fp, u), ng);
                }
                term = mean / f32(taps * taps);
            } else {
                term = (2.0 * term + corners) / 3.0;
            }
        }
        if max3(term) <= 0.0 {
            continue;
        }
        // Normal offset of about one shadow texel against acne on surfaces at grazing light.
        let offset = shadow_offset(l, p, ng);
        let sv = view_of(l, p + offset);
        var v = light_visibility(l, sv, p + offset);
        if taps > 1u && penumbra(l, sv, p + offset, v, fp.dx, fp.dy) {
            v = 0.0;
            for (var j = 0u; j < taps * taps; j++) {
                let q = footprint_point(p + offset, fp, tap_offset(j, taps));
                v += light_visibility(l, view_at(l, q, sv), q);
            }
            v /= f32(taps * taps);
        }
        sum += term * v;
    }
    return sum;
}

// The uber material of sample `g`, with Mitsuba's exact model in its place where it has
// one (exact_models.wgsl: loaded here for the lobes' evaluations that follow).
fn sample_material(g: GSample) -> Material {
    var m: Material;
    m.diffuse = g.diffuse.xyz;
    m.roughness = gbuffer_roughness(g.diffuse.w);
    m.specular = g.specular.xyz;
    m.fresnel = u32(g.specular.w > 0.5);
    exact_load(g.emission.w, m.diffuse);
    return m;
}

// World -> clip of sampled-light shadow layer `layer`.
fn sample_view(layer: u32) -> mat4x4<f32> {
    return mat4x4<f32>(
        textureLoad(sample_views, vec2<u32>(0u, layer), 0),
        textureLoad(sample_views, vec2<u32>(1u, layer), 0),
        textureLoad(sample_views, vec2<u32>(2u, layer), 0),
        textureLoad(sample_views, vec2<u32>(3u, layer), 0),
    );
}

// The diffuse lobe of `bsdf_eval` alone (Lambert with its Fresnel coupling).
fn diffuse_eval(m: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let co = dot(n, wo);
    let ci = dot(n, wi);
    if exact_on {
        return model_diffuse(exact_model, n, wo, wi);
    }
    if co * ci <= 0.0 || max3(m.diffuse) <= 0.0 {
        return vec3<f32>(0.0);
    }
    if !GLOSSY {
        return m.diffuse / PI;
    }
    let one_minus_avg = vec3<f32>(1.0) - fresnel_avg(m);
    let num = (vec3<f32>(1.0) - fresnel_spec(m, abs(co))) * (vec3<f32>(1.0) - fresnel_spec(m, abs(ci)));
    let coupling = select(vec3<f32>(0.0), num / one_minus_avg, one_minus_avg > vec3<f32>(1e-6));
    return m.diffuse / PI * coupling;
}

// θ/sin θ for the angle θ between two unit vectors of cosine `x`: the rational fit of Hill &
// Heitz (2016, "Real-time area lighting: a journey from research to production"), relative
// error below 2e-6 over x in [−1, 1] (checked against acos in float64), in place of an
// atan2, a length and a division per edge.
fn theta_over_sin(x: f32) -> f32 {
    let y = abs(x);
    let a = 0.8543985 + (0.4965155 + 0.0145206 * y) * y;
    let b = 3.4175940 + (4.1616724 + y) * y;
    let v = a / b;
    return TWO_PI * select(0.5 * inverseSqrt(max(1.0 - x * x, 1e-7)) - v, v, x > 0.0);
}

// Lambert's edge term θ·û of the arc from unit vector `u` to unit vector `w`.
fn edge_vector(u: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    return cross(u, w) * theta_over_sin(dot(u, w));
}

// Lambert's edge term of the horizon's arc from unit vector `u` to unit vector `w`, where a
// clipped polygon leaves and re-enters the hemisphere, with θ from atan2: these two can be
// nearly opposite (a receiver close to the polygon's plane, e.g. next to an emitting box's
// edge), where θ/sin θ's fit is clamped (sin θ under 3e-4) and the small terms of the
// clipped edges must cancel the arc's large one.
fn arc_vector(u: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    let c = cross(u, w);
    let s = length(c);
    if s <= 0.0 {
        return vec3<f32>(0.0);
    }
    return c * (atan2(s, dot(u, w)) / s);
}

// Adds the part of the edge `p` → `q` (heights `dp`, `dq` above the horizon) that lies above
// the horizon to `phi`, and records where the polygon leaves (`exit`) or re-enters
// (`entry`) the hemisphere.
fn clipped_edge(
    p: vec3<f32>,
    q: vec3<f32>,
    dp: f32,
    dq: f32,
    phi: ptr<function, vec3<f32>>,
    exit: ptr<function, vec3<f32>>,
    entry: ptr<function, vec3<f32>>,
) {
    if dp > 0.0 && dq > 0.0 {
        *phi += edge_vector(normalize(p), normalize(q));
    } else if dp > 0.0 {
        let x = normalize(mix(p, q, dp / (dp - dq)));
        *phi += edge_vector(normalize(p), x);
        *exit = x;
    } else if dq > 0.0 {
        let x = normalize(mix(p, q, dp / (dp - dq)));
        *phi += edge_vector(x, normalize(q));
        *entry = x;
    }
}

// Lambert's vector irradiance ½ Σ θᵢ·ûᵢ of the polygon `a`, `b`, `c` (and `d` when `quad`:
// a convex quad), relative to the receiver, of unit radiance, clipped to the hemisphere
// above `n`: its irradiance is |n·Φ|, its direction the mean direction of the light
// arriving from it. Convex, it leaves and re-enters the hemisphere once at most. Written
// without arrays: with the clipped polygon in a private array, lavapipe spent ~50 ms a
// polygon a frame at 640×480 here, about three times as long (docs/bench/lights-gpu.md).
fn polygon_vector(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, d: vec3<f32>, quad: bool, n: vec3<f32>) -> vec3<f32> {
    let da = dot(a, n);
    let db = dot(b, n);
    let dc = dot(c, n);
    let dd = select(dc, dot(d, n), quad);
    if da > 0.0 && db > 0.0 && dc > 0.0 && dd > 0.0 {
        let ua = normalize(a);
        let ub = normalize(b);
        let uc = normalize(c);
        var phi = edge_vector(ua, ub) + edge_vector(ub, uc);
        if quad {
            let ud = normalize(d);
            phi += edge_vector(uc, ud) + edge_vector(ud, ua);
        } else {
            phi += edge_vector(uc, ua);
        }
        return 0.5 * phi;
    }
    if da <= 0.0 && db <= 0.0 && dc <= 0.0 && dd <= 0.0 {
        return vec3<f32>(0.0);
    }
    // Partly above: the clipped edges, then the horizon's arc from the exit to the entry.
    var phi = vec3<f32>(0.0);
    var exit = vec3<f32>(0.0);
    var entry = vec3<f32>(0.0);
    clipped_edge(a, b, da, db, &phi, &exit, &entry);
    clipped_edge(b, c, db, dc, &phi, &exit, &entry);
    if quad {
        clipped_edge(c, d, dc, dd, &phi, &exit, &entry);
        clipped_edge(d, a, dd, da, &phi, &exit, &entry);
    } else {
        clipped_edge(c, a, dc, da, &phi, &exit, &entry);
    }
    return 0.5 * (phi + arc_vector(exit, entry));
}

// The unshadowed diffuse light at `p` of the emitter polygons [`first`, `end`) (one group:
// see the header).
fn polygons_diffuse(p: vec3<f32>, ns: vec3<f32>, m: Material, wo: vec3<f32>, first: u32, end: u32) -> vec3<f32> {
    var e = vec3<f32>(0.0);
    var dir = vec3<f32>(0.0);
    for (var t = first; t < end; t++) {
        let t0 = textureLoad(emitter_polygons, vec2<u32>(0u, t), 0);
        let t1 = textureLoad(emitter_polygons, vec2<u32>(1u, t), 0);
        var phi = vec3<f32>(0.0);
        if ROUND_LIGHTS && t1.w > 1.5 {
            // A sphere (round_lights.wgsl).
            phi = round_vector(p, t, ns);
        } else {
            let a = t0.xyz - p;
            let b = t1.xyz - p;
            let t2 = textureLoad(emitter_polygons, vec2<u32>(2u, t), 0);
            let c = t2.xyz - p;
            // A one-sided emitter lights its front side only. A receiver in the polygon's
            // plane (within the bound in t2.w: the plane 1e-4 of the polygon's size thick)
            // gets no light from it, every direction to it grazing: its own face, or one
            // flush with it, which rounding would put just in front, lit as if the polygon
            // filled its hemisphere.
            let height = dot(a, cross(b - a, c - a));
            if (t0.w < 0.5 && height >= 0.0) || abs(height) <= t2.w {
                continue;
            }
            let quad = t1.w > 0.5;
            var d = c;
            if quad {
                d = textureLoad(emitter_polygons, vec2<u32>(4u, t), 0).xyz - p;
            }
            phi = polygon_vector(a, b, c, d, quad, ns);
        }
        let en = dot(ns, phi);
        let l = textureLoad(emitter_polygons, vec2<u32>(3u, t), 0).xyz;
        e += l * abs(en);
        dir += phi * (select(-1.0, 1.0, en >= 0.0) * (l.x + l.y + l.z));
    }
    let len = length(dir);
    if len <= 0.0 {
        return vec3<f32>(0.0);
    }
    return diffuse_eval(m, ns, wo, dir / len) * e;
}

// The light at `p` of emitter point `i`: its diffuse lobe unshadowed (`fd`), its glossy
// lobe unshadowed (`fs`) and its shadow map's visibility (`v`).
struct PointLight {
    fd: vec3<f32>,
    fs: vec3<f32>,
    v: f32,
}

fn point_light(i: u32, p: vec3<f32>, ns: vec3<f32>, ng: vec3<f32>, m: Material, glossy: Material, wo: vec3<f32>) -> PointLight {
    var out = PointLight(vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    let t0 = textureLoad(sample_records, vec2<u32>(0u, i), 0);
    let to_point = t0.xyz - p;
    let d2 = dot(to_point, to_point);
    let wi = to_point * inverseSqrt(d2);
    let cos_g = dot(wi, ng);
    if cos_g <= 0.0 {
        return out;
    }
    let t1 = textureLoad(sample_records, vec2<u32>(1u, i), 0);
    let t3 = textureLoad(sample_records, vec2<u32>(3u, i), 0);
    var cos_e = -dot(wi, t1.xyz);
    if t3.x > 0.5 {
        cos_e = abs(cos_e);
    }
    if cos_e <= 0.0 {
        return out;
    }
    let t2 = textureLoad(sample_records, vec2<u32>(2u, i), 0);
    let g = t2.xyz * (abs(dot(ns, wi)) * cos_e / (d2 + t2.w));
    out.fd = diffuse_eval(m, ns, wo, wi) * g;
    if GLOSSY && max3(m.specular) > 0.0 {
        out.fs = exact_glossy(glossy, ns, wo, wi) * g;
    }
    if max3(out.fd + out.fs) <= 0.0 {
        return out;
    }
    let dist = sqrt(d2);
    let q = p + ng * (t1.w * dist * (1.0 - cos_g) + 1e-4 * dist);
    let layer = shadow_layer_of(u32(t0.w + 0.5), 6u, q - t0.xyz);
    out.v = shadow_tap(sample_maps, shadow_sampler, sample_view(layer), layer, q);
    return out;
}

// The light of the points drawn on the emitters and of the directions drawn from the sky
// at `p` (see the header).
fn sampled_light(p: vec3<f32>, ns: vec3<f32>, ng: vec3<f32>, m: Material, wo: vec3<f32>, tree_samples: u32) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    // Glossy lobe alone (the diffuse one is summed apart for the ratio estimator).
    var glossy = m;
    glossy.diffuse = vec3<f32>(0.0);
    let has_glossy = GLOSSY && max3(m.specular) > 0.0;
    // The polygon groups' points come first, group by group: per group the ratio estimator.
    var plain = 0u;
    if direct_params.ratio != 0u && direct_params.polygons > 0u {
        for (var g = 0u; g < min(direct_params.groups, MAX_GROUPS); g++) {
            let range = direct_params.group_ranges[g];
            var lit = vec3<f32>(0.0);
            var unshadowed = vec3<f32>(0.0);
            var glit = vec3<f32>(0.0);
            var gun = vec3<f32>(0.0);
            for (var i = range.x; i < range.y; i++) {
                let l = point_light(i, p, ns, ng, m, glossy, wo);
                lit += l.fd * l.v;
                unshadowed += l.fd;
                glit += l.fs * l.v;
                gun += l.fs;
            }
            if LTC_LIGHTS && has_glossy {
                // The glossy lobe in closed form, ratio-estimated (ltc_direct.wgsl).
                sum += ltc_group_glossy(p, ns, m, wo, range, glit, gun, lit, unshadowed);
            } else {
                sum += glit;
            }
            if max3(m.diffuse) > 0.0 {
                sum += polygons_diffuse(p, ns, m, wo, range.z, range.w) * visible_ratio(lit, unshadowed);
            }
            plain = max(plain, range.y);
        }
    }
    if direct_params.ratio != 0u && direct_params.tree_triangles > 0u {
        // The other emitters, selected per shading point: their unshadowed light from the
        // tree (both lobes) times the visibility ratio of their shadow-mapped points,
        // Σ f·G·V / Σ f·G (1 where none lights the point).
        var lit = vec3<f32>(0.0);
        var unshadowed = vec3<f32>(0.0);
        for (var i = plain; i < direct_params.area_count; i++) {
            let l = point_light(i, p, ns, ng, m, glossy, wo);
            lit += (l.fd + l.fs) * l.v;
            unshadowed += l.fd + l.fs;
        }
        sum += tree_light(p, ns, ng, m, wo, tree_samples) * visible_ratio(lit, unshadowed);
    } else {
        // The other points (every point without the ratio estimator), summed as they are.
        for (var i = plain; i < direct_params.area_count; i++) {
            let l = point_light(i, p, ns, ng, m, glossy, wo);
            sum += (l.fd + l.fs) * l.v;
        }
    }
    if direct_params.sky_count == 0u {
        return sum;
    }
    // The sky's sums (sky_cone.wgsl; in ordinary frames each direction's visibility over
    // its cone, shared over the pixel's 2×2 quad where it lies on one plane).
    let sky = sky_pixel_sums(p, ns, ng, m, glossy, wo, has_glossy);
    let lit = sky.lit;
    let unshadowed = sky.unshadowed;
    let glit = sky.glit;
    if direct_params.ratio == 0u {
        return sum + lit + glit;
    }
    if has_glossy {
        sum += env_glossy_unshadowed(m, ns, ng, wo) * env_glossy_visibility(glit, sky.gun, sky.clit, sky.cun);
    }
    // The ratio estimator of the diffuse lobe: its unshadowed light in closed form (the
    // irradiance table; the Fresnel coupling's mean over the incident cosines is 1 − F_avg,
    // exact for a constant sky) times the sampled visibility ratio.
    if max3(m.diffuse) > 0.0 {
        let one_minus_avg = vec3<f32>(1.0) - fresnel_avg(m);
        let coupling = select(vec3<f32>(0.0), (vec3<f32>(1.0) - fresnel_spec(m, abs(dot(ns, wo)))), one_minus_avg > vec3<f32>(1e-6));
        let u = exact_env_diffuse(m.diffuse / PI * coupling, ns, wo) * env_irradiance(ns);
        sum += u * visible_ratio(lit, unshadowed);
    }
    return sum;
}
