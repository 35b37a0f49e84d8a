// One-bounce indirect light from virtual point lights (method `bidir`, Tokuyoshi & Ogaki
// 2012 §4.1): for every G-buffer pixel x3, the sum over VPLs x1 of
//   Φ1 · f(x1; ω1,3, ω1,0) · f(x3; ω3,4, ω3,1) · |n3·ω3,1| · |ng1·ω1,3| / ‖x1 − x3‖² · V(x1, x3)
// with V from the VPL's cube shadow map (six layers from `first_layer`). Φ1 already holds
// the VPL's share of its light's flux and the shading-to-geometric cosine ratio at x1.

struct Vpl {
    position: vec3<f32>,
    first_layer: u32,
    flux: vec3<f32>,
    // World size of one shadow texel at unit distance from the VPL.
    texel_scale: f32,
    // Unit direction from the VPL towards its light (ω1,0).
    to_light: vec3<f32>,
    fresnel: u32,
    diffuse: vec3<f32>,
    roughness: f32,
    specular: vec3<f32>,
    _pad0: f32,
    // Shading and geometric normals, towards the light.
    ns: vec3<f32>,
    _pad1: f32,
    ng: vec3<f32>,
    _pad2: f32,
}

struct VplParams {
    eye: vec3<f32>,
    count: u32,
}

@group(0) @binding(0) var<uniform> params: VplParams;
@group(0) @binding(1) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(2) var<storage, read> shadow_views: array<mat4x4<f32>>;
@group(0) @binding(3) var shadow_maps: texture_depth_2d_array;
@group(0) @binding(4) var shadow_sampler: sampler_comparison;
@group(1) @binding(0) var g_position: texture_2d<f32>;
@group(1) @binding(1) var g_normals: texture_2d<f32>;
@group(1) @binding(2) var g_diffuse: texture_2d<f32>;
@group(1) @binding(3) var g_specular: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let px = vec2<i32>(frag.xy);
    let pos = textureLoad(g_position, px, 0);
    if pos.w == 0.0 {
        return vec4<f32>(0.0);
    }
    let p = pos.xyz;
    let nn = textureLoad(g_normals, px, 0);
    let ns = oct_decode(nn.xy);
    let ng = oct_decode(nn.zw);
    let d = textureLoad(g_diffuse, px, 0);
    let s = textureLoad(g_specular, px, 0);
    var m: Material;
    m.diffuse = d.xyz;
    m.roughness = d.w;
    m.specular = s.xyz;
    m.fresnel = u32(s.w > 0.5);
    let wo = normalize(params.eye - p);
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < params.count; i++) {
        let v = vpls[i];
        let to_vpl = v.position - p;
        let dist2 = dot(to_vpl, to_vpl);
        let dist = sqrt(dist2);
        let wi = to_vpl / dist;
        // Both ends must face each other: x3 on its lit side, x1 towards x3.
        let cos1 = -dot(wi, v.ng);
        if dot(wi, ng) <= 0.0 || cos1 <= 0.0 {
            continue;
        }
        var m1: Material;
        m1.diffuse = v.diffuse;
        m1.roughness = v.roughness;
        m1.specular = v.specular;
        m1.fresnel = v.fresnel;
        let f1 = bsdf_eval(m1, v.ns, -wi, v.to_light);
        let f3 = bsdf_eval(m, ns, wo, wi);
        let t = v.flux * f1 * f3 * (abs(dot(ns, wi)) * cos1 / dist2);
        if max3(t) <= 0.0 {
            continue;
        }
        let offset = ng * (v.texel_scale * dist * (1.0 - dot(wi, ng)) + 1e-4 * dist);
        sum += t * shadow_visibility(v.first_layer, 6u, v.position, p + offset);
    }
    return vec4<f32>(sum, 1.0);
}
