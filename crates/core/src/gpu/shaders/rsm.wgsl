// Reflective shadow map (Dachsbacher & Stamminger 2005) for method `bidir`: the scene
// rasterized from a light's view (the views of the ISPM bounce map: one perspective view per
// spot light, six 90° cube faces per point light). A covered texel is the surface point the
// light's flux through that texel reaches: position, normals (oriented towards the light),
// material, and the flux Φ = I(ω)·A_texel·cos³θ (A_texel carries the per-light round-off
// correction, so a light's texels sum to its power). VPLs are drawn from these texels.

struct BounceView {
    view_proj: mat4x4<f32>,
    light_position: vec3<f32>,
    texel_area: f32,
    forward: vec3<f32>,
    kind: u32,
    intensity: vec3<f32>,
    cos_inner: f32,
    spot_direction: vec3<f32>,
    cos_outer: f32,
    seed: u32,
    layer: u32,
}

@group(0) @binding(0) var<uniform> view: BounceView;
@group(0) @binding(1) var<storage, read> materials: array<Material>;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) geometric_normal: vec3<f32>,
    @location(3) material: u32,
    @location(4) uv: vec2<f32>,
    @location(5) tangent: vec4<f32>,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) geometric_normal: vec3<f32>,
    @location(3) @interpolate(flat) material: u32,
    @location(4) uv: vec2<f32>,
    @location(5) @interpolate(flat) tangent: vec4<f32>,
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var o: VertexOut;
    o.clip = view.view_proj * vec4<f32>(v.position, 1.0);
    o.world = v.position;
    o.normal = v.normal;
    o.geometric_normal = v.geometric_normal;
    o.material = v.material;
    o.uv = v.uv;
    o.tangent = v.tangent;
    return o;
}

struct RsmOut {
    // World position; w = 1 marks a covered texel.
    @location(0) position: vec4<f32>,
    // Octahedral shading normal (xy) and geometric normal (zw), both towards the light.
    @location(1) normals: vec4<f32>,
    // Diffuse colour, roughness.
    @location(2) diffuse: vec4<f32>,
    // Specular colour, Fresnel flag.
    @location(3) specular: vec4<f32>,
    // Flux (W) through the texel.
    @location(4) flux: vec4<f32>,
}

fn rsm_falloff(cos_t: f32) -> f32 {
    if cos_t >= view.cos_inner {
        return 1.0;
    }
    if cos_t <= view.cos_outer {
        return 0.0;
    }
    let t = (cos_t - view.cos_outer) / (view.cos_inner - view.cos_outer);
    return t * t * (3.0 - 2.0 * t);
}

@fragment
fn fs_main(in: VertexOut) -> RsmOut {
    return rsm(in, false);
}

@fragment
fn fs_textured(in: VertexOut) -> RsmOut {
    return rsm(in, true);
}

@fragment
fn fs_masked(in: VertexOut) -> RsmOut {
    if alpha_cut(material_maps[in.material], in.uv) {
        discard;
    }
    return rsm(in, true);
}

fn rsm(in: VertexOut, textured: bool) -> RsmOut {
    let duvdx = dpdx(in.uv);
    let duvdy = dpdy(in.uv);
    let wo = normalize(view.light_position - in.world);
    var ng = in.geometric_normal;
    var ns = in.normal;
    let len = length(ns);
    if !(len > 0.0) {
        ns = ng;
    } else {
        ns = ns / len;
        if dot(ns, ng) < 0.0 {
            ns = -ns;
        }
    }
    var m = materials[in.material];
    if textured {
        let maps = material_maps[in.material];
        ns = mapped_normal(maps, ns, in.tangent, in.uv, duvdx, duvdy);
        m = textured_material(maps, m, in.uv, duvdx, duvdy);
    }
    if dot(wo, ns) * dot(wo, ng) <= 0.0 {
        ns = ng;
    }
    if dot(wo, ng) < 0.0 {
        ng = -ng;
        ns = -ns;
    }
    let d = -wo;
    let c = max(dot(d, view.forward), 0.0);
    var intensity = view.intensity;
    if view.kind == 1u {
        intensity *= rsm_falloff(dot(d, view.spot_direction));
    }
    var o: RsmOut;
    o.position = vec4<f32>(in.world, 1.0);
    o.normals = vec4<f32>(oct_encode(ns), oct_encode(ng));
    o.diffuse = vec4<f32>(m.diffuse, m.roughness);
    o.specular = vec4<f32>(m.specular, f32(m.fresnel));
    o.flux = vec4<f32>(intensity * view.texel_area * c * c * c, 0.0);
    return o;
}
