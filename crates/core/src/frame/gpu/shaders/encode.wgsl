// The frame's radiance encoded for readback (`frame::gpu::encode`) into a storage buffer,
// one thread a pixel, rows top first, the same formulas as `frame::readout` (CPU) and
// `gi.display` (Python): the tone-mapped 8-bit sRGB image (exposure, then `clip` or
// `agx`, then round(255·v), as numpy rounds: half to even) as RGBA8 words, or the
// radiance as RGBA half floats (two words a pixel), as the uniform says.

struct Encode {
    // 2^exposure.
    scale: f32,
    // 0: clip, 1: agx.
    tonemap: u32,
    // 1: the half-float encoding; 0: the display image.
    half: u32,
    _pad: u32,
}

@group(0) @binding(0) var radiance: texture_2d<f32>;
@group(0) @binding(1) var<uniform> encode: Encode;
@group(0) @binding(2) var<storage, read_write> encoded: array<u32>;

fn srgb_encode(v: vec3<f32>) -> vec3<f32> {
    let x = clamp(v, vec3<f32>(0.0), vec3<f32>(1.0));
    let curve = 1.055 * pow(x, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(curve, 12.92 * x, x <= vec3<f32>(0.0031308));
}

// Rows of the AgX matrices are the input channels (`rgb @ M`, as in `gi.display`): each
// row given as a WGSL column, so that `W * x = Σ_i row_i · x_i = x @ M`.
const AGX_INSET = mat3x3<f32>(
    vec3<f32>(0.842479062253094, 0.0423282422610123, 0.0423756549057051),
    vec3<f32>(0.0784335999999992, 0.878468636469772, 0.0784336),
    vec3<f32>(0.0792237451477643, 0.0791661274605434, 0.879142973793104),
);
const AGX_OUTSET = mat3x3<f32>(
    vec3<f32>(1.19687900512017, -0.0528968517574562, -0.0529716355144438),
    vec3<f32>(-0.0980208811401368, 1.15190312990417, -0.0980434501171241),
    vec3<f32>(-0.0990297440797205, -0.0989611768448433, 1.15107367264116),
);
const AGX_MIN_EV: f32 = -12.47393;
const AGX_MAX_EV: f32 = 4.026069;

fn agx(linear: vec3<f32>) -> vec3<f32> {
    let x = AGX_INSET * max(linear, vec3<f32>(1e-10));
    let t = (clamp(log2(max(x, vec3<f32>(1e-10))), vec3<f32>(AGX_MIN_EV), vec3<f32>(AGX_MAX_EV))
        - AGX_MIN_EV) / (AGX_MAX_EV - AGX_MIN_EV);
    var s = vec3<f32>(15.5);
    s = s * t - 40.14;
    s = s * t + 31.96;
    s = s * t - 6.868;
    s = s * t + 0.4298;
    s = s * t + 0.1191;
    s = s * t - 0.00232;
    let y = clamp(AGX_OUTSET * s, vec3<f32>(0.0), vec3<f32>(1.0));
    return srgb_encode(pow(y, vec3<f32>(2.2)));
}

// NaN and ±infinity show black, as in `gi.display.to_display`.
fn finite(v: vec3<f32>) -> vec3<f32> {
    let bad = (v != v) | (abs(v) > vec3<f32>(3.4e38));
    return select(v, vec3<f32>(0.0), bad);
}

// The index of thread `id`'s pixel, rows top first; -1 outside the image.
fn pixel_index(id: vec3<u32>) -> i32 {
    let size = textureDimensions(radiance);
    if id.x >= size.x || id.y >= size.y {
        return -1;
    }
    return i32(id.y * size.x + id.x);
}

// The display image's RGBA8 word of radiance `c`.
fn display_word(c: vec3<f32>) -> u32 {
    let x = max(finite(c), vec3<f32>(0.0)) * encode.scale;
    var v = srgb_encode(x);
    if encode.tonemap == 1u {
        v = agx(x);
    }
    // round() first: pack4x8unorm rounds half up, numpy half to even.
    let q = round(clamp(v, vec3<f32>(0.0), vec3<f32>(1.0)) * 255.0) / 255.0;
    return pack4x8unorm(vec4<f32>(q, 1.0));
}

@compute @workgroup_size(8, 8)
fn cs_encode(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = pixel_index(id);
    if i < 0 {
        return;
    }
    let c = textureLoad(radiance, vec2<i32>(id.xy), 0).xyz;
    if encode.half == 1u {
        encoded[2 * i] = pack2x16float(c.xy);
        encoded[2 * i + 1] = pack2x16float(vec2<f32>(c.z, 1.0));
    } else {
        encoded[i] = display_word(c);
    }
}
