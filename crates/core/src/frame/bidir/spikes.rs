//! Hot-spot control of the lighting pass's image (issue 48), mean-preserving: a pixel of
//! the indirect light far above its neighbourhood (a VPL next to the surface it lights, a
//! light subpath's corner path: the 1/d² of a connection the MIS weights do not damp) keeps
//! [`SPIKE_FACTOR`] times the neighbourhood's median (plus a floor of
//! [`FLOOR_SHARE`] of the image's mean), and its excess is spread evenly over the covered
//! pixels of the (2·[`SPREAD_RADIUS`] + 1)² window around it.
//!
//! Bias, stated: the excess stays within [`SPREAD_RADIUS`] pixels of where it was drawn, so
//! the image's sum (its mean) is unchanged exactly and a region's light moves by at most
//! that radius; a feature of the indirect light sharper than the median window (a glossy
//! highlight one or two pixels wide) is blurred by it too. Tokuyoshi & Ogaki's own
//! spike controls are biased in another way: §4.3 clamps the two-bounce connection (light
//! lost), §5 widens glossy lobes (the roughness clamp, `roughness_clamping`, kept here:
//! it changes the lobe's shape, not its albedo). Without it, one frame's largest pixel of
//! the light past the direct light reached 4–15 times `path`'s (`tests/test_bidir_transport.py`).

use glam::Vec3;

/// A pixel keeps at most this many times the median of its neighbourhood.
pub(super) const SPIKE_FACTOR: f32 = 3.0;

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

/// Spreads the spikes of `img` (`width` × `height`, row-major; `covered[i]`: pixel i sees a
/// surface) in place; returns the number of pixels that gave light away.
pub(super) fn spread(img: &mut [Vec3], covered: &[bool], width: usize, height: usize) -> usize {
    let n = img.len();
    let count = covered.iter().filter(|&&c| c).count().max(1);
    let mean = img
        .iter()
        .zip(covered)
        .filter(|(_, &c)| c)
        .map(|(p, _)| lum(*p))
        .sum::<f32>()
        / count as f32;
    let floor = FLOOR_SHARE * mean.max(0.0);
    let window = |x: usize, y: usize, r: i64| {
        let (x, y) = (x as i64, y as i64);
        (-r..=r).flat_map(move |dy| (-r..=r).map(move |dx| (x + dx, y + dy)))
    };
    let index = |(x, y): (i64, i64)| {
        (x >= 0 && y >= 0 && (x as usize) < width && (y as usize) < height)
            .then(|| y as usize * width + x as usize)
    };
    let mut delta = vec![Vec3::ZERO; n];
    let mut spikes = 0;
    let mut around = Vec::with_capacity(25);
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            let l = lum(img[i]);
            if !covered[i] || l.is_nan() || l <= floor {
                continue;
            }
            around.clear();
            around.extend(
                window(x, y, MEDIAN_RADIUS)
                    .filter_map(index)
                    .filter(|&j| j != i && covered[j])
                    .map(|j| lum(img[j])),
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
            let excess = img[i] * ((l - keep) / l);
            let targets: Vec<usize> = window(x, y, SPREAD_RADIUS)
                .filter_map(index)
                .filter(|&j| covered[j])
                .collect();
            delta[i] -= excess;
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
        assert_eq!(spread(&mut img, &covered, w, h), 1);
        let after: Vec3 = img.iter().sum();
        assert!(((after - before).abs() / before).max_element() < 1e-5);
        assert!(lum(img[spike]) < 2.0, "{}", img[spike]);
        // The excess went to the 7×7 window, nowhere else.
        let far = 5 * w + 12;
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
}
