// Texture lookups (see crates/core/src/texture.rs and raster/textures.rs): every mip level of
// every texture is a rectangle of an Rgba16Float atlas; wrap (repeat), bilinear weights and
// the blend between levels are done here with the arithmetic of `Texture::sample`, so the
// CPU and the GPU read the same values.

struct TexLevel {
    x: u32,
    y: u32,
    w: u32,
    h: u32,
    page: u32,
}

// Texture indices of a material (0xffffffff: none).
struct MaterialMaps {
    diffuse: u32,
    specular: u32,
    roughness: u32,
    normal: u32,
    alpha: u32,
    alpha_cutoff: f32,
    emission: u32,
    _p1: u32,
}

const NO_TEXTURE: u32 = 0xffffffffu;
// bsdf.wgsl's MIRROR_ROUGHNESS (this file is also used without bsdf.wgsl).
const TEX_MIRROR_ROUGHNESS: f32 = 1e-3;
// Entries per row of the table texture (`raster::textures::TABLE_WIDTH`).
const TEX_TABLE_WIDTH: u32 = 1024u;

@group(1) @binding(0) var tex_atlas: texture_2d_array<f32>;
// The texture table (a texture: reads are far cheaper than storage reads on lavapipe).
// Entry t < texture count: (first level's entry, levels, width | height << 16, 0); level
// entries: (x | y << 16, width | height << 16, page, 0).
@group(1) @binding(1) var tex_table: texture_2d<u32>;
@group(1) @binding(2) var<storage, read> material_maps: array<MaterialMaps>;

fn tex_entry(i: u32) -> vec4<u32> {
    return textureLoad(tex_table, vec2<u32>(i % TEX_TABLE_WIDTH, i / TEX_TABLE_WIDTH), 0);
}

fn tex_level(i: u32) -> TexLevel {
    let e = tex_entry(i);
    return TexLevel(e.x & 0xffffu, e.x >> 16u, e.y & 0xffffu, e.y >> 16u, e.z);
}

fn tex_wrap(i: i32, n: u32) -> u32 {
    let m = i32(n);
    return u32(((i % m) + m) % m);
}

fn tex_texel(l: TexLevel, x: i32, y: i32) -> vec4<f32> {
    let p = vec2<u32>(l.x + tex_wrap(x, l.w), l.y + tex_wrap(y, l.h));
    return textureLoad(tex_atlas, p, l.page, 0);
}

fn tex_mix(a: vec4<f32>, b: vec4<f32>, t: f32) -> vec4<f32> {
    return a * (1.0 - t) + b * t;
}

fn tex_bilinear(l: TexLevel, uv: vec2<f32>) -> vec4<f32> {
    let f = uv - floor(uv);
    let p = f * vec2<f32>(f32(l.w), f32(l.h)) - 0.5;
    let p0 = floor(p);
    let t = p - p0;
    let x = i32(p0.x);
    let y = i32(p0.y);
    let top = tex_mix(tex_texel(l, x, y), tex_texel(l, x + 1, y), t.x);
    let bottom = tex_mix(tex_texel(l, x, y + 1), tex_texel(l, x + 1, y + 1), t.x);
    return tex_mix(top, bottom, t.y);
}

// Trilinear lookup of texture `t` at an explicit level of detail (clamped to its chain).
fn tex_sample(t: u32, uv: vec2<f32>, lod: f32) -> vec4<f32> {
    return tex_sample_info(tex_entry(t), uv, lod);
}

fn tex_sample_info(info: vec4<u32>, uv: vec2<f32>, lod: f32) -> vec4<f32> {
    let top = f32(info.y - 1u);
    var l = 0.0;
    if lod == lod {
        l = clamp(lod, 0.0, top);
    }
    let l0 = floor(l);
    let f = l - l0;
    let a = tex_bilinear(tex_level(info.x + u32(l0)), uv);
    if f > 0.0 {
        return tex_mix(a, tex_bilinear(tex_level(info.x + u32(l0) + 1u), uv), f);
    }
    return a;
}

// Lookup of texture `t` at the level of detail of texture-coordinate derivatives along the
// screen axes: log2 of the longer footprint axis in texels of the finest level.
fn tex_sample_grad(t: u32, uv: vec2<f32>, duvdx: vec2<f32>, duvdy: vec2<f32>) -> vec4<f32> {
    let info = tex_entry(t);
    let size = vec2<f32>(f32(info.z & 0xffffu), f32(info.z >> 16u));
    let r = max(dot(duvdx * size, duvdx * size), dot(duvdy * size, duvdy * size));
    return tex_sample_info(info, uv, 0.5 * log2(max(r, 1e-20)));
}

// A material with its textures `maps` applied at `uv` (as `Scene::material_at`).
fn textured_material(maps: MaterialMaps, base: Material, uv: vec2<f32>, duvdx: vec2<f32>, duvdy: vec2<f32>) -> Material {
    var m = base;
    if maps.diffuse != NO_TEXTURE {
        let c = tex_sample_grad(maps.diffuse, uv, duvdx, duvdy).xyz;
        m.diffuse *= c;
        m.transmission *= c;
    }
    if maps.specular != NO_TEXTURE {
        m.specular *= tex_sample_grad(maps.specular, uv, duvdx, duvdy).xyz;
    }
    if maps.roughness != NO_TEXTURE {
        // As on the CPU: a map never turns a glossy lobe into a mirror.
        let glossy = m.roughness >= TEX_MIRROR_ROUGHNESS;
        m.roughness *= tex_sample_grad(maps.roughness, uv, duvdx, duvdy).y;
        if glossy {
            m.roughness = max(m.roughness, TEX_MIRROR_ROUGHNESS);
        }
    }
    if maps.emission != NO_TEXTURE && max(m.emission.x, max(m.emission.y, m.emission.z)) > 0.0 {
        m.emission *= tex_sample_grad(maps.emission, uv, duvdx, duvdy).xyz;
    }
    return m;
}

// Whether a material with textures `maps` is cut out at `uv` (finest level, as the CPU's
// any-hit test).
fn alpha_cut(maps: MaterialMaps, uv: vec2<f32>) -> bool {
    if maps.alpha == NO_TEXTURE {
        return false;
    }
    return tex_sample(maps.alpha, uv, 0.0).w < maps.alpha_cutoff;
}

// The shading normal `ns` (on the winding's side) with the normal map of `maps` applied, as
// `surface::perturb_normal`; `tangent.w` = 0 marks degenerate texture coordinates.
fn mapped_normal(maps: MaterialMaps, ns: vec3<f32>, tangent: vec4<f32>, uv: vec2<f32>, duvdx: vec2<f32>, duvdy: vec2<f32>) -> vec3<f32> {
    if maps.normal == NO_TEXTURE || tangent.w == 0.0 {
        return ns;
    }
    let texel = tex_sample_grad(maps.normal, uv, duvdx, duvdy).xyz;
    let m = texel * 2.0 - vec3<f32>(1.0);
    let tt = tangent.xyz - ns * dot(ns, tangent.xyz);
    let len = length(tt);
    if !(len > 0.0) {
        return ns;
    }
    let t = tt / len;
    let b = cross(ns, t) * tangent.w;
    let n = t * m.x - b * m.y + ns * m.z;
    let nl = length(n);
    if !(nl > 0.0) {
        return ns;
    }
    return n / nl;
}
