//! Interleaved sampling of the deep light subpath vertices (issue 48's cost; Keller &
//! Heidrich 2001, "Interleaved sampling"): the lighting pass (`bidir.wgsl`,
//! `interleave`) lets each vertex of order 3 and more light one pixel of every
//! [`BLOCK`]×[`BLOCK`] block, weighted [`BLOCK`]², so that a pixel evaluates a quarter of
//! them (at 2) and the pass's cost per path length past the third drops by as much. Each
//! pixel's estimate stays unbiased (the cell a vertex falls to is rotated by a uniform
//! per-frame offset), but neighbouring pixels see different vertices: [`filter`] spreads
//! each pixel's light evenly over the pixels of its block that lie at the same depth (the
//! geometry-aware filter), which gives every such pixel the block's full set of vertices.
//! A pixel's loop walks every [`BLOCK`]²-th vertex (a skipped iteration would not save
//! lavapipe's time: neighbouring pixels run together). Both sides of the image must be
//! multiples of [`BLOCK`], or nothing is interleaved (and nothing filtered).
//!
//! Bias, stated: the filter takes the whole lighting pass's image (the one-bounce light
//! too, which the pass does not interleave), so light moves by at most one pixel within a
//! block; the image's sum (its mean) is unchanged exactly. Pixels whose depths differ by
//! more than [`DEPTH_TOLERANCE`] keep their own light (a block across an object's edge then
//! keeps the interleaving's pattern there).

use glam::Vec3;

/// Side of the pixel blocks the deep vertices are interleaved over (`INTERLEAVE` of
/// `bidir.wgsl`; a unit test checks that the two agree).
pub(super) const BLOCK: usize = 2;

/// Largest relative difference of two pixels' distances from the eye for the filter to
/// share light between them: neighbours on one surface seen at a grazing 20° at 48 pixels
/// over a 40° field differ by about 4%; an object in front of a wall by far more.
const DEPTH_TOLERANCE: f32 = 0.1;

/// Spreads each covered pixel's light of `img` (`width` × `height`, row-major) evenly over
/// the covered pixels of its [`BLOCK`]² block within [`DEPTH_TOLERANCE`] of its distance
/// (`depth`, `None`: not covered), itself included. Keeps the image's sum. Nothing where a
/// side is not a multiple of [`BLOCK`] (the pass did not interleave).
pub(super) fn filter(img: &mut [Vec3], depth: &[Option<f32>], width: usize, height: usize) {
    if width % BLOCK != 0 || height % BLOCK != 0 {
        return;
    }
    let src = img.to_vec();
    for by in (0..height).step_by(BLOCK) {
        for bx in (0..width).step_by(BLOCK) {
            let cells: Vec<usize> = (by..(by + BLOCK).min(height))
                .flat_map(|y| (bx..(bx + BLOCK).min(width)).map(move |x| y * width + x))
                .collect();
            for &i in &cells {
                img[i] = Vec3::ZERO;
            }
            for &p in &cells {
                let Some(dp) = depth[p] else {
                    img[p] += src[p];
                    continue;
                };
                let near = |q: &usize| {
                    depth[*q].is_some_and(|dq| (dq - dp).abs() <= DEPTH_TOLERANCE * dp.min(dq))
                };
                let partners: Vec<usize> = cells.iter().copied().filter(near).collect();
                let share = src[p] / partners.len().max(1) as f32;
                for q in partners {
                    img[q] += share;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: usize, height: usize) -> Vec<Vec3> {
        (0..width * height)
            .map(|i| Vec3::new((i % 7) as f32, (i % 3) as f32 * 2.0, 1.0 + (i % 5) as f32))
            .collect()
    }

    #[test]
    fn keeps_the_sum_and_the_pixels_off_the_surface() {
        let (w, h) = (8, 6);
        let mut img = image(w, h);
        let before: Vec3 = img.iter().copied().sum();
        // A nearer object over the left columns, a background pixel, the rest a wall.
        let depth: Vec<Option<f32>> = (0..w * h)
            .map(|i| match (i % w, i / w) {
                (3, 2) => None,
                (x, _) if x < 3 => Some(2.0),
                _ => Some(5.0),
            })
            .collect();
        let bg = img[2 * w + 3];
        let odd = img[..35].to_vec();
        let mut img_odd = odd.clone();
        filter(&mut img_odd, &depth[..35], 7, 5);
        assert_eq!(img_odd, odd);
        filter(&mut img, &depth, w, h);
        let after: Vec3 = img.iter().copied().sum();
        assert!(
            (after - before).abs().max_element() < 1e-4,
            "{before} {after}"
        );
        assert_eq!(img[2 * w + 3], bg);
    }

    #[test]
    fn averages_a_block_on_one_surface_and_not_across_depths() {
        let mut img = vec![Vec3::splat(4.0), Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
        filter(&mut img, &[Some(1.0); 4], 2, 2);
        assert!(img
            .iter()
            .all(|p| (*p - Vec3::ONE).abs().max_element() < 1e-6));
        let mut img = vec![Vec3::splat(4.0), Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
        let depth = [Some(1.0), Some(3.0), Some(1.05), Some(3.0)];
        filter(&mut img, &depth, 2, 2);
        assert_eq!(
            img,
            vec![Vec3::splat(2.0), Vec3::ZERO, Vec3::splat(2.0), Vec3::ZERO]
        );
    }

    #[test]
    fn block_matches_the_lighting_pass() {
        let wgsl = include_str!("../../raster/shaders/bidir.wgsl");
        let line = format!("const INTERLEAVE: u32 = {BLOCK}u;");
        assert!(wgsl.contains(&line), "bidir.wgsl lacks `{line}`");
    }
}
