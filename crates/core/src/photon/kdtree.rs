//! A balanced kd-tree over points (photon positions) with k-nearest-neighbour queries.
//!
//! Layout: an implicit tree in one array. The node of a range `lo..hi` is its median
//! element `mid = (lo + hi) / 2`, split on the axis of largest extent (stored per node);
//! its subtrees are the ranges `lo..mid` and `mid + 1..hi`. Small ranges are leaves
//! scanned linearly.

use glam::Vec3;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Ranges at most this long are scanned without splitting.
const LEAF: usize = 8;
/// Ranges longer than this are built in parallel.
const PARALLEL_BUILD: usize = 1 << 14;
/// Subtrees larger than this ask whether to stop before they are built.
const STOP_CHECK: usize = 1 << 12;

/// A found neighbour: index into the points the tree was built from, squared distance (m²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour {
    pub index: u32,
    pub dist2: f32,
}

impl Eq for Neighbour {}
impl PartialOrd for Neighbour {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Neighbour {
    /// By distance, then index (a total order, so results are deterministic).
    fn cmp(&self, other: &Self) -> Ordering {
        self.dist2
            .total_cmp(&other.dist2)
            .then(self.index.cmp(&other.index))
    }
}

/// Balanced kd-tree; see the module documentation for the layout.
#[derive(Clone, Debug, Default)]
pub struct KdTree {
    /// Points in tree order.
    points: Vec<Vec3>,
    /// Original index of each point in tree order.
    indices: Vec<u32>,
    /// Split axis of the node at each position (unused in leaves).
    axes: Vec<u8>,
}

impl KdTree {
    /// Builds the tree over `points` (O(n log n), parallel near the root).
    pub fn build(points: &[Vec3]) -> Self {
        Self::build_until(points, &|| false).unwrap_or_default()
    }

    /// [`KdTree::build`] that gives up (`None`) once `stop()` holds, asked at every node
    /// of more than a few thousand points.
    pub fn build_until(points: &[Vec3], stop: &(dyn Fn() -> bool + Sync)) -> Option<Self> {
        let mut items: Vec<(Vec3, u32)> = points
            .iter()
            .enumerate()
            .map(|(i, p)| (*p, i as u32))
            .collect();
        let mut axes = vec![0u8; points.len()];
        let bounds = points
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        build_range(&mut items, &mut axes, bounds, stop);
        if stop() {
            return None;
        }
        let (points, indices) = items.into_iter().unzip();
        Some(KdTree {
            points,
            indices,
            axes,
        })
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The up to `k` nearest points to `p` within squared distance `max_dist2` for which
    /// `accept(index)` holds, closest first, written to `out` (cleared first).
    pub fn nearest(
        &self,
        p: Vec3,
        k: usize,
        max_dist2: f32,
        accept: impl Fn(u32) -> bool,
        out: &mut Vec<Neighbour>,
    ) {
        out.clear();
        if k == 0 || self.points.is_empty() {
            return;
        }
        let mut q = Query {
            p,
            k,
            r2: max_dist2,
            heap: BinaryHeap::with_capacity(k + 1),
            accept,
        };
        self.search(0, self.points.len(), &mut q);
        out.extend(q.heap.into_sorted_vec());
    }

    /// Every point within squared distance `r2` of `p` (inclusive), as (point, original
    /// index), appended to `out` in no particular order.
    pub fn within(&self, p: Vec3, r2: f32, out: &mut Vec<(Vec3, u32)>) {
        self.range(0, self.points.len(), p, r2, out);
    }

    fn range(&self, lo: usize, hi: usize, p: Vec3, r2: f32, out: &mut Vec<(Vec3, u32)>) {
        if hi - lo <= LEAF {
            for i in lo..hi {
                if self.points[i].distance_squared(p) <= r2 {
                    out.push((self.points[i], self.indices[i]));
                }
            }
            return;
        }
        let mid = (lo + hi) / 2;
        let axis = self.axes[mid] as usize;
        let delta = p[axis] - self.points[mid][axis];
        if self.points[mid].distance_squared(p) <= r2 {
            out.push((self.points[mid], self.indices[mid]));
        }
        if delta <= 0.0 || delta * delta <= r2 {
            self.range(lo, mid, p, r2, out);
        }
        if delta >= 0.0 || delta * delta <= r2 {
            self.range(mid + 1, hi, p, r2, out);
        }
    }

    fn search<F: Fn(u32) -> bool>(&self, lo: usize, hi: usize, q: &mut Query<F>) {
        if hi - lo <= LEAF {
            for i in lo..hi {
                q.offer(self.points[i], self.indices[i]);
            }
            return;
        }
        let mid = (lo + hi) / 2;
        let axis = self.axes[mid] as usize;
        let delta = q.p[axis] - self.points[mid][axis];
        let (near, far) = if delta < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search(near.0, near.1, q);
        q.offer(self.points[mid], self.indices[mid]);
        if delta * delta <= q.r2 {
            self.search(far.0, far.1, q);
        }
    }
}

/// State of one k-nearest query: a max-heap of the best candidates and the current bound.
struct Query<F> {
    p: Vec3,
    k: usize,
    /// Squared search radius: the maximum, shrunk to the k-th distance once k are found.
    r2: f32,
    heap: BinaryHeap<Neighbour>,
    accept: F,
}

impl<F: Fn(u32) -> bool> Query<F> {
    #[inline]
    fn offer(&mut self, point: Vec3, index: u32) {
        let dist2 = point.distance_squared(self.p);
        if dist2 > self.r2 || !(self.accept)(index) {
            return;
        }
        self.heap.push(Neighbour { index, dist2 });
        if self.heap.len() > self.k {
            self.heap.pop();
        }
        if self.heap.len() == self.k {
            self.r2 = self.heap.peek().map_or(self.r2, |n| n.dist2);
        }
    }
}

/// Arranges `items` as the implicit subtree of their range, recording split axes. `bounds`
/// (lower, upper corner) contains the items; each split cuts it at the median.
fn build_range(
    items: &mut [(Vec3, u32)],
    axes: &mut [u8],
    bounds: (Vec3, Vec3),
    stop: &(dyn Fn() -> bool + Sync),
) {
    if items.len() <= LEAF || (items.len() > STOP_CHECK && stop()) {
        return;
    }
    let (lo, hi) = bounds;
    let extent = hi - lo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| {
        a.0[axis].total_cmp(&b.0[axis]).then(a.1.cmp(&b.1))
    });
    axes[mid] = axis as u8;
    let split = items[mid].0[axis];
    let (mut left_hi, mut right_lo) = (hi, lo);
    left_hi[axis] = split;
    right_lo[axis] = split;
    let (left, rest) = items.split_at_mut(mid);
    let (left_axes, rest_axes) = axes.split_at_mut(mid);
    let (right, right_axes) = (&mut rest[1..], &mut rest_axes[1..]);
    if left.len() > PARALLEL_BUILD {
        rayon::join(
            || build_range(left, left_axes, (lo, left_hi), stop),
            || build_range(right, right_axes, (right_lo, hi), stop),
        );
    } else {
        build_range(left, left_axes, (lo, left_hi), stop);
        build_range(right, right_axes, (right_lo, hi), stop);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn brute(
        points: &[Vec3],
        p: Vec3,
        k: usize,
        max_dist2: f32,
        accept: impl Fn(u32) -> bool,
    ) -> Vec<Neighbour> {
        let mut all: Vec<Neighbour> = points
            .iter()
            .enumerate()
            .map(|(i, q)| Neighbour {
                index: i as u32,
                dist2: q.distance_squared(p),
            })
            .filter(|n| n.dist2 <= max_dist2 && accept(n.index))
            .collect();
        all.sort();
        all.truncate(k);
        all
    }

    /// kNN equals brute force on random points (some clustered on a plane, with duplicates),
    /// for several k, radii and an index filter.
    #[test]
    fn nearest_matches_brute_force() {
        let mut rng = Rng::new(3, 0, 0);
        let mut points: Vec<Vec3> = (0..5000)
            .map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()))
            .collect();
        points.extend((0..2000).map(|_| Vec3::new(rng.next_f32(), 0.5, rng.next_f32() * 0.1)));
        points.extend_from_within(..50);
        let tree = KdTree::build(&points);
        assert_eq!(tree.len(), points.len());
        let mut out = Vec::new();
        for qi in 0..300 {
            let p = Vec3::new(
                rng.next_f32() * 1.2 - 0.1,
                rng.next_f32() * 1.2 - 0.1,
                rng.next_f32() * 1.2 - 0.1,
            );
            for (k, r2) in [
                (1, f32::INFINITY),
                (10, 0.01),
                (100, 0.05),
                (64, f32::INFINITY),
            ] {
                let odd = qi % 2 == 0;
                let accept = |i: u32| !odd || i % 3 != 0;
                tree.nearest(p, k, r2, accept, &mut out);
                let expected = brute(&points, p, k, r2, accept);
                assert_eq!(out, expected, "query {qi}, k {k}, r² {r2}");
            }
        }
    }

    /// The range query finds exactly the points within the radius (boundary included) on
    /// random and clustered points with duplicates.
    #[test]
    fn within_matches_brute_force() {
        let mut rng = Rng::new(5, 0, 0);
        let mut points: Vec<Vec3> = (0..4000)
            .map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()))
            .collect();
        points.extend((0..2000).map(|_| Vec3::new(rng.next_f32(), 0.5, rng.next_f32() * 0.1)));
        points.extend_from_within(..50);
        let tree = KdTree::build(&points);
        let mut out = Vec::new();
        for qi in 0..200 {
            let p = if qi % 4 == 0 {
                points[qi]
            } else {
                Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32())
            };
            for r2 in [0.0, 1e-3, 0.02, 0.3] {
                out.clear();
                tree.within(p, r2, &mut out);
                let mut got: Vec<u32> = out.iter().map(|&(_, i)| i).collect();
                got.sort_unstable();
                let expected: Vec<u32> = (0..points.len() as u32)
                    .filter(|&i| points[i as usize].distance_squared(p) <= r2)
                    .collect();
                assert_eq!(got, expected, "query {qi}, r² {r2}");
            }
        }
    }

    #[test]
    fn empty_and_tiny() {
        let mut out = vec![Neighbour {
            index: 9,
            dist2: 0.0,
        }];
        KdTree::build(&[]).nearest(Vec3::ZERO, 5, 1.0, |_| true, &mut out);
        assert!(out.is_empty());
        let tree = KdTree::build(&[Vec3::X, Vec3::Y]);
        tree.nearest(Vec3::ZERO, 5, 10.0, |_| true, &mut out);
        assert_eq!(out.len(), 2);
    }
}
