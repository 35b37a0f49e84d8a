// Linearly transformed cosines (Heitz, Dupuy, Hill & Neubelt 2016): the GGX or Beckmann
// lobe's integral over a polygon in closed form (raster/ltc.rs, the CPU reference of these
// functions, step by step). The fitted tables are a texture, `ltc_table` (declared by the
// includer: the direct pass binds it in group 0), laid out by raster/ltc.rs
// `LtcTable::texels`, table 0 (GGX) then table 1 (Beckmann) from row size + 1: a table's
// first row's texel 0 holds (roughness at its row 0, at the last row, θ_o at the last
// column, size), its row i + 1 the cells of roughness i, two texels per θ_o: M⁻¹'s entries
// [m00, m02, m20, m22], then the lobe's albedo n and its Schlick moment s. A texture, not a WGSL array: lavapipe compiled the
// direct pipeline with the table as a private array ~3.5x slower.

// One interpolated cell.
struct LtcCell {
    minv: vec4<f32>,
    // n, s.
    moments: vec2<f32>,
}

// Cell (i, j) of the table whose first row is `base`.
fn ltc_node(base: u32, i: u32, j: u32) -> LtcCell {
    let minv = textureLoad(ltc_table, vec2<u32>(2u * j, base + i + 1u), 0);
    let moments = textureLoad(ltc_table, vec2<u32>(2u * j + 1u, base + i + 1u), 0).xy;
    return LtcCell(minv, moments);
}

fn ltc_mix(a: LtcCell, b: LtcCell, t: f32) -> LtcCell {
    return LtcCell(mix(a.minv, b.minv, t), mix(a.moments, b.moments, t));
}

// The cell of table `table` (0: GGX, 1: Beckmann) at `roughness` and view cosine `cos_o`,
// bilinear between the nodes (clamped).
fn ltc_lookup(table: u32, roughness: f32, cos_o: f32) -> LtcCell {
    let base = table * (u32(textureLoad(ltc_table, vec2<u32>(0u, 0u), 0).w) + 1u);
    let range = textureLoad(ltc_table, vec2<u32>(0u, base), 0);
    let size = u32(range.w);
    let last = range.w - 1.0;
    let theta = acos(clamp(cos_o, 0.0, 1.0));
    let fi = clamp((roughness - range.x) / (range.y - range.x) * last, 0.0, last);
    let fj = clamp(theta / range.z * last, 0.0, last);
    let i = min(u32(fi), size - 2u);
    let j = min(u32(fj), size - 2u);
    let u = fi - f32(i);
    let w = fj - f32(j);
    let lo = ltc_mix(ltc_node(base, i, j), ltc_node(base, i, j + 1u), w);
    let hi = ltc_mix(ltc_node(base, i + 1u, j), ltc_node(base, i + 1u, j + 1u), w);
    return ltc_mix(lo, hi, u);
}

// M⁻¹·w.
fn ltc_apply(c: LtcCell, w: vec3<f32>) -> vec3<f32> {
    let m = c.minv;
    return vec3<f32>(m.x * w.x + m.y * w.z, w.y, m.z * w.x + m.w * w.z);
}

// The z part of Lambert's edge term θ·n̂ of the arc between unit vectors `a` and `b`.
fn ltc_edge_z(a: vec3<f32>, b: vec3<f32>) -> f32 {
    let c = cross(a, b);
    let s = length(c);
    if s <= 0.0 {
        return 0.0;
    }
    return atan2(s, dot(a, b)) * (c.z / s);
}

// The part of edge `p` → `q` above z = 0, its edge term added to `sum`; where the polygon
// leaves the hemisphere the crossing goes to `exit`, where it re-enters to `entry`. One
// edge term for every case: each is inlined where it is called, and lavapipe's compile
// time grows with the code.
fn ltc_clip_edge(p: vec3<f32>, q: vec3<f32>, sum: ptr<function, f32>, exit: ptr<function, vec3<f32>>, entry: ptr<function, vec3<f32>>) {
    let up = p.z > 0.0;
    let uq = q.z > 0.0;
    if !up && !uq {
        return;
    }
    var x = vec3<f32>(0.0);
    if up != uq {
        x = normalize(p + (q - p) * (p.z / (p.z - q.z)));
    }
    *sum += ltc_edge_z(select(x, normalize(p), up), select(x, normalize(q), uq));
    if up && !uq {
        *exit = x;
    }
    if uq && !up {
        *entry = x;
    }
}

// The form factor of the polygon a, b, c, d (a triangle repeats its first corner) clipped to
// z > 0: |Σ θᵢ·(n̂ᵢ)_z| / 2π, the horizon's arc from the exit to the entry included. No
// arrays: a private array of the clipped corners cost lavapipe ~3x (direct_shade.wgsl's
// `polygon_vector`); the corners turn through one edge's code.
fn ltc_form_factor(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, d: vec3<f32>) -> f32 {
    var sum = 0.0;
    var exit = vec3<f32>(0.0);
    var entry = vec3<f32>(0.0);
    var p = a;
    var q = b;
    var r = c;
    var s = d;
    for (var k = 0u; k < 4u; k++) {
        ltc_clip_edge(p, q, &sum, &exit, &entry);
        let t = p;
        p = q;
        q = r;
        r = s;
        s = t;
    }
    sum += ltc_edge_z(exit, entry);
    return abs(sum) / 6.28318530718;
}

// The shading frame's tangent t₁: v's tangential part, any tangent at normal view.
fn ltc_view_tangent(n: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    let t = v - n * dot(n, v);
    let l = length(t);
    if l > 1e-6 {
        return t / l;
    }
    let a = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0), abs(n.x) < 0.9);
    return normalize(a - n * dot(n, a));
}

// ∫ f·cos θi dω of the GGX (`table` 0) or Beckmann (1) lobe of `roughness` (α =
// roughness², Fresnel 1) over the polygon a, b, c, d (relative to the shading point; a
// triangle repeats its first corner) seen from unit normal `n` and unit view direction
// `v`, and the same with the Schlick weight (1 − wi·h)⁵: a Schlick Fresnel of reflectance
// F0 gives F0·x + (1 − F0)·y.
fn ltc_glossy(table: u32, n: vec3<f32>, v: vec3<f32>, roughness: f32, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, d: vec3<f32>) -> vec2<f32> {
    let cell = ltc_lookup(table, roughness, dot(n, v));
    let t1 = ltc_view_tangent(n, v);
    let t2 = cross(n, t1);
    let ta = ltc_apply(cell, vec3<f32>(dot(a, t1), dot(a, t2), dot(a, n)));
    let tb = ltc_apply(cell, vec3<f32>(dot(b, t1), dot(b, t2), dot(b, n)));
    let tc = ltc_apply(cell, vec3<f32>(dot(c, t1), dot(c, t2), dot(c, n)));
    let td = ltc_apply(cell, vec3<f32>(dot(d, t1), dot(d, t2), dot(d, n)));
    return ltc_form_factor(ta, tb, tc, td) * cell.moments;
}
