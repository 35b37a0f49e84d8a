//! Linear BVH over photon footprints (Fabianowski & Dingliana 2009, §5.2–5.3, after
//! Lauterbach et al. 2009): 30-bit Morton codes of the footprint centres, an LSD radix sort,
//! and a hierarchy that splits each interval of the sorted sequence at its highest differing
//! Morton bit, stopping at a leaf-size threshold T.
//!
//! obvhs builds excellent BVHs (PLOC), but its leaves are shaped by a SAH collapse, not by a
//! photon count on Morton intervals; the paper's leaf-size threshold and its T_auto
//! heuristic are defined on the latter, so this module builds its own hierarchy. Measured
//! against an obvhs `Bvh2` with `point_traverse` over the same footprint boxes
//! (docs/bench/photon-map.md, section 4: `cornell`, 400k photons, ~100 footprints per query
//! point, 2 threads): obvhs's SAH builds (very_fast … medium) take 3.6–6.6× as long to build
//! (175–324 ms against 49 ms) for queries 0.77–0.82× as long; its fastest_build (1 footprint
//! per leaf) is 1.6× the build and 1.17× the query time. On this loaded shared machine the
//! query ratios of other runs ranged from 0.8 to 2.5, so the gain is small and uncertain: the
//! extra build time pays back after ~1.3 (very_fast) to ~2.2 (fast) queries per pixel of a
//! 256² image, and it would give up the paper's leaf-size threshold and T_auto.

use glam::Vec3;
use rayon::prelude::*;

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    #[inline]
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    pub fn centre(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
}

/// Spreads the low 10 bits of `v` to every third bit.
fn expand_bits(mut v: u32) -> u32 {
    v &= 0x3ff;
    v = (v | (v << 16)) & 0x0300_00ff;
    v = (v | (v << 8)) & 0x0300_f00f;
    v = (v | (v << 4)) & 0x030c_30c3;
    v = (v | (v << 2)) & 0x0924_9249;
    v
}

/// 30-bit Morton code of `p` within `bounds` (10 bits per axis).
pub fn morton30(p: Vec3, bounds: &Aabb) -> u32 {
    let extent = (bounds.max - bounds.min).max(Vec3::splat(1e-20));
    let q = ((p - bounds.min) / extent * 1024.0).clamp(Vec3::ZERO, Vec3::splat(1023.0));
    (expand_bits(q.x as u32) << 2) | (expand_bits(q.y as u32) << 1) | expand_bits(q.z as u32)
}

/// LSD radix sort of (code, index) pairs by the 30-bit code: three passes of 10 bits.
pub fn radix_sort(keys: &mut Vec<(u32, u32)>) {
    let mut tmp = vec![(0u32, 0u32); keys.len()];
    for pass in 0..3 {
        let shift = pass * 10;
        let mut count = [0usize; 1025];
        for k in keys.iter() {
            count[((k.0 >> shift) & 0x3ff) as usize + 1] += 1;
        }
        for i in 0..1024 {
            count[i + 1] += count[i];
        }
        for k in keys.iter() {
            let b = ((k.0 >> shift) & 0x3ff) as usize;
            tmp[count[b]] = *k;
            count[b] += 1;
        }
        std::mem::swap(keys, &mut tmp);
    }
}

/// A node: inner nodes hold their two children, leaves a range of the sorted items.
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// Inner: index of the left child (the right one follows the left subtree). Leaf: first item.
    first: u32,
    /// Inner: index of the right child. Leaf: item count.
    second: u32,
    leaf: bool,
}

/// The linear BVH: item indices in Morton order and the node hierarchy over them.
pub struct LinearBvh {
    nodes: Vec<Node>,
    /// Item indices (into the caller's arrays) in Morton order.
    pub order: Vec<u32>,
    pub leaf_size: usize,
}

impl LinearBvh {
    /// Builds over items with the given bounds, stopping at `leaf_size` items per leaf
    /// (items sharing a Morton code always share a leaf).
    pub fn build(bounds: &[Aabb], leaf_size: usize) -> LinearBvh {
        let leaf_size = leaf_size.max(1);
        if bounds.is_empty() {
            return LinearBvh {
                nodes: Vec::new(),
                order: Vec::new(),
                leaf_size,
            };
        }
        let centres: Vec<Vec3> = bounds.par_iter().map(Aabb::centre).collect();
        let scene = centres
            .iter()
            .fold(Aabb::EMPTY, |b, c| b.union(Aabb { min: *c, max: *c }));
        let mut keys: Vec<(u32, u32)> = centres
            .par_iter()
            .enumerate()
            .map(|(i, c)| (morton30(*c, &scene), i as u32))
            .collect();
        radix_sort(&mut keys);
        let codes: Vec<u32> = keys.iter().map(|k| k.0).collect();
        let order: Vec<u32> = keys.iter().map(|k| k.1).collect();
        let mut nodes = Vec::with_capacity(2 * bounds.len() / leaf_size + 1);
        build_node(
            &codes,
            &order,
            bounds,
            0,
            codes.len(),
            leaf_size,
            &mut nodes,
        );
        LinearBvh {
            nodes,
            order,
            leaf_size,
        }
    }

    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Calls `visit(item)` for every item whose leaf box contains `p` (a superset of the
    /// items whose own boxes contain it; the caller tests those).
    #[inline]
    pub fn for_each_candidate(&self, p: Vec3, mut visit: impl FnMut(u32)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let n = &self.nodes[stack[top] as usize];
            if !n.bounds.contains(p) {
                continue;
            }
            if n.leaf {
                for &i in &self.order[n.first as usize..(n.first + n.second) as usize] {
                    visit(i);
                }
            } else if top + 2 <= stack.len() {
                stack[top] = n.second;
                stack[top + 1] = n.first;
                top += 2;
            }
        }
    }
}

/// Builds the subtree over sorted items [lo, hi) depth-first; returns its node index.
fn build_node(
    codes: &[u32],
    order: &[u32],
    bounds: &[Aabb],
    lo: usize,
    hi: usize,
    leaf_size: usize,
    nodes: &mut Vec<Node>,
) -> u32 {
    let index = nodes.len() as u32;
    let same_code = codes[lo] == codes[hi - 1];
    if hi - lo <= leaf_size || same_code {
        let b = order[lo..hi]
            .iter()
            .fold(Aabb::EMPTY, |b, &i| b.union(bounds[i as usize]));
        nodes.push(Node {
            bounds: b,
            first: lo as u32,
            second: (hi - lo) as u32,
            leaf: true,
        });
        return index;
    }
    // Split where the highest bit that differs between the interval's ends flips.
    let bit = 31 - (codes[lo] ^ codes[hi - 1]).leading_zeros();
    let prefix = codes[lo] >> bit;
    let split = lo + codes[lo..hi].partition_point(|c| (c >> bit) == prefix);
    nodes.push(Node {
        bounds: Aabb::EMPTY,
        first: 0,
        second: 0,
        leaf: false,
    });
    let left = build_node(codes, order, bounds, lo, split, leaf_size, nodes);
    let right = build_node(codes, order, bounds, split, hi, leaf_size, nodes);
    let b = nodes[left as usize]
        .bounds
        .union(nodes[right as usize].bounds);
    nodes[index as usize] = Node {
        bounds: b,
        first: left,
        second: right,
        leaf: false,
    };
    index
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn random_boxes(n: usize, seed: u64) -> Vec<Aabb> {
        let mut rng = Rng::new(seed, 0, 0);
        (0..n)
            .map(|_| {
                let c = Vec3::new(rng.next_f32(), rng.next_f32() * 0.5, rng.next_f32() * 2.0);
                let r = Vec3::splat(0.002 + 0.03 * rng.next_f32());
                Aabb {
                    min: c - r,
                    max: c + r,
                }
            })
            .collect()
    }

    #[test]
    fn radix_sort_sorts() {
        let mut rng = Rng::new(1, 0, 0);
        let mut keys: Vec<(u32, u32)> = (0..10_000)
            .map(|i| (rng.next_u32() & 0x3fff_ffff, i))
            .collect();
        let mut expected = keys.clone();
        expected.sort_by_key(|k| k.0);
        radix_sort(&mut keys);
        assert_eq!(
            keys.iter().map(|k| k.0).collect::<Vec<_>>(),
            expected.iter().map(|k| k.0).collect::<Vec<_>>()
        );
    }

    #[test]
    fn morton_orders_by_interleaved_bits() {
        let b = Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        assert_eq!(morton30(Vec3::ZERO, &b), 0);
        assert_eq!(morton30(Vec3::ONE, &b), 0x3fff_ffff);
        assert!(morton30(Vec3::new(0.6, 0.0, 0.0), &b) > morton30(Vec3::new(0.4, 0.9, 0.9), &b));
    }

    /// Every box containing a query point is among the candidates, for several leaf sizes.
    #[test]
    fn queries_find_every_containing_box() {
        let boxes = random_boxes(5000, 2);
        let mut rng = Rng::new(3, 0, 0);
        for leaf in [1, 4, 32] {
            let bvh = LinearBvh::build(&boxes, leaf);
            for _ in 0..500 {
                let p = Vec3::new(rng.next_f32(), rng.next_f32() * 0.5, rng.next_f32() * 2.0);
                let mut found: Vec<u32> = Vec::new();
                bvh.for_each_candidate(p, |i| {
                    if boxes[i as usize].contains(p) {
                        found.push(i)
                    }
                });
                found.sort_unstable();
                let brute: Vec<u32> = (0..boxes.len() as u32)
                    .filter(|&i| boxes[i as usize].contains(p))
                    .collect();
                assert_eq!(found, brute);
            }
        }
    }
}
