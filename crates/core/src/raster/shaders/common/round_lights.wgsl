// Round emitters (scene/emitters/round.rs) in the direct light, after direct_shade.wgsl
// (its `emitter_polygons`, `clipped_edge`, `arc_vector`). A sphere's row of the polygons
// texture (raster/direct.rs `round_texels`, flag 2 in the second texel's w) stands for the
// disc it shows a shading point outside it: radius r·√(1 − r²/d²), centred (1 − r²/d²) of
// the way to the sphere's centre, facing the point (the same cone of directions); a flat
// disc's row (its normal in the second texel) for itself. The disc is taken as the regular
// polygon of the same area, its corners walked by rotation (no sin/cos, no arrays). Read
// where ROUND_LIGHTS is (the scene has a round group).

// The polygon standing for round emitter `t` seen from `p`, relative to `p`: corner k is
// centre + cos(kθ)·u + sin(kθ)·v; `ok` false inside the sphere.
struct RoundPolygon {
    centre: vec3<f32>,
    u: vec3<f32>,
    v: vec3<f32>,
    corners: u32,
    // (cos θ, sin θ).
    step: vec2<f32>,
    ok: bool,
    // The disc's own radius (the polygon's over its scale) and its solid angle.
    radius: f32,
    solid_angle: f32,
}

fn round_polygon(p: vec3<f32>, t: u32) -> RoundPolygon {
    let t0 = textureLoad(emitter_polygons, vec2<u32>(0u, t), 0);
    let t2 = textureLoad(emitter_polygons, vec2<u32>(2u, t), 0);
    let t4 = textureLoad(emitter_polygons, vec2<u32>(4u, t), 0);
    let d = t0.xyz - p;
    let d2 = dot(d, d);
    let r2 = t2.x * t2.x;
    var out = RoundPolygon(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), u32(t2.y + 0.5), t4.xy, d2 > r2, 0.0, 0.0);
    let normal = textureLoad(emitter_polygons, vec2<u32>(1u, t), 0).xyz;
    if any(normal != vec3<f32>(0.0)) {
        return round_disc(out, d, normal, t2, t0.w > 0.5);
    }
    if !out.ok {
        return out;
    }
    let k = r2 / d2;
    let w = d * inverseSqrt(d2);
    let a = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0), abs(w.x) < 0.9);
    let u = normalize(cross(a, w));
    out.radius = t2.x * sqrt(1.0 - k);
    // 2π(1 − cos ρ), sin²ρ = k, in a form exact for small k.
    out.solid_angle = 6.28318530718 * k / (1.0 + sqrt(1.0 - k));
    out.centre = d * (1.0 - k);
    out.u = u * (out.radius * t2.z);
    out.v = cross(w, u) * (out.radius * t2.z);
    return out;
}

// `round_polygon` of a flat disc of unit `normal` (radius, corners, scale in `r`) whose
// centre is at `d` from the point: the disc itself, lit on its front side unless
// `two_sided`, none of it in its plane (within 1e-4 of its radius: its own face). Its solid
// angle that of a small disc, π·r²·cos/d² (`round_quadrature`'s weight, only where the
// disc is small against the lobe).
fn round_disc(q: RoundPolygon, d: vec3<f32>, normal: vec3<f32>, r: vec4<f32>, two_sided: bool) -> RoundPolygon {
    var out = q;
    let height = -dot(d, normal);
    out.ok = select(height, abs(height), two_sided) > 1e-4 * r.x;
    let a = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0), abs(normal.x) < 0.9);
    let u = normalize(cross(a, normal));
    let d2 = dot(d, d);
    out.radius = r.x;
    out.solid_angle = 3.14159265359 * r.x * r.x * abs(height) / (d2 * sqrt(d2));
    out.centre = d;
    out.u = u * (r.x * r.z);
    out.v = cross(normal, u) * (r.x * r.z);
    return out;
}

// `q` with more corners where its disc is large against a glossy lobe of width α (its
// angular radius ρ = `rho_over_alpha`·α): the N-gon of the disc's area strays from the rim
// by about ρ·π²/(2N²) (±, in angle), kept under α/4 so that the polygon's straight edges
// do not show in a sharp highlight: N ≥ π·√(2ρ/α), rounded up to a multiple of 4, from the
// record's (12) up to 64. The polygon's radius over the disc's for N corners of the same
// area: √(2π / (N·sin(2π/N))).
fn round_sides(q: RoundPolygon, rho_over_alpha: f32) -> RoundPolygon {
    let n = min(4.0 * ceil(0.78539816 * sqrt(2.0 * rho_over_alpha)), 64.0);
    if n <= f32(q.corners) {
        return q;
    }
    var out = q;
    let step = 6.28318530718 / n;
    out.step = vec2<f32>(cos(step), sin(step));
    out.corners = u32(n);
    let k = sqrt(6.28318530718 / (n * out.step.y)) * q.radius / length(q.u);
    out.u = q.u * k;
    out.v = q.v * k;
    return out;
}

// The corner at angle (cos, sin) `cs`.
fn round_corner(q: RoundPolygon, cs: vec2<f32>) -> vec3<f32> {
    return q.centre + q.u * cs.x + q.v * cs.y;
}

// `cs` turned by the polygon's step.
fn round_turn(q: RoundPolygon, cs: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(cs.x * q.step.x - cs.y * q.step.y, cs.x * q.step.y + cs.y * q.step.x);
}

// Lambert's vector irradiance of round emitter `t` at `p` of unit radiance, clipped to the
// hemisphere above `n` (`polygon_vector`'s, for `polygons_diffuse`).
fn round_vector(p: vec3<f32>, t: u32, n: vec3<f32>) -> vec3<f32> {
    let q = round_polygon(p, t);
    if !q.ok {
        return vec3<f32>(0.0);
    }
    var phi = vec3<f32>(0.0);
    var exit = vec3<f32>(0.0);
    var entry = vec3<f32>(0.0);
    var cs = vec2<f32>(1.0, 0.0);
    var a = round_corner(q, cs);
    var da = dot(a, n);
    for (var k = 0u; k < q.corners; k++) {
        cs = round_turn(q, cs);
        let b = round_corner(q, cs);
        let db = dot(b, n);
        clipped_edge(a, b, da, db, &phi, &exit, &entry);
        a = b;
        da = db;
    }
    return 0.5 * (phi + arc_vector(exit, entry));
}
