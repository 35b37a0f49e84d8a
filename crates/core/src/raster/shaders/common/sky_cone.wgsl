// The visibility of one sampled sky direction over the cone of directions it stands for
// (after direct_shade.wgsl: uses its bindings, `sample_view` and `on_plane`).
//
// A frame draws `sky_count` directions (64 by default), each standing for a solid angle
// Ω = 1/(N·p(ω)) of the sky. Looked up with one tap of its orthographic shadow map, each
// direction shadows as a parallel light: a room lit through a window got one hard,
// window-shaped patch per direction that passes the opening, moving with the seed (Bitterli's
// living-room; tests/test_sky_openings.py). Here, in ordinary frames, a direction's
// visibility is its mean over the cone of half-angle α, 2π(1 − cos α) = Ω, around it, by
// percentage-closer soft shadows (Fernando 2005) taken on the receiver: the blockers inside
// the cone are searched in the direction's map, their mean height h above the receiver sets
// the penumbra's radius ρ = h·tan α (for a blocker parallel to the receiver, moving the
// receiver point by x on its plane is tilting the direction by x/h), and the visibility is
// the mean of the drawn direction's taps at receiver points on a disc of radius ρ in the
// tangent plane. Those points are the eye G-buffer's samples on the same plane (the pixel
// each disc point falls in): surfaces that exist, so that the disc never reaches through a
// wall (a floor plane continued past the room's wall would be lit by every direction; a
// lookup of the cone's rays in the one depth layer of the map cannot see the walls under the
// roof either, and leaked light near every wall, 2-3x the room's light). The disc is turned
// per pixel (interleaved gradient noise, Jimenez 2014) and per direction, so the directions'
// sum has noise, not banding.
//
// Bias (ordinary frames only; progressive passes keep the one tap of the drawn direction,
// whose mean over passes converges): the light of the cone is weighted as its centre's
// (f·cos·E of the drawn direction); the cone's visibility is PCSS's estimate (one mean
// blocker height per lookup, a single depth layer, a planar receiver), over the receiver
// points the camera sees (a disc partly hidden or off screen averages the rest); cones of
// neighbouring directions overlap or leave gaps where the lattice is uneven. Measured on
// tests/scenes/openings/window_room.json: see tests/test_sky_openings.py.
//
// Cost (`sky_sums`): a pixel takes the cones of one direction in `SKY_CONE_SHARE` (2: the
// even or the odd ones, by a checkerboard of pixels) and the drawn direction's tap for the
// others; the taken cone corrects the tap by twice its difference, clamped to a visibility
// in [0, 1]. Unclamped, a pair of neighbouring pixels would have the mean of both cones (the
// sums are linear in each direction's visibility: no ratio over fewer directions, which
// spread the frame mean over seeds); the clamp keeps every pixel's light non-negative (3-4%
// of window_room's pixels went below 0 without it) and biases the frame mean up by ~0.8%
// there (direct 0.991-1.006 of `path` with every cone, 0.999-1.013 with half).

// The blocker search's widest disc, in texels of the sampled lights' maps.
const SKY_CONE_MAX: f32 = 40.0;
// Blocker-search and filter taps per direction.
const SKY_CONE_SEARCH: u32 = 4u;
const SKY_CONE_TAPS: u32 = 8u;

// What a shading point's cones share, computed once a pixel (`sky_cone_frame`): its
// pixel's noise, its tangent frame and their clip-space images in the eye view (a disc
// point p + x·t1 + y·t2 projects to clip + x·clip_t1 + y·clip_t2: no matrix a tap).
struct SkyCone {
    noise: f32,
    t1: vec3<f32>,
    t2: vec3<f32>,
    clip: vec4<f32>,
    clip_t1: vec4<f32>,
    clip_t2: vec4<f32>,
    size: vec2<i32>,
    // Which of the directions the pixel takes the cones of (`sky_sums`): those with
    // k ≡ phase (mod `SKY_CONE_SHARE`).
    phase: u32,
}

fn sky_cone_frame(p: vec3<f32>, ng: vec3<f32>) -> SkyCone {
    let t1 = normalize(select(vec3<f32>(0.0, -ng.z, ng.y), vec3<f32>(-ng.y, ng.x, 0.0), abs(ng.z) < 0.9));
    let t2 = cross(ng, t1);
    let clip = view.view_proj * vec4<f32>(p, 1.0);
    let size = vec2<i32>(textureDimensions(g_position));
    // Interleaved gradient noise (Jimenez 2014) of the pixel that sees `p`, in [0, 1).
    let px = floor(sky_cone_window(clip, size));
    let noise = fract(52.9829189 * fract(dot(px, vec2<f32>(0.06711056, 0.00583715))));
    let ct1 = view.view_proj * vec4<f32>(t1, 0.0);
    let ct2 = view.view_proj * vec4<f32>(t2, 0.0);
    // Each 2×2 block of pixels holds every phase of 4 (a checkerboard for 2).
    let ip = vec2<u32>(max(px, vec2<f32>(0.0)));
    let phase = select((ip.x + ip.y) & 1u, (ip.x & 1u) + 2u * (ip.y & 1u), SKY_CONE_SHARE == 4u) % SKY_CONE_SHARE;
    return SkyCone(noise, t1, t2, clip, ct1, ct2, size, phase);
}

// The edge passes (direct_edges.wgsl `shade_edges`) shade every sub-pixel sample of a pixel
// on a geometric edge (no quad to share with): sub-pixel sample `s` looks up only the
// directions k ≡ s (mod `SKY_PHASES`), each with its cone (`sky_share_sums`), so that the
// pixel's mean over its samples (4 by default) has every direction, at a quarter of the
// cost. The phase is the same for every pixel of a dispatch: lanes that skip different
// directions would each wait for the others' (SIMD on the CPU's lavapipe). Bias: each
// sample's ratio estimators are over its quarter of the directions (on edge pixels alone).
var<private> sky_edge_phase: u32;

fn sky_edge_sample(s: u32) {
    sky_edge_phase = 1u + s % SKY_PHASES;
}

// The window position (pixels) of clip-space point `clip` in the eye view.
fn sky_cone_window(clip: vec4<f32>, size: vec2<i32>) -> vec2<f32> {
    return (clip.xy / clip.w * vec2<f32>(0.5, -0.5) + 0.5) * vec2<f32>(size);
}

// Most sky directions one shading point looks up in ordinary frames: with more (the
// `sky_samples` option up to 256), each pixel takes every k-th from an offset of its own, so
// that the frame's directions all count in the image while a pixel pays for 64. (Thinning
// the default 64 per pixel was tried on window_room, seeds 1-4: 16 a pixel cut the frame's
// time ~4x but spread its mean over seeds 1.98% and 32 2.11%, against 1.57% with all 64.)
const SKY_PIXEL_DIRECTIONS: u32 = 64u;

// One in this many of the directions a pixel looks up takes its cone there (1, 2 or 4; see
// the header). 4 was tried on window_room: frame mean 1.010-1.026 of `path` (the clamp), floor
// patch error 0.40-0.54 (over the test's 0.5), against 1.000-1.013 and 0.31-0.45 with 2.
const SKY_CONE_SHARE: u32 = 2u;

// The sky records a shading point at `p` looks up, as (first, step, count) from the first
// sky record: all of them in progressive passes (their plain sums must converge) or when
// there are at most `SKY_PIXEL_DIRECTIONS`; else every `step`-th (the stratified lattice
// thinned evenly) from a per-pixel offset.
fn sky_subset(c: SkyCone) -> vec3<u32> {
    let n = direct_params.sky_count;
    if direct_params.ratio == 0u || n <= SKY_PIXEL_DIRECTIONS {
        return vec3<u32>(0u, 1u, n);
    }
    let step = n / SKY_PIXEL_DIRECTIONS;
    let first = min(u32(c.noise * f32(step)), step - 1u);
    return vec3<u32>(first, step, (n - first + step - 1u) / step);
}

// The golden angle's rotation (cos, sin): a Vogel disc's point j + 1 is point j turned by it.
const SKY_GOLDEN = vec2<f32>(-0.7373688, 0.6754903);

// `r` turned by the angle whose (cos, sin) is `turn`.
fn sky_cone_turn(r: vec2<f32>, turn: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(r.x * turn.x - r.y * turn.y, r.x * turn.y + r.y * turn.x);
}

// The mean depth (x) and count (y) of the blockers of sky record `i`'s cone (tan α `tan_a`)
// above the receiver at map position `uv`, depth `z`: the surfaces seen in the map inside
// the cone, i.e. at a lateral offset (texels) under their height above the receiver (depth
// units) times `spread` (texels per depth unit at the cone's rim), by a texel and a half
// (the receiver's own surface near it, the depth bias). The search reaches the widest disc,
// its `SKY_CONE_SEARCH` points on a Vogel disc whose first point's angle is `turn` (cos, sin).
fn sky_cone_blockers(layer: u32, uv: vec2<f32>, z: f32, spread: f32, turn: vec2<f32>) -> vec2<f32> {
    let size = f32(textureDimensions(sample_maps).x);
    let search = min(z * spread, SKY_CONE_MAX);
    var blockers = 0.0;
    var zb = 0.0;
    var dir = turn;
    for (var j = 0u; j < SKY_CONE_SEARCH; j++) {
        let o = dir * (sqrt((f32(j) + 0.5) / f32(SKY_CONE_SEARCH)) * search);
        dir = sky_cone_turn(dir, SKY_GOLDEN);
        let t = clamp(vec2<i32>(floor(uv * size + o)), vec2<i32>(0), vec2<i32>(i32(size) - 1));
        let d = textureLoad(sample_maps, t, layer, 0);
        if (z - d) * spread >= length(o) + 1.5 {
            blockers += 1.0;
            zb += d;
        }
    }
    return vec2<f32>(zb / max(blockers, 1.0), blockers);
}

// Whether world point `p` is lit in shadow layer `layer` (view `m`, orthographic): its depth
// against the map's texel (clamped to the edge, as the comparison sampler is), one texel:
// the cone's taps average many, so no bilinear filter.
fn sky_cone_tap(m: mat4x4<f32>, layer: u32, p: vec3<f32>) -> f32 {
    let clip = m * vec4<f32>(p, 1.0);
    let size = vec2<i32>(textureDimensions(sample_maps));
    let uv = clip.xy * vec2<f32>(0.5, -0.5) + 0.5;
    let t = clamp(vec2<i32>(floor(uv * vec2<f32>(size))), vec2<i32>(0), size - 1);
    return select(0.0, 1.0, clip.z <= textureLoad(sample_maps, t, layer, 0));
}

// Where sky record `i`'s cone meets its shadow layer `layer` (view `m`) for the receiver
// moved to `q`: (map uv, depth z, `spread`: texels per depth unit at the cone's rim), or
// spread 0 where the drawn direction's tap stands for the cone (progressive passes, a record
// without a cone, a cone narrower than a texel at that depth).
fn sky_cone_site(i: u32, m: mat4x4<f32>, q: vec3<f32>) -> vec4<f32> {
    // x: world units of depth 0 → 1; y: tan α; z: world size of a texel.
    let cone = textureLoad(sample_records, vec2<u32>(2u, i), 0);
    let clip = m * vec4<f32>(q, 1.0);
    let spread = cone.x * cone.y / max(cone.z, 1e-30);
    let uv = clip.xy * vec2<f32>(0.5, -0.5) + 0.5;
    let on = direct_params.ratio != 0u && cone.y > 0.0 && clip.z * spread >= 1.0;
    return vec4<f32>(uv, clip.z, select(0.0, spread, on));
}

// The first point's angle (cos, sin) of sky record `i`'s Vogel discs at the pixel of `c`.
fn sky_cone_start(i: u32, c: SkyCone) -> vec2<f32> {
    let angle = TWO_PI * c.noise + f32(i) * 1.7;
    return vec2<f32>(cos(angle), sin(angle));
}

// The blockers (`sky_cone_blockers`) of sky record `i` at `site` (`sky_cone_site`) where its
// cone's visibility may differ from `tap`, the drawn direction's: some blocker, and not all
// of them over a shadowed receiver; (0, 0) elsewhere.
fn sky_cone_penumbra(i: u32, layer: u32, c: SkyCone, site: vec4<f32>, tap: f32) -> vec2<f32> {
    if site.w == 0.0 {
        return vec2<f32>(0.0);
    }
    let b = sky_cone_blockers(layer, site.xy, site.z, site.w, sky_cone_start(i, c));
    if b.y == f32(SKY_CONE_SEARCH) && tap == 0.0 {
        return vec2<f32>(0.0);
    }
    return b;
}

// The visibility over its cone of sky record `i` (shadow layer `layer`, its view `m`) at
// receiver `p` (geometric normal `ng`, cone frame `c`; `q`: `p` moved off the surface for
// the lookup; `tap`: the drawn direction's visibility there; `zb`: its blockers' mean
// depth): the drawn direction's taps at the receiver points on the penumbra's disc (see the
// header).
fn sky_cone_visibility(i: u32, layer: u32, m: mat4x4<f32>, c: SkyCone, p: vec3<f32>, ng: vec3<f32>, q: vec3<f32>, tap: f32, zb: f32) -> f32 {
    let cone = textureLoad(sample_records, vec2<u32>(2u, i), 0);
    let z = (m * vec4<f32>(q, 1.0)).z;
    // The penumbra's radius on the receiver: the blockers' height above it times tan α.
    let rho = (z - zb) * cone.x * cone.y;
    // Receiver points on the disc of that radius in the tangent plane, each replaced by the
    // G-buffer sample of its pixel when that lies on the same plane and within the disc
    // (a surface the camera sees: the disc never reaches through a wall), each looked up
    // along the drawn direction from its own position. The disc is the search's turned by
    // 0.9 rad.
    let offset = q - p;
    var v = tap;
    var n = 1.0;
    var dir = sky_cone_turn(sky_cone_start(i, c), vec2<f32>(0.6216100, 0.7833269));
    for (var j = 0u; j < SKY_CONE_TAPS; j++) {
        let d = dir * (sqrt((f32(j) + 0.5) / f32(SKY_CONE_TAPS)) * rho);
        dir = sky_cone_turn(dir, SKY_GOLDEN);
        let px = vec2<i32>(floor(sky_cone_window(c.clip + d.x * c.clip_t1 + d.y * c.clip_t2, c.size)));
        if any(px < vec2<i32>(0)) || any(px >= c.size) {
            continue;
        }
        let g = textureLoad(g_position, px, 0);
        if !on_plane(p, ng, g) || distance(g.xyz, p) > 1.25 * rho {
            continue;
        }
        v += sky_cone_tap(m, layer, g.xyz + offset);
        n += 1.0;
    }
    return v / n;
}

// The sampled sky directions' sums at a shading point: the diffuse lobe's, the glossy
// lobe's and the cosine's light, shadowed (`lit`, `glit`, `clit`) and not.
struct SkySums {
    lit: vec3<f32>,
    unshadowed: vec3<f32>,
    glit: vec3<f32>,
    gun: vec3<f32>,
    clit: vec3<f32>,
    cun: vec3<f32>,
}

// One sampled sky direction's terms at a shading point: its record `i`, f_d·cos·E,
// f_s·cos·E, cos·E, its shadow layer, the lookup point and the drawn direction's tap
// (`sky_tapped`); `used` false where it does not light the point.
struct SkyTerm {
    i: u32,
    fd: vec3<f32>,
    fs: vec3<f32>,
    e: vec3<f32>,
    layer: u32,
    q: vec3<f32>,
    tap: f32,
    used: bool,
}

// Adds term `t` seen with visibility `v` to the shadowed sums of `s`.
fn sky_add_lit(s: ptr<function, SkySums>, t: SkyTerm, v: f32) {
    (*s).lit += t.fd * v;
    (*s).glit += t.fs * v;
    (*s).clit += t.e * v;
}

// Adds term `t` with visibility `v` to the sums of `s`, shadowed and not.
fn sky_add(s: ptr<function, SkySums>, t: SkyTerm, v: f32) {
    sky_add_lit(s, t, v);
    (*s).unshadowed += t.fd;
    (*s).gun += t.fs;
    (*s).cun += t.e;
}

fn sky_term(i: u32, p: vec3<f32>, ns: vec3<f32>, ng: vec3<f32>, m: Material, glossy: Material, wo: vec3<f32>, has_glossy: bool) -> SkyTerm {
    var t: SkyTerm;
    t.i = i;
    let t0 = textureLoad(sample_records, vec2<u32>(0u, i), 0);
    let wi = t0.xyz;
    let cos_g = dot(wi, ng);
    let t1 = textureLoad(sample_records, vec2<u32>(1u, i), 0);
    t.e = select(vec3<f32>(0.0), t1.xyz * abs(dot(ns, wi)), cos_g > 0.0);
    t.fd = diffuse_eval(m, ns, wo, wi) * t.e;
    if has_glossy {
        t.fs = exact_glossy(glossy, ns, wo, wi) * t.e;
    }
    t.used = cos_g > 0.0 && max3(t.fd + t.fs + t.e) > 0.0;
    // The sky's layers follow the emitter points' six each, in order (`samples.rs`).
    // Computed from the loop index, not read from the record: on an NVIDIA H100 the
    // record's layer (a value the same for every pixel, loaded from a texture) passed to
    // `shadow_tap` looked up the wrong map from the second direction on (18-29% dark;
    // docs/gpu-check.md), while the index-derived one is right on every adapter.
    t.layer = 6u * direct_params.area_count + (i - direct_params.area_count);
    t.q = p + ng * (t1.w * (1.0 - cos_g) + 0.5 * t1.w);
    return t;
}

// The term of direction `k` of subset `sub` (`sky_subset`) at a shading point, with its
// drawn direction's tap where it lights the point.
fn sky_tapped(k: u32, sub: vec3<u32>, p: vec3<f32>, ns: vec3<f32>, ng: vec3<f32>, m: Material, glossy: Material, wo: vec3<f32>, has_glossy: bool) -> SkyTerm {
    var t = sky_term(direct_params.area_count + sub.x + k * sub.y, p, ns, ng, m, glossy, wo, has_glossy);
    if t.used {
        t.tap = shadow_tap(sample_maps, shadow_sampler, sample_view(t.layer), t.layer, t.q);
    }
    return t;
}

// The sums over the sky directions a shading point looks up (`sky_subset`) in two passes:
// every direction with its drawn direction's tap, noting those of the pixel's share
// (`SkyCone::phase`) whose cone may differ from it (`sky_cone_penumbra`) with their tap and
// blockers; then those alone, each sum corrected by `SKY_CONE_SHARE` times the cone's
// visibility less the tap, clamped to a visibility in [0, 1] (see the header).
fn sky_sums(p: vec3<f32>, ns: vec3<f32>, ng: vec3<f32>, m: Material, glossy: Material, wo: vec3<f32>, has_glossy: bool) -> SkySums {
    var s: SkySums;
    let c = sky_cone_frame(p, ng);
    let sub = sky_subset(c);
    var todo = vec2<u32>(0u);
    // The penumbra directions' drawn taps and mean blocker depths, by `k`.
    var taps: array<f32, SKY_PIXEL_DIRECTIONS>;
    var depths: array<f32, SKY_PIXEL_DIRECTIONS>;
    for (var k = 0u; k < sub.z; k++) {
        let t = sky_tapped(k, sub, p, ns, ng, m, glossy, wo, has_glossy);
        if !t.used {
            continue;
        }
        sky_add(&s, t, t.tap);
        if k % SKY_CONE_SHARE != c.phase {
            continue;
        }
        let b = sky_cone_penumbra(t.i, t.layer, c, sky_cone_site(t.i, sample_view(t.layer), t.q), t.tap);
        if b.y > 0.0 {
            taps[k] = t.tap;
            depths[k] = b.x;
            todo |= select(vec2<u32>(0u, 1u << (k - 32u)), vec2<u32>(1u << k, 0u), k < 32u);
        }
    }
    // The penumbra directions (k < 64: `SKY_PIXEL_DIRECTIONS`).
    loop {
        if all(todo == vec2<u32>(0u)) {
            break;
        }
        let low = todo.x != 0u;
        let k = select(32u + firstTrailingBit(todo.y), firstTrailingBit(todo.x), low);
        todo = select(vec2<u32>(todo.x, todo.y & (todo.y - 1u)), vec2<u32>(todo.x & (todo.x - 1u), todo.y), low);
        let i = direct_params.area_count + sub.x + k * sub.y;
        let t = sky_term(i, p, ns, ng, m, glossy, wo, has_glossy);
        let tap = taps[k];
        let cone = sky_cone_visibility(i, t.layer, sample_view(t.layer), c, p, ng, t.q, tap, depths[k]);
        let dv = clamp(tap + f32(SKY_CONE_SHARE) * (cone - tap), 0.0, 1.0) - tap;
        sky_add_lit(&s, t, dv);
    }
    return s;
}

// Half resolution: the full-screen passes share the cones over each 2×2 quad of pixels
// (`sky_quad_prepare`, called by the entry points before shading; quad values are exchanged
// by fine derivatives, so no extra pass, target or binding). Where the quad's four samples
// lie on one plane, each pixel looks up only the directions k ≡ its quad position (mod 4)
// of `sky_subset`, every one of them with its cone where a penumbra is near, and the quad's
// four partial sums are added: each pixel's visibility ratios are over every direction, each
// direction's cone taken at one of the quad's pixels (an estimate of the cone's visibility
// at a point at most a pixel away, on the same plane: the cone's disc is many pixels wide
// wherever it differs from the tap). A quad across a plane break (and the edge passes, and
// progressive passes: no cones there) shades each pixel with all its directions
// (`sky_sums`). Bias, beyond the cones' own (header): the visibility ratios are constant over
// a quad (a shadow sharper than two pixels is blurred to the quad: contact shadows), and
// the quad's samples' lobes weight their directions in one ratio.
var<private> sky_quad_on: bool;
var<private> sky_quad: SkySums;
// The quad's phases (and the edge passes' samples', above).
const SKY_PHASES: u32 = 4u;

// The sum of `v` over the pixel's 2×2 quad (`s`: +1 on even, −1 on odd columns and rows).
fn sky_quad_sum(v: vec3<f32>, s: vec2<f32>) -> vec3<f32> {
    let row = 2.0 * v + s.x * dpdxFine(v);
    return 2.0 * row + s.y * dpdyFine(row);
}

// Whether every sample of the pixel's quad has a surface on the plane of this one's
// (`p`, geometric normal `ng`, coverage `w`): exchanged by fine derivatives.
fn sky_quad_flat(p: vec3<f32>, ng: vec3<f32>, w: f32, s: vec2<f32>) -> bool {
    let pos = vec4<f32>(p, w);
    let px = pos + s.x * dpdxFine(pos);
    let py = pos + s.y * dpdyFine(pos);
    let pd = py + s.x * dpdxFine(py);
    let nx = ng + s.x * dpdxFine(ng);
    let ny = ng + s.y * dpdyFine(ng);
    let nd = ny + s.x * dpdxFine(ny);
    var level = w > 0.0 && on_plane(p, ng, px) && on_plane(p, ng, py) && on_plane(p, ng, pd);
    level = level && min(dot(ng, nx), min(dot(ng, ny), dot(ng, nd))) > 0.95;
    let count = sky_quad_sum(vec3<f32>(select(0.0, 1.0, level)), s).x;
    return count > 3.5;
}

// The sums over the directions k ≡ `phase` (mod `SKY_PHASES`) of `sky_subset`, each with its cone's
// visibility where a penumbra is near (else its tap).
fn sky_share_sums(p: vec3<f32>, ns: vec3<f32>, ng: vec3<f32>, m: Material, glossy: Material, wo: vec3<f32>, has_glossy: bool, phase: u32) -> SkySums {
    var s: SkySums;
    let c = sky_cone_frame(p, ng);
    let sub = sky_subset(c);
    for (var k = phase; k < sub.z; k += SKY_PHASES) {
        let t = sky_tapped(k, sub, p, ns, ng, m, glossy, wo, has_glossy);
        if !t.used {
            continue;
        }
        let mv = sample_view(t.layer);
        var v = t.tap;
        let b = sky_cone_penumbra(t.i, t.layer, c, sky_cone_site(t.i, mv, t.q), v);
        if b.y > 0.0 {
            v = sky_cone_visibility(t.i, t.layer, mv, c, p, ng, t.q, v, b.x);
        }
        sky_add(&s, t, v);
    }
    return s;
}

// Sets the quad's sky sums (`sky_quad`, `sky_quad_on`) for the sample `g` of the pixel at
// window position `frag`; called in uniform control flow by the full-screen entry points
// before they shade (see above).
fn sky_quad_prepare(frag: vec2<f32>, g: GSample) {
    sky_quad_on = false;
    if !SAMPLED_LIGHTS || direct_params.sky_count == 0u || direct_params.ratio == 0u {
        return;
    }
    let ip = vec2<u32>(max(frag, vec2<f32>(0.0)));
    let odd = vec2<f32>(ip & vec2<u32>(1u));
    let s = 1.0 - 2.0 * odd;
    let p = g.position.xyz;
    let ng = oct_decode(g.normals.zw);
    let flat = sky_quad_flat(p, ng, g.position.w, s);
    var own: SkySums;
    if flat {
        let m = sample_material(g);
        var glossy = m;
        glossy.diffuse = vec3<f32>(0.0);
        let has_glossy = GLOSSY && max3(m.specular) > 0.0;
        let ns = oct_decode(g.normals.xy);
        let phase = (ip.x & 1u) + 2u * (ip.y & 1u);
        own = sky_share_sums(p, ns, ng, m, glossy, normalize(view.eye - p), has_glossy, phase);
    }
    sky_quad.lit = sky_quad_sum(own.lit, s);
    sky_quad.unshadowed = sky_quad_sum(own.unshadowed, s);
    sky_quad.glit = sky_quad_sum(own.glit, s);
    sky_quad.gun = sky_quad_sum(own.gun, s);
    sky_quad.clit = sky_quad_sum(own.clit, s);
    sky_quad.cun = sky_quad_sum(own.cun, s);
    sky_quad_on = flat;
}

// The sky's sums at a shading point: its quad's (`sky_quad_prepare`) where they were shared,
// an edge sample's phase of the directions (`sky_edge_sample`), else its own over every
// direction (`sky_sums`).
fn sky_pixel_sums(p: vec3<f32>, ns: vec3<f32>, ng: vec3<f32>, m: Material, glossy: Material, wo: vec3<f32>, has_glossy: bool) -> SkySums {
    if sky_quad_on {
        return sky_quad;
    }
    if sky_edge_phase > 0u && direct_params.ratio != 0u {
        return sky_share_sums(p, ns, ng, m, glossy, wo, has_glossy, sky_edge_phase - 1u);
    }
    return sky_sums(p, ns, ng, m, glossy, wo, has_glossy);
}
