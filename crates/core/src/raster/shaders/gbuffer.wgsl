// Eye G-buffer: rasterizes the scene from a (jittered) camera view and writes what the
// deferred passes need per sample. Target formats (see raster/gbuffer.rs for the reasons).

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> materials: array<Material>;

@vertex
fn vs_main(v: VertexIn, i: InstanceIn) -> VertexOut {
    return scene_vertex(v, i, view.view_proj);
}

struct GBufferOut {
    // World position xyz; w = 1 where a surface covers the sample, 0 (clear) elsewhere.
    @location(0) position: vec4<f32>,
    // Octahedral shading normal (xy) and geometric normal (zw), both facing the viewer.
    @location(1) normals: vec4<f32>,
    // Diffuse albedo rgb, roughness.
    @location(2) diffuse: vec4<f32>,
    // Specular F0 rgb, Fresnel flag (0 or 1).
    @location(3) specular: vec4<f32>,
    // Scatter probability towards the viewer (the albedo AOV).
    @location(4) albedo: vec4<f32>,
    // Radiance emitted towards the viewer; w = the material's index + 1 (its exact model:
    // common/exact_models.wgsl), 0 on a one-sided material's back.
    @location(5) emission: vec4<f32>,
}

// Three entry points, one per kind of scene (`raster::textures::Variant`): without textures,
// with textures, with alpha masks. Only the last discards: a shader that may discard loses
// early depth testing on lavapipe and shades every overdrawn fragment (8x slower here).
@fragment
fn fs_main(in: VertexOut) -> GBufferOut {
    return gbuffer(in, false, vec2<f32>(0.0), vec2<f32>(0.0));
}

@fragment
fn fs_textured(in: VertexOut) -> GBufferOut {
    return gbuffer(in, true, dpdx(in.uv), dpdy(in.uv));
}

@fragment
fn fs_masked(in: VertexOut) -> GBufferOut {
    // Derivatives first (uniform control flow), then the alpha mask.
    let duvdx = dpdx(in.uv);
    let duvdy = dpdy(in.uv);
    if alpha_cut(material_maps[in.material], in.uv) {
        discard;
    }
    return gbuffer(in, true, duvdx, duvdy);
}

fn gbuffer(in: VertexOut, textured: bool, duvdx: vec2<f32>, duvdy: vec2<f32>) -> GBufferOut {
    var m = materials[in.material];
    var maps: MaterialMaps;
    if textured {
        maps = material_maps[in.material];
        m = textured_material(maps, m, in.uv, duvdx, duvdy);
    }
    let wo = normalize(view.eye - in.world);
    var ng = in.geometric_normal;
    // `Material::emitted`: the front face (the winding's side) emits, both when two-sided.
    let emits = (m.two_sided & MATERIAL_EMITS_BACK) != 0u || dot(wo, ng) > 0.0;
    // A one-sided material's back is black, shaded by no exact model (index 0).
    let back = one_sided_back(m, front_normal(in.normal, ng), wo);
    if back {
        m = without_lobes(m);
    }
    // Shading normal as in trace::Interaction::new: on the side of ng, and replaced by ng
    // where the two disagree about the side the view ray comes from.
    var ns = shading_normal(in.normal, ng);
    if textured {
        ns = mapped_normal(maps, ns, in.tangent, in.uv, duvdx, duvdy);
    }
    let facing = facing_normals(wo, ns, ng);
    ns = facing.shading;
    ng = facing.geometric;
    var o: GBufferOut;
    o.position = vec4<f32>(in.world, 1.0);
    o.normals = vec4<f32>(oct_encode(ns), oct_encode(ng));
    o.diffuse = vec4<f32>(m.diffuse, m.roughness);
    o.specular = vec4<f32>(m.specular, f32(m.fresnel));
    o.albedo = vec4<f32>(scatter_probability(m, dot(wo, ns)), 1.0);
    o.emission = vec4<f32>(select(vec3<f32>(0.0), m.emission, emits), select(f32(in.material + 1u), 0.0, back));
    return o;
}
