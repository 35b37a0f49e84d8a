// The visibility of one sampled sky direction over the cone of directions it stands for
// (after direct_shade.wgsl: uses its bindings, `sample_view` and `on_plane`).
//
// A frame draws `sky_count` directions (16 by default), each standing for a solid angle
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
    return SkyCone(noise, t1, t2, clip, ct1, ct2, size);
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

// The visibility of sky record `i` (shadow layer `layer`) at receiver `p` (geometric normal
// `ng`, its cone frame `c`; `q`: `p` moved off the surface for the lookup): one bilinear tap
// of the drawn direction unless the ratio estimator is on and the record holds its cone (see
// the header).
fn sky_visibility(i: u32, layer: u32, c: SkyCone, p: vec3<f32>, ng: vec3<f32>, q: vec3<f32>) -> f32 {
    let m = sample_view(layer);
    let tap = shadow_tap(sample_maps, shadow_sampler, m, layer, q);
    // x: world units of depth 0 → 1; y: tan α; z: world size of a texel.
    let cone = textureLoad(sample_records, vec2<u32>(2u, i), 0);
    if direct_params.ratio == 0u || cone.y <= 0.0 {
        return tap;
    }
    let clip = m * vec4<f32>(q, 1.0);
    let z = clip.z;
    let spread = cone.x * cone.y / cone.z;
    if z * spread < 1.0 {
        return tap;
    }
    let uv = clip.xy * vec2<f32>(0.5, -0.5) + 0.5;
    let angle = TWO_PI * c.noise + f32(i) * 1.7;
    let turn = vec2<f32>(cos(angle), sin(angle));
    let b = sky_cone_blockers(layer, uv, z, spread, turn);
    if b.y == 0.0 {
        return tap;
    }
    if b.y == f32(SKY_CONE_SEARCH) && tap == 0.0 {
        return 0.0;
    }
    // The penumbra's radius on the receiver: the blockers' height above it times tan α.
    let rho = (z - b.x) * cone.x * cone.y;
    // Receiver points on the disc of that radius in the tangent plane, each replaced by the
    // G-buffer sample of its pixel when that lies on the same plane and within the disc
    // (a surface the camera sees: the disc never reaches through a wall), each looked up
    // along the drawn direction from its own position. The disc is the search's turned by
    // 0.9 rad.
    let offset = q - p;
    var v = tap;
    var n = 1.0;
    var dir = sky_cone_turn(turn, vec2<f32>(0.6216100, 0.7833269));
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
