// Reflective shadow map (Dachsbacher & Stamminger 2005) for method `bidir`: the scene
// rasterized from a light's view (the views of the ISPM bounce map: one perspective view per
// spot light, six 90° cube faces per point light). A covered texel is the surface point the
// light's flux through that texel reaches: position, normals (oriented towards the light),
// material, and the flux Φ = I(ω)·A_texel·cos³θ (A_texel carries the per-light round-off
// correction, so a light's texels sum to its power). VPLs are drawn from these texels.

@group(0) @binding(1) var<storage, read> materials: array<Material>;

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
    let surface = fragment_surface(in, materials[in.material], textured, duvdx, duvdy);
    var m = surface.m;
    // A one-sided material lit from behind reflects nothing.
    if one_sided_back(m, front_normal(in.normal, in.geometric_normal), wo) {
        m = without_lobes(m);
    }
    let facing = facing_normals(wo, surface.ns, in.geometric_normal);
    var o: RsmOut;
    o.position = vec4<f32>(in.world, 1.0);
    o.normals = vec4<f32>(oct_encode(facing.shading), oct_encode(facing.geometric));
    o.diffuse = vec4<f32>(m.diffuse, m.roughness);
    o.specular = vec4<f32>(m.specular, f32(m.fresnel));
    o.flux = vec4<f32>(texel_flux(wo), 0.0);
    return o;
}
