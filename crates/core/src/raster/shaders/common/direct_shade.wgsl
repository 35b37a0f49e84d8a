// Deferred direct lighting of one G-buffer sample, shared by the full-screen passes
// (direct.wgsl) and the edge-sample compute passes (direct_edges.wgsl): the sum over lights
// of f(wo, wi)·|cos θi|·I(−wi)/d² times the PCF shadow-map visibility.

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var<storage, read> shadow_views: array<mat4x4<f32>>;
@group(0) @binding(3) var shadow_maps: texture_depth_2d_array;
@group(0) @binding(4) var shadow_sampler: sampler_comparison;
// Sub-pixel visibility taps per axis where a pixel-centre sample lies in a shadow's
// penumbra (1: none).
@group(0) @binding(5) var<uniform> penumbra_taps: vec4<u32>;
@group(1) @binding(0) var g_position: texture_2d<f32>;
@group(1) @binding(1) var g_normals: texture_2d<f32>;
@group(1) @binding(2) var g_diffuse: texture_2d<f32>;
@group(1) @binding(3) var g_specular: texture_2d<f32>;

// One G-buffer sample: world position (w = coverage, 0 where no surface was hit),
// octahedral shading and geometric normals, diffuse + roughness, specular + Fresnel flag.
struct GSample {
    position: vec4<f32>,
    normals: vec4<f32>,
    diffuse: vec4<f32>,
    specular: vec4<f32>,
}

fn load_sample(px: vec2<i32>) -> GSample {
    var g: GSample;
    g.position = textureLoad(g_position, px, 0);
    g.normals = textureLoad(g_normals, px, 0);
    g.diffuse = textureLoad(g_diffuse, px, 0);
    g.specular = textureLoad(g_specular, px, 0);
    return g;
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

// Direct radiance towards the eye from sample `g` (0 where it has no surface).
fn shade(g: GSample) -> vec3<f32> {
    var centre: Footprint;
    centre.taps = 1u;
    return shade_pixel(g, centre);
}

// Unshadowed light from `l` scattered towards the eye at `p` (shading normal `ns`,
// geometric `ng`): f(wo, wi)·|cos θi|·I(−wi)/d², 0 behind the geometry.
fn light_term(l: Light, m: Material, p: vec3<f32>, ns: vec3<f32>, ng: vec3<f32>) -> vec3<f32> {
    let to_light = l.position - p;
    let dist2 = dot(to_light, to_light);
    let wi = to_light * inverseSqrt(dist2);
    // Reflection only: the light must be on the viewer's side of the geometry.
    if dot(wi, ng) <= 0.0 {
        return vec3<f32>(0.0);
    }
    var li = l.intensity / dist2;
    if l.kind == 1u {
        li *= cone_falloff(dot(-wi, l.direction), l.cos_inner, l.cos_outer);
    }
    let wo = normalize(view.eye - p);
    return bsdf_eval(m, ns, wo, wi) * abs(dot(ns, wi)) * li;
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
    if max3(m.specular) > 0.0 || m.fresnel != 0u {
        return false;
    }
    let to_light = l.position - p;
    let d = length(to_light);
    let s = length(fp.dx) + length(fp.dy);
    if s > 0.03 * d || length(fp.dndx) + length(fp.dndy) > 0.03 {
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
        return vec3<f32>(0.0);
    }
    let p = g.position.xyz;
    let ns = oct_decode(g.normals.xy);
    let ng = oct_decode(g.normals.zw);
    var m: Material;
    m.diffuse = g.diffuse.xyz;
    m.roughness = g.diffuse.w;
    m.specular = g.specular.xyz;
    m.fresnel = u32(g.specular.w > 0.5);
    let taps = fp.taps;
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < arrayLength(&lights); i++) {
        let l = lights[i];
        // Kind 2 (directional): not shaded here yet.
        if l.kind == 2u {
            continue;
        }
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
        let to_light = l.position - p;
        let dist = length(to_light);
        let cos_g = dot(to_light / dist, ng);
        let offset = ng * (l.texel_scale * dist * (1.0 - cos_g) + 1e-4 * dist);
        let sv = view_of(l, p + offset);
        var v = visibility(sv, p + offset);
        if taps > 1u && penumbra(l, sv, p + offset, v, fp.dx, fp.dy) {
            v = 0.0;
            for (var j = 0u; j < taps * taps; j++) {
                let q = footprint_point(p + offset, fp, tap_offset(j, taps));
                v += visibility(view_at(l, q, sv), q);
            }
            v /= f32(taps * taps);
        }
        sum += term * v;
    }
    return sum;
}
