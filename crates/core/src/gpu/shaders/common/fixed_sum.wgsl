// An order-independent sum of RGB terms: 96-bit fixed point per channel with 48 fractional
// bits (resolution 3.6e-15, range ±1.4e14; two's complement for `fixed_add_signed`),
// added exactly in integers, so the same terms in any order give the same bits. The compute estimators
// build their photon lists with atomics, in an order that varies between runs; summing
// through this keeps their images bitwise reproducible. Each term is truncated below
// 2^-48 (a relative error far below f32's rounding for any visible term); NaN and zero terms
// are skipped, and `fixed_add` skips negative ones; terms of 2^47 or more saturate.

struct FixedSum {
    lo: vec3<u32>,
    mid: vec3<u32>,
    hi: vec3<u32>,
}

fn fixed_zero() -> FixedSum {
    return FixedSum(vec3<u32>(0u), vec3<u32>(0u), vec3<u32>(0u));
}

// `m` shifted left by `s` bits (any s ≥ 0) as 96 bits: (word 0, word 1, word 2).
fn fixed_words(m: u32, s: i32) -> vec3<u32> {
    if s < 0 {
        return vec3<u32>(select(m >> u32(-s), 0u, -s >= 32), 0u, 0u);
    }
    let u = u32(s);
    if u < 32u {
        return vec3<u32>(m << u, select(m >> (32u - u), 0u, u == 0u), 0u);
    }
    if u < 64u {
        let v = u - 32u;
        return vec3<u32>(0u, m << v, select(m >> (32u - v), 0u, v == 0u));
    }
    if u <= 71u {
        return vec3<u32>(0u, 0u, m << (u - 64u));
    }
    return vec3<u32>(0u, 0u, 0x7fffffffu);
}

// |v|·2^48 as 96 bits.
fn fixed_magnitude(v: f32) -> vec3<u32> {
    let bits = bitcast<u32>(abs(v));
    let e = (bits >> 23u) & 0xffu;
    // |v| = m·2^(e−150) (normal) or m·2^(−149) (subnormal); times 2^48.
    let m = (bits & 0x7fffffu) | select(0x800000u, 0u, e == 0u);
    let s = select(i32(e), 1, e == 0u) - 102;
    return fixed_words(m, s);
}

// `acc` plus the non-negative terms of `t`.
fn fixed_add(acc: FixedSum, t: vec3<f32>) -> FixedSum {
    var out = acc;
    for (var c = 0u; c < 3u; c++) {
        if t[c] > 0.0 {
            out = fixed_add_words(out, c, fixed_magnitude(t[c]));
        }
    }
    return out;
}

// Two's complement of a 96-bit value.
fn fixed_negate(w: vec3<u32>) -> vec3<u32> {
    let n0 = ~w.x + 1u;
    let c0 = u32(w.x == 0u);
    let n1 = ~w.y + c0;
    let c1 = u32(c0 == 1u && w.y == 0u);
    return vec3<u32>(n0, n1, ~w.z + c1);
}

// `acc` plus `t`, of any sign.
fn fixed_add_signed(acc: FixedSum, t: vec3<f32>) -> FixedSum {
    var out = acc;
    for (var c = 0u; c < 3u; c++) {
        let v = t[c];
        if v > 0.0 {
            out = fixed_add_words(out, c, fixed_magnitude(v));
        } else if v < 0.0 {
            out = fixed_add_words(out, c, fixed_negate(fixed_magnitude(v)));
        }
    }
    return out;
}

// `acc` plus the 96-bit `w` in channel `c`, carrying between the words.
fn fixed_add_words(acc: FixedSum, c: u32, w: vec3<u32>) -> FixedSum {
    var out = acc;
    let lo = acc.lo[c] + w.x;
    let c0 = u32(lo < w.x);
    let mid1 = acc.mid[c] + w.y;
    let c1 = u32(mid1 < w.y);
    let mid2 = mid1 + c0;
    let c2 = u32(mid2 < c0);
    out.lo[c] = lo;
    out.mid[c] = mid2;
    out.hi[c] = acc.hi[c] + w.z + c1 + c2;
    return out;
}

fn fixed_value(acc: FixedSum) -> vec3<f32> {
    return vec3<f32>(acc.hi) * 65536.0 + vec3<f32>(acc.mid) * (1.0 / 65536.0)
        + vec3<f32>(acc.lo) * 3.5527137e-15;
}

// The value of a sum made with `fixed_add_signed` (two's complement).
fn fixed_value_signed(acc: FixedSum) -> vec3<f32> {
    var out = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c++) {
        var w = vec3<u32>(acc.lo[c], acc.mid[c], acc.hi[c]);
        let negative = (w.z >> 31u) != 0u;
        if negative {
            w = fixed_negate(w);
        }
        let v = f32(w.z) * 65536.0 + f32(w.y) * (1.0 / 65536.0) + f32(w.x) * 3.5527137e-15;
        out[c] = select(v, -v, negative);
    }
    return out;
}
