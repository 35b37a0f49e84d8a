//! Hot-spot control of the lighting pass's image (issue 48), mean-preserving: a pixel of
//! the indirect light far above its neighbourhood (a VPL next to the surface it lights, a
//! light subpath's corner path: the 1/d² of a connection the MIS weights do not damp) keeps
//! [`SPIKE_FACTOR`] times the neighbourhood's median (plus a floor of
//! [`FLOOR_SHARE`] of the image's mean), and its excess is spread evenly over the covered
//! pixels of the (2·[`SPREAD_RADIUS`] + 1)² window around it; first on blocks of 2×2
//! pixels ([`LEVELS`]: a spike a few pixels wide, its excess over a window of 7×7 blocks),
//! then on single pixels.
//!
//! Bias, stated: the excess stays within [`SPREAD_RADIUS`] pixels (blocks at the second
//! level: up to 7 pixels) of where it was drawn, so
//! the image's sum (its mean) is unchanged exactly and a region's light moves by at most
//! that radius; a feature of the indirect light sharper than the median window (a glossy
//! highlight one or two pixels wide) is blurred by it too. Tokuyoshi & Ogaki's own
//! spike controls are biased in another way: §4.3 clamps the two-bounce connection (light
//! lost), §5 widens glossy lobes (the roughness clamp, `roughness_clamping`, kept here:
//! it changes the lobe's shape, not its albedo). Without it, one frame's largest pixel of
//! the light past the direct light reached 4–15 times `path`'s (`tests/test_bidir_transport.py`).

use glam::Vec3;

/// A pixel (or block) keeps at most this many times the median of its neighbourhood. At 3
/// (before, single pixels only) one frame's largest pixel of the light past the direct light
/// reached 3.8 times `path`'s on `cornell` (seed 8: a streak along the ceiling's edge, its
/// 5×5 median already 1.1 times `path`'s largest) and 3.2 on mitsuba.cornell_box(); at 2
/// with 2×2 blocks first, 2.6 and 2.2 over seeds 1–8 (issue 48).
pub(super) const SPIKE_FACTOR: f32 = 2.0;

/// Half side of the median's window (5×5).
const MEDIAN_RADIUS: i64 = 2;

/// Half side of the window the excess is spread over (7×7).
pub(super) const SPREAD_RADIUS: i64 = 3;

/// The threshold's floor, as a share of the image's mean luminance (dark regions next to
/// lit ones keep their light).
const FLOOR_SHARE: f32 = 0.1;

/// The textures to read back, with the lighting pass's (`indirect`) that [`spread`] needs.
pub(super) fn with_indirect(mut names: Vec<&'static str>) -> Vec<&'static str> {
    if !names.contains(&"indirect") {
        names.push("indirect");
    }
    names
}

fn lum(c: Vec3) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

/// Block sides the spikes are looked for at, in turn: blocks of 2×2 pixels (a blotch a few
/// pixels wide, from a VPL's or a subpath vertex's 1/d² over a corner, whose pixels are
/// each other's neighbours and so pass the single-pixel median test: on `cornell` seed 8
/// and mitsuba.cornell_box() seeds 5 and 6 one frame's largest pixel of the light past the
/// direct light stayed at 2.9–3.8 times `path`'s with single pixels alone; issue 48), then
/// single pixels. Blocks first: spread first, a blotch's rim would raise the medians
/// around its core.
const LEVELS: [usize; 2] = [2, 1];

/// Spreads the spikes of `img` (`width` × `height`, row-major; `covered[i]`: pixel i sees a
/// surface) in place, at each of [`LEVELS`]; returns the number of pixels or blocks that
/// gave light away.
pub(super) fn spread(img: &mut [Vec3], covered: &[bool], width: usize, height: usize) -> usize {
    LEVELS
        .iter()
        .map(|&b| spread_blocks(img, covered, width, height, b))
        .sum()
}

/// One level of [`spread`] on blocks of `b`×`b` pixels (each block's value the mean
/// luminance of its covered pixels): a block above [`SPIKE_FACTOR`] times the median of the
/// covered blocks around it (plus the floor) gives the same share of each of its covered
/// pixels' light, the whole spread evenly over the covered pixels of the window of blocks
/// around it. At `b` = 1 a pixel's own test.
fn spread_blocks(
    img: &mut [Vec3],
    covered: &[bool],
    width: usize,
    height: usize,
    b: usize,
) -> usize {
    let count = covered.iter().filter(|&&c| c).count().max(1);
    let mean = img
        .iter()
        .zip(covered)
        .filter(|(_, &c)| c)
        .map(|(p, _)| lum(*p))
        .sum::<f32>()
        / count as f32;
    let floor = FLOOR_SHARE * mean.max(0.0);
    let (bw, bh) = (width.div_ceil(b), height.div_ceil(b));
    // The covered pixels of block (bx, by).
    let pixels = |bx: usize, by: usize| {
        let (x0, y0) = (bx * b, by * b);
        (y0..(y0 + b).min(height))
            .flat_map(move |y| (x0..(x0 + b).min(width)).map(move |x| y * width + x))
            .filter(|&i| covered[i])
    };
    let value: Vec<Option<f32>> = (0..bw * bh)
        .map(|k| {
            let (n, sum) =
                pixels(k % bw, k / bw).fold((0, 0.0), |(n, s), i| (n + 1, s + lum(img[i])));
            (n > 0).then(|| sum / n as f32)
        })
        .collect();
    let window = |x: usize, y: usize, r: i64| {
        let (x, y) = (x as i64, y as i64);
        (-r..=r).flat_map(move |dy| (-r..=r).map(move |dx| (x + dx, y + dy)))
    };
    let index = |(x, y): (i64, i64)| {
        (x >= 0 && y >= 0 && (x as usize) < bw && (y as usize) < bh)
            .then(|| y as usize * bw + x as usize)
    };
    let mut delta = vec![Vec3::ZERO; img.len()];
    let mut spikes = 0;
    let mut around = Vec::with_capacity(25);
    for by in 0..bh {
        for bx in 0..bw {
            let k = by * bw + bx;
            let Some(l) = value[k] else { continue };
            if l.is_nan() || l <= floor {
                continue;
            }
            around.clear();
            around.extend(
                window(bx, by, MEDIAN_RADIUS)
                    .filter_map(index)
                    .filter(|&j| j != k)
                    .filter_map(|j| value[j]),
            );
            if around.is_empty() {
                continue;
            }
            let mid = around.len() / 2;
            let median = *around.select_nth_unstable_by(mid, f32::total_cmp).1;
            let keep = SPIKE_FACTOR * median.max(0.0) + floor;
            if l <= keep {
                continue;
            }
            let share_of = (l - keep) / l;
            let mut excess = Vec3::ZERO;
            for i in pixels(bx, by) {
                let e = img[i] * share_of;
                delta[i] -= e;
                excess += e;
            }
            let targets: Vec<usize> = window(bx, by, SPREAD_RADIUS)
                .filter_map(index)
                .flat_map(|j| pixels(j % bw, j / bw))
                .collect();
            let share = excess / targets.len() as f32;
            for j in targets {
                delta[j] += share;
            }
            spikes += 1;
        }
    }
    for (p, d) in img.iter_mut().zip(&delta) {
        *p += *d;
    }
    spikes
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth ramp keeps every pixel; an isolated spike gives its excess to its window,
    /// the sum unchanged, and ends below the bound.
    #[test]
    fn spikes_spread_and_the_sum_is_kept() {
        let (w, h) = (16, 12);
        let mut img: Vec<Vec3> = (0..w * h)
            .map(|i| Vec3::splat(0.2 + 0.01 * (i % w) as f32))
            .collect();
        let covered = vec![true; w * h];
        let smooth = img.clone();
        assert_eq!(spread(&mut img, &covered, w, h), 0);
        assert_eq!(img, smooth);
        let spike = 5 * w + 7;
        img[spike] = Vec3::new(40.0, 20.0, 10.0);
        let before: Vec3 = img.iter().sum();
        // Its block, then (if still above its pixels' median) the pixel.
        assert!((1..=2).contains(&spread(&mut img, &covered, w, h)));
        let after: Vec3 = img.iter().sum();
        assert!(((after - before).abs() / before).max_element() < 1e-5);
        assert!(lum(img[spike]) < 2.0, "{}", img[spike]);
        // The excess went to the window of 7×7 blocks of 2×2 (pixels 0..=13 of the row),
        // nowhere else.
        let far = 5 * w + 14;
        assert_eq!(img[far], smooth[far]);
        assert!(img[5 * w + 10].x > smooth[5 * w + 10].x);
        // Uncovered pixels neither give nor take.
        let mut img2 = smooth.clone();
        img2[spike] = Vec3::splat(40.0);
        let mut cov2 = covered.clone();
        cov2[spike + 1] = false;
        spread(&mut img2, &cov2, w, h);
        assert_eq!(img2[spike + 1], smooth[spike + 1]);
    }

    /// A blotch of 4×4 pixels: its 2×2 core passes the single-pixel test (more than half
    /// of each core pixel's median window lies in the blotch) and is caught at the second
    /// level; the whole ends well below its height, the sum unchanged, its light within 7
    /// pixels of the blotch.
    #[test]
    fn a_blotch_wider_than_a_pixel_is_spread_by_the_block_level() {
        let (w, h) = (24, 24);
        let smooth = vec![Vec3::splat(0.2); w * h];
        let covered = vec![true; w * h];
        let blotch: Vec<usize> = (10..14)
            .flat_map(|y| (10..14).map(move |x| y * w + x))
            .collect();
        let mut img = smooth.clone();
        for &i in &blotch {
            img[i] = Vec3::splat(8.0);
        }
        let core = 11 * w + 11;
        let mut single = img.clone();
        spread_blocks(&mut single, &covered, w, h, 1);
        // (It kept its light and took some of its rim's.)
        assert!(single[core].x >= 8.0, "{}", single[core]);
        let before: Vec3 = img.iter().sum();
        spread(&mut img, &covered, w, h);
        let after: Vec3 = img.iter().sum();
        assert!(((after - before).abs() / before).max_element() < 1e-5);
        for &i in &blotch {
            assert!(lum(img[i]) < 3.0, "{i}: {}", img[i]);
        }
        // Blocks (5..=6) ± 3 hold pixels 4..=19: pixel 4 takes light, pixel 2 none.
        assert!(img[12 * w + 4].x > 0.2);
        assert_eq!(img[12 * w + 2], smooth[12 * w + 2]);
    }
}
