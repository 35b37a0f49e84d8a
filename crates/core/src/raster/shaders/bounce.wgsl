// ISPM bounce map (section 4.2): rasterizes the scene from a light's view (one perspective
// view per spot light, six exact 90° cube faces per point light). Every covered texel is one
// photon leaving the light through that texel: its power is I(ω)·dω with the texel's solid
// angle dω = A_texel·cos³θ on a unit-distance image plane (A_texel already carries the
// per-light round-off correction, so all texels of a light sum to its power). The hit it
// lands on is direct light (not stored). Its first scatter is taken here: the uber BSDF is
// importance-sampled (a port of `Material::sample`, with a hash-seeded PCG generator per
// frame seed, layer and texel), then Russian roulette as in `photon::trace` (survival
// q = min(1, max(Φ·w)/max(Φ)), survivors carry Φ·w/q), and the path density factor.

struct BounceOut {
    // Origin of the scattered photon (offset off the surface), path density (0: absorbed).
    @location(0) origin: vec4<f32>,
    // Unit direction of the scattered photon; w = 1 if it survived.
    @location(1) direction: vec4<f32>,
    // Power (W) of the scattered photon.
    @location(2) power: vec4<f32>,
    // Photon power (W) arriving at the hit; w = 1 marks a covered texel.
    @location(3) incident: vec4<f32>,
    // Arriving power times the scatter probability (the expected scattered power).
    @location(4) expected: vec4<f32>,
}

// Three entry points, one per kind of scene (see gbuffer.wgsl): only `fs_masked` discards.
@fragment
fn fs_main(in: VertexOut) -> BounceOut {
    return bounce(in, false);
}

@fragment
fn fs_textured(in: VertexOut) -> BounceOut {
    return bounce(in, true);
}

@fragment
fn fs_masked(in: VertexOut) -> BounceOut {
    // The alpha test at the photon's jittered origin (the same jitter `bounce` draws).
    let duvdx = dpdx(in.uv);
    let duvdy = dpdy(in.uv);
    let jitter = texel_jitter(in);
    if alpha_cut(material_maps[in.material], in.uv + jitter.x * duvdx + jitter.y * duvdy) {
        discard;
    }
    return bounce(in, true);
}

// Seeds the texel's random sequence and draws its jitter (the first two numbers).
fn texel_jitter(in: VertexOut) -> vec2<f32> {
    let texel = vec2<u32>(in.clip.xy);
    rng_state = hash_u32(view.seed ^ hash_u32(view.layer ^ hash_u32(texel.x ^ hash_u32(texel.y))));
    return vec2<f32>(rng_next(), rng_next()) - 0.5;
}

fn bounce(in: VertexOut, textured: bool) -> BounceOut {
    // Stratified jitter: the photon leaves the light through a uniformly random point of its
    // texel instead of the texel centre (the surface point and interpolated normal are moved
    // along their screen derivatives, exact within a planar triangle). Centre-sampled
    // texels map a regular grid through mirrors and glass onto the receivers and show as
    // moiré in sparse caustics. The offset is part of the frame-seeded sequence, so static
    // scenes stay frame-coherent.
    let dwdx = dpdx(in.world);
    let dwdy = dpdy(in.world);
    let dndx = dpdx(in.normal);
    let dndy = dpdy(in.normal);
    let duvdx = dpdx(in.uv);
    let duvdy = dpdy(in.uv);
    let jitter = texel_jitter(in);
    let world = in.world + jitter.x * dwdx + jitter.y * dwdy;
    let uv = in.uv + jitter.x * duvdx + jitter.y * duvdy;
    // Materials at the finest level (zero derivatives): a photon is a point sample, as in
    // the CPU photon tracer and `path`, so the first scatter sees the material the CPU sees
    // at the same point (a texel's mip-filtered albedo would weight every photon of a
    // minified texture with the texture's local mean instead of the albedo where it lands).
    let point = vec2<f32>(0.0);
    let to_light = view.light_position - world;
    let wo = normalize(to_light);
    // Normals as in the eye G-buffer, oriented towards the light.
    var ng = in.geometric_normal;
    var ns = shading_normal(in.normal + jitter.x * dndx + jitter.y * dndy, ng);
    var maps: MaterialMaps;
    if textured {
        maps = material_maps[in.material];
        ns = mapped_normal(maps, ns, in.tangent, uv, point, point);
    }
    let facing = facing_normals(wo, ns, ng);
    ns = facing.shading;
    ng = facing.geometric;
    let phi = texel_flux(wo);
    var m = materials[in.material];
    if textured {
        m = textured_material(maps, m, uv, point, point);
    }
    // A one-sided material lit from behind scatters nothing.
    let back = one_sided_back(m, front_normal(in.normal, in.geometric_normal), wo);
    if back {
        m = without_lobes(m);
    }
    // Mitsuba's exact model of the material, if it has one (common/exact_models.wgsl).
    exact_load(select(f32(in.material + 1u), 0.0, back), m.diffuse);
    var o: BounceOut;
    o.incident = vec4<f32>(phi, 1.0);
    o.expected = vec4<f32>(phi * exact_scatter(scatter_probability(m, dot(wo, ns)), dot(wo, ns)), 1.0);
    o.origin = vec4<f32>(0.0);
    o.direction = vec4<f32>(0.0);
    o.power = vec4<f32>(0.0);
    if max3(phi) <= 0.0 {
        return o;
    }
    // Shading frame (Duff et al.), +z = ns.
    let sz = select(-1.0, 1.0, ns.z >= 0.0);
    let a = -1.0 / (sz + ns.z);
    let bb = ns.x * ns.y * a;
    let t = vec3<f32>(1.0 + sz * ns.x * ns.x * a, sz * bb, -sz * ns.x);
    let b = vec3<f32>(bb, sz + ns.y * ns.y * a, -ns.y);
    let wo_l = vec3<f32>(dot(wo, t), dot(wo, b), dot(wo, ns));
    let bs = sample_bsdf(m, wo_l);
    if !bs.ok {
        return o;
    }
    let wi = normalize(t * bs.wi.x + b * bs.wi.y + ns * bs.wi.z);
    // Reflections stay on the arrival side, refractions cross.
    let same_side = dot(wi, ng) * dot(wo, ng) > 0.0;
    if same_side == (bs.lobe == 4u) {
        return o;
    }
    let scattered = phi * bs.weight;
    let q = min(max3(scattered) / max3(phi), 1.0);
    if !(q > 0.0) || rng_next() >= q {
        return o;
    }
    let eps = 1e-4 * (1.0 + max3(abs(world)));
    let origin = world + ng * eps * sign(dot(wi, ng));
    o.origin = vec4<f32>(origin, path_density_factor(m, bs.lobe));
    o.direction = vec4<f32>(wi, 1.0);
    // w: the material has a delta lobe (a mirror or glass first hit: with photon focusing
    // such photons come from the CPU's aimed emission instead, `photon::trace`).
    let delta = (max3(m.specular) > 0.0 && m.roughness < MIRROR_ROUGHNESS) || max3(m.transmission) > 0.0;
    o.power = vec4<f32>(scattered / q, select(0.0, 1.0, delta));
    return o;
}

// ---- First scatter (port of `bsdf::Material::sample` and `photon::trace::follow`) ----

@group(0) @binding(1) var<storage, read> materials: array<Material>;
// The materials' exact models (raster/exact_models.rs): `sample_bsdf` draws by the uber
// material's lobes and weighs by the model's f·cos/pdf.
@group(0) @binding(2) var<storage, read> model_materials: array<ModelMaterial>;

var<private> rng_state: u32;

fn hash_u32(x_in: u32) -> u32 {
    var x = x_in;
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

// PCG-RXS-M-XS 32-bit step; 24-bit uniform floats in [0, 1).
fn rng_next() -> f32 {
    rng_state = rng_state * 747796405u + 2891336453u;
    var w = ((rng_state >> ((rng_state >> 28u) + 4u)) ^ rng_state) * 277803737u;
    w = (w >> 22u) ^ w;
    return f32(w >> 8u) * (1.0 / 16777216.0);
}

struct BsdfSample {
    wi: vec3<f32>,
    weight: vec3<f32>,
    // 0 diffuse, 1 glossy, 2 mirror, 3 glass reflection, 4 glass refraction.
    lobe: u32,
    ok: bool,
}

// `Material::sample` in the local frame.
fn sample_bsdf(m: Material, wo: vec3<f32>) -> BsdfSample {
    var s: BsdfSample;
    s.ok = false;
    let flip = wo.z < 0.0;
    let sgn = select(1.0, -1.0, flip);
    let wo_up = wo * sgn;
    let p = lobe_probabilities(m, wo_up.z);
    let u = rng_next();
    let u2 = vec2<f32>(rng_next(), rng_next());
    let n = vec3<f32>(0.0, 0.0, 1.0);
    if u < p.x + p.y {
        if u < p.x && m.roughness < MIRROR_ROUGHNESS {
            s.wi = vec3<f32>(-wo.x, -wo.y, wo.z);
            s.weight = exact_mirror(fresnel_spec(m, wo_up.z), wo_up.z) / p.x;
            s.lobe = 2u;
            s.ok = true;
            return s;
        }
        var wi_up: vec3<f32>;
        if u < p.x {
            let h = ggx_sample_h(u2, m.roughness * m.roughness);
            wi_up = 2.0 * dot(wo_up, h) * h - wo_up;
            s.lobe = 1u;
        } else {
            wi_up = cosine_hemisphere(u2);
            s.lobe = 0u;
        }
        if wi_up.z <= 0.0 {
            return s;
        }
        let wi = wi_up * sgn;
        let pdf = bsdf_pdf_local(m, wo, wi);
        if pdf <= 0.0 {
            return s;
        }
        s.wi = wi;
        s.weight = exact_eval(m, n, wo, wi) * wi_up.z / pdf;
        s.ok = true;
        return s;
    }
    if p.z <= 0.0 {
        return s;
    }
    // Smooth glass: the geometric side decides whether we enter or leave.
    s.weight = m.transmission * (vec3<f32>(1.0) - fresnel_spec(m, wo_up.z)) / p.z;
    let eta = select(m.ior, 1.0 / m.ior, flip);
    let f = fresnel_dielectric(wo_up.z, eta);
    let fr = f.x;
    let cos_t = f.y;
    if u2.x < fr {
        s.wi = vec3<f32>(-wo.x, -wo.y, wo.z);
        s.lobe = 3u;
    } else {
        let wt_up = -wo_up / eta + (wo_up.z / eta - cos_t) * n;
        s.wi = normalize(wt_up * sgn);
        s.lobe = 4u;
    }
    s.ok = true;
    return s;
}

