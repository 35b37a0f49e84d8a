// The uber BSDF's sampling helpers (`bsdf::Material::sample` and its parts, crates/core/src/
// bsdf/): lobe numbers, lobe probabilities, the non-delta density, cosine and GGX
// half-vector sampling, the ISPM path density factor. Shared by the
// bounce maps' first scatter (`raster/shaders/bounce.wgsl`) and the GPU photon trace
// (`gpu/shaders/photon/scatter.wgsl`). After `types.wgsl` and `bsdf.wgsl`.

const LOBE_DIFFUSE: u32 = 0u;
const LOBE_GLOSSY: u32 = 1u;
const LOBE_MIRROR: u32 = 2u;
const LOBE_GLASS_REFLECT: u32 = 3u;
const LOBE_GLASS_REFRACT: u32 = 4u;

fn avg3(v: vec3<f32>) -> f32 {
    return (v.x + v.y + v.z) / 3.0;
}

// Probabilities of the specular, diffuse and glass lobes at viewing cosine `cos_o`.
fn lobe_probabilities(m: Material, cos_o: f32) -> vec3<f32> {
    let f = fresnel_spec(m, cos_o);
    let one = vec3<f32>(1.0);
    let ws = avg3(f);
    let wd = avg3((one - f) * m.diffuse);
    let wg = avg3((one - f) * m.transmission);
    let total = ws + wd + wg;
    if total <= 0.0 {
        return vec3<f32>(0.0);
    }
    return vec3<f32>(ws / total, wd / total, wg / total);
}

// `sampling::cosine_hemisphere`.
fn cosine_hemisphere(u: vec2<f32>) -> vec3<f32> {
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    return vec3<f32>(r * cos(phi), r * sin(phi), sqrt(max(1.0 - u.x, 0.0)));
}

// `microfacet::sample_h` for GGX.
fn ggx_sample_h(u: vec2<f32>, alpha: f32) -> vec3<f32> {
    let a2 = alpha * alpha;
    let cos2 = (1.0 - u.x) / (1.0 + (a2 - 1.0) * u.x);
    let cos_t = sqrt(max(cos2, 0.0));
    let sin_t = sqrt(max(1.0 - cos2, 0.0));
    let phi = 2.0 * PI * u.y;
    return vec3<f32>(sin_t * cos(phi), sin_t * sin(phi), cos_t);
}

// `Material::pdf` of the non-delta lobes (`wo`, `wi` local, on one side).
fn bsdf_pdf_local(m: Material, wo_in: vec3<f32>, wi_in: vec3<f32>) -> f32 {
    if wo_in.z * wi_in.z <= 0.0 {
        return 0.0;
    }
    let s = select(1.0, -1.0, wo_in.z < 0.0);
    let wo = wo_in * s;
    let wi = wi_in * s;
    let p = lobe_probabilities(m, wo.z);
    var pdf = p.y * wi.z / PI;
    if m.roughness >= MIRROR_ROUGHNESS && p.x > 0.0 {
        let h = normalize(wo + wi);
        let oh = abs(dot(wo, h));
        if oh > 0.0 {
            let alpha = m.roughness * m.roughness;
            pdf += p.x * ggx_d(h.z, alpha) * h.z / (4.0 * oh);
        }
    }
    return pdf;
}

// `photon::path_density_factor`.
fn path_density_factor(m: Material, lobe: u32) -> f32 {
    if lobe == LOBE_DIFFUSE {
        return avg3(m.diffuse) / 1000.0;
    }
    if lobe == LOBE_GLOSSY {
        return avg3(m.specular) / 10.0;
    }
    if lobe == LOBE_MIRROR {
        return avg3(m.specular);
    }
    return avg3(m.transmission);
}
