//! A bounding volume hierarchy over the emitting triangles that picks one for a shading
//! point by its importance there: power, distance and orientation (Conty Estevez & Kulla
//! 2018, "Importance sampling of many lights with adaptive tree splitting"; as pbrt-v4's
//! `BVHLightSampler`). Each node bounds its lights' positions (a box), their total power,
//! and their normals (a cone of half-angle θo around an axis, with the emission's own
//! spread θe = π/2 for a Lambertian emitter). From the root down, a child is chosen with
//! probability proportional to its importance, a conservative bound of what it can
//! contribute at the point: Φ·cos θ′/d², θ′ the smallest angle between the cone and the
//! direction to the point, times the largest cosine at the receiving surface. The
//! probability of a light is the product of the choices on its way, recomputed by
//! [`LightBvh::prob`] from its path (a bit trail) for multiple importance sampling.

use glam::Vec3;
use std::f32::consts::PI;

/// Bounds of a set of emitters: where they are, how much they emit and which way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    pub lo: Vec3,
    pub hi: Vec3,
    /// Total power (the sum of channels, W).
    pub phi: f32,
    /// Axis of the cone of normals (unit).
    pub axis: Vec3,
    /// Cosine of the cone's half-angle θo (-1: every direction).
    pub cos_o: f32,
    /// Cosine of the angle θe beyond the normals that light leaves at (0 for Lambertian
    /// emitters: π/2).
    pub cos_e: f32,
    /// Whether any emitter emits from both faces.
    pub two_sided: bool,
}

/// `cos(a − b)` clamped to 1 where a < b (angles given by sine and cosine).
#[inline]
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        1.0
    } else {
        cos_a * cos_b + sin_a * sin_b
    }
}

/// `sin(a − b)` clamped to 0 where a < b.
#[inline]
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        0.0
    } else {
        sin_a * cos_b - cos_a * sin_b
    }
}

#[inline]
fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// The smallest cone (axis, cos θ) holding the cones `a` and `b` (pbrt-v4's
/// `DirectionCone::Union`).
fn cone_union(a: (Vec3, f32), b: (Vec3, f32)) -> (Vec3, f32) {
    let theta_a = a.1.clamp(-1.0, 1.0).acos();
    let theta_b = b.1.clamp(-1.0, 1.0).acos();
    let theta_d = a.0.dot(b.0).clamp(-1.0, 1.0).acos();
    if (theta_d + theta_b).min(PI) <= theta_a {
        return a;
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return b;
    }
    let theta_o = 0.5 * (theta_a + theta_d + theta_b);
    if theta_o >= PI {
        return (a.0, -1.0);
    }
    let theta_r = theta_o - theta_a;
    let wr = a.0.cross(b.0);
    if wr.length_squared() < 1e-12 {
        return (a.0, -1.0);
    }
    let axis = glam::Quat::from_axis_angle(wr.normalize(), theta_r) * a.0;
    (axis.normalize(), theta_o.cos())
}

impl LightBounds {
    /// The bounds of one triangle of corners `p` emitting `phi` watts (sum of channels)
    /// from the side its normal `n` faces, or both.
    pub fn triangle(p: [Vec3; 3], n: Vec3, phi: f32, two_sided: bool) -> Self {
        LightBounds {
            lo: p[0].min(p[1]).min(p[2]),
            hi: p[0].max(p[1]).max(p[2]),
            phi,
            axis: n,
            cos_o: 1.0,
            cos_e: 0.0,
            two_sided,
        }
    }

    pub fn union(&self, o: &LightBounds) -> LightBounds {
        if self.phi <= 0.0 {
            return *o;
        }
        if o.phi <= 0.0 {
            return *self;
        }
        let (axis, cos_o) = cone_union((self.axis, self.cos_o), (o.axis, o.cos_o));
        LightBounds {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
            phi: self.phi + o.phi,
            axis,
            cos_o,
            cos_e: self.cos_e.min(o.cos_e),
            two_sided: self.two_sided || o.two_sided,
        }
    }

    fn centre(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }

    /// A conservative bound of the light these emitters send to point `p` of a surface of
    /// normal `n` (zero: none; `n` zero for a point in space), up to a common factor.
    pub fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        if self.phi <= 0.0 {
            return 0.0;
        }
        let pc = self.centre();
        let diag = self.hi - self.lo;
        // Clamped below so that points inside the box do not blow up (pbrt's choice).
        let d2 = p.distance_squared(pc).max(0.5 * diag.length());
        let wi = (p - pc).normalize_or_zero();
        let mut cos_w = self.axis.dot(wi);
        if self.two_sided {
            cos_w = cos_w.abs();
        }
        let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
        // The angle the box subtends from p (its bounding sphere's).
        let radius2 = 0.25 * diag.length_squared();
        let dist2 = p.distance_squared(pc);
        let cos_b = if dist2 < radius2 || wi == Vec3::ZERO {
            -1.0
        } else {
            safe_sqrt(1.0 - radius2 / dist2)
        };
        let sin_b = safe_sqrt(1.0 - cos_b * cos_b);
        // θ′ = max(0, θw − θo − θb).
        let sin_o = safe_sqrt(1.0 - self.cos_o * self.cos_o);
        let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, self.cos_o);
        let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, self.cos_o);
        let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
        if cos_p <= self.cos_e {
            return 0.0;
        }
        let mut importance = self.phi * cos_p / d2;
        if n != Vec3::ZERO {
            let cos_i = wi.dot(n).abs();
            let sin_i = safe_sqrt(1.0 - cos_i * cos_i);
            importance *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
        }
        if importance.is_finite() {
            importance.max(0.0)
        } else {
            0.0
        }
    }

    /// The cost of a node of these bounds inside a parent box of extent `diag`, split along
    /// `axis` (pbrt-v4's `EvaluateCost`: power × orientation measure × surface area, with a
    /// penalty for thin boxes).
    fn cost(&self, diag: Vec3, axis: usize) -> f32 {
        let theta_o = self.cos_o.clamp(-1.0, 1.0).acos();
        let theta_e = self.cos_e.clamp(-1.0, 1.0).acos();
        let theta_w = (theta_o + theta_e).min(PI);
        let sin_o = safe_sqrt(1.0 - self.cos_o * self.cos_o);
        let m_omega = 2.0 * PI * (1.0 - self.cos_o)
            + PI / 2.0
                * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                    + self.cos_o);
        let kr = if diag[axis] > 0.0 {
            diag.max_element() / diag[axis]
        } else {
            1.0
        };
        let e = self.hi - self.lo;
        let area = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
        self.phi * m_omega * kr * area.max(1e-20)
    }
}

/// A node: its bounds and either two children (the first at `index + 1`, the second at
/// `second`) or one light.
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: LightBounds,
    /// Interior: the second child's index; leaf: the light's index.
    child_or_light: u32,
    leaf: bool,
}

/// The light BVH: nodes in depth-first order, and per light its path from the root.
#[derive(Clone, Debug)]
pub struct LightBvh {
    nodes: Vec<Node>,
    /// Per light: the bits of its path (bit i: the second child at depth i) and its depth.
    trails: Vec<(u64, u8)>,
}

/// Split candidates per axis.
const BUCKETS: usize = 12;
/// Depth from which nodes are split at the median (the trail holds 64 levels).
const MEDIAN_DEPTH: u32 = 40;

impl LightBvh {
    /// The hierarchy over `lights` (index = light index); lights without power are left out.
    /// `None` when none has power.
    pub fn build(lights: &[LightBounds]) -> Option<LightBvh> {
        let mut items: Vec<u32> = (0..lights.len() as u32)
            .filter(|&i| {
                let b = &lights[i as usize];
                b.phi > 0.0 && b.phi.is_finite() && b.lo.is_finite() && b.hi.is_finite()
            })
            .collect();
        if items.is_empty() {
            return None;
        }
        let mut bvh = LightBvh {
            nodes: Vec::with_capacity(2 * items.len()),
            trails: vec![(0, u8::MAX); lights.len()],
        };
        bvh.build_node(lights, &mut items, 0, 0);
        Some(bvh)
    }

    /// Appends the subtree over `items` (reached by `trail` at `depth`); returns its bounds.
    fn build_node(
        &mut self,
        lights: &[LightBounds],
        items: &mut [u32],
        trail: u64,
        depth: u32,
    ) -> LightBounds {
        let at = self.nodes.len();
        if items.len() == 1 {
            let b = lights[items[0] as usize];
            self.nodes.push(Node {
                bounds: b,
                child_or_light: items[0],
                leaf: true,
            });
            self.trails[items[0] as usize] = (trail, depth as u8);
            return b;
        }
        let mid = split(lights, items, depth);
        // Placeholder, filled once the children are built.
        self.nodes.push(Node {
            bounds: lights[items[0] as usize],
            child_or_light: 0,
            leaf: false,
        });
        let (left, right) = items.split_at_mut(mid);
        let a = self.build_node(lights, left, trail, depth + 1);
        let second = self.nodes.len() as u32;
        let b = self.build_node(lights, right, trail | (1u64 << depth), depth + 1);
        let bounds = a.union(&b);
        self.nodes[at] = Node {
            bounds,
            child_or_light: second,
            leaf: false,
        };
        bounds
    }

    /// Lights in the hierarchy.
    pub fn len(&self) -> usize {
        self.trails.iter().filter(|t| t.1 != u8::MAX).count()
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The nodes in depth-first order, each as its bounds, whether it is a leaf, and its
    /// light (leaf) or its second child's index (interior; the first child follows it): for
    /// a copy of the hierarchy on the GPU.
    pub fn nodes(&self) -> impl Iterator<Item = (LightBounds, bool, u32)> + '_ {
        self.nodes
            .iter()
            .map(|n| (n.bounds, n.leaf, n.child_or_light))
    }

    /// A light chosen for point `p` (surface normal `n`, or zero) from `u` in [0, 1), and its
    /// probability; `None` when no light can reach the point.
    pub fn sample(&self, p: Vec3, n: Vec3, mut u: f32) -> Option<(usize, f32)> {
        let mut i = 0usize;
        let mut prob = 1.0f32;
        loop {
            let node = &self.nodes[i];
            if node.leaf {
                if node.bounds.importance(p, n) > 0.0 {
                    return Some((node.child_or_light as usize, prob));
                }
                return None;
            }
            let (a, b) = (i + 1, node.child_or_light as usize);
            let ia = self.nodes[a].bounds.importance(p, n);
            let ib = self.nodes[b].bounds.importance(p, n);
            let total = ia + ib;
            if total.is_nan() || total <= 0.0 {
                return None;
            }
            let pa = ia / total;
            if u < pa {
                u = (u / pa).min(1.0 - f32::EPSILON);
                prob *= pa;
                i = a;
            } else {
                u = ((u - pa) / (1.0 - pa)).clamp(0.0, 1.0 - f32::EPSILON);
                prob *= 1.0 - pa;
                i = b;
            }
        }
    }

    /// The probability that [`LightBvh::sample`] picks `light` for `p`, `n`.
    pub fn prob(&self, p: Vec3, n: Vec3, light: usize) -> f32 {
        let Some(&(trail, depth)) = self.trails.get(light) else {
            return 0.0;
        };
        if depth == u8::MAX {
            return 0.0;
        }
        let mut i = 0usize;
        let mut prob = 1.0f32;
        for level in 0..depth as u32 {
            let node = &self.nodes[i];
            let (a, b) = (i + 1, node.child_or_light as usize);
            let ia = self.nodes[a].bounds.importance(p, n);
            let ib = self.nodes[b].bounds.importance(p, n);
            let total = ia + ib;
            if total.is_nan() || total <= 0.0 {
                return 0.0;
            }
            if trail >> level & 1 == 0 {
                prob *= ia / total;
                i = a;
            } else {
                prob *= ib / total;
                i = b;
            }
        }
        if self.nodes[i].bounds.importance(p, n) > 0.0 {
            prob
        } else {
            0.0
        }
    }
}

/// Reorders `items` and returns where to split them: the cheapest of the bucket boundaries
/// along each axis by [`LightBounds::cost`], else (flat distributions, deep nodes) the
/// median along the widest axis of the centres.
fn split(lights: &[LightBounds], items: &mut [u32], depth: u32) -> usize {
    let centre = |i: &u32| lights[*i as usize].centre();
    let (clo, chi) = items
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), i| {
            (lo.min(centre(i)), hi.max(centre(i)))
        });
    let all = items
        .iter()
        .skip(1)
        .fold(lights[items[0] as usize], |b, i| {
            b.union(&lights[*i as usize])
        });
    let diag = all.hi - all.lo;
    let mut best: Option<(f32, usize, f32)> = None;
    if depth < MEDIAN_DEPTH {
        for axis in 0..3 {
            let (lo, hi) = (clo[axis], chi[axis]);
            if hi.is_nan() || lo.is_nan() || hi <= lo {
                continue;
            }
            let bucket =
                |c: f32| (((c - lo) / (hi - lo) * BUCKETS as f32) as usize).min(BUCKETS - 1);
            let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
            for i in items.iter() {
                let b = &lights[*i as usize];
                let k = bucket(b.centre()[axis]);
                buckets[k] = Some(buckets[k].map_or(*b, |x| x.union(b)));
            }
            for cut in 1..BUCKETS {
                let union = |r: &[Option<LightBounds>]| {
                    r.iter().flatten().fold(None::<LightBounds>, |acc, b| {
                        Some(acc.map_or(*b, |a| a.union(b)))
                    })
                };
                let (Some(a), Some(b)) = (union(&buckets[..cut]), union(&buckets[cut..])) else {
                    continue;
                };
                let cost = a.cost(diag, axis) + b.cost(diag, axis);
                if best.is_none_or(|(c, ..)| cost < c) {
                    let at = lo + (hi - lo) * cut as f32 / BUCKETS as f32;
                    best = Some((cost, axis, at));
                }
            }
        }
    }
    if let Some((_, axis, at)) = best {
        let mid = partition(items, |i| centre(i)[axis] < at);
        if mid > 0 && mid < items.len() {
            return mid;
        }
    }
    let axis = (chi - clo).max_position();
    items.sort_unstable_by(|a, b| centre(a)[axis].total_cmp(&centre(b)[axis]));
    items.len() / 2
}

/// Moves the items satisfying `pred` to the front; returns how many there are.
fn partition(items: &mut [u32], pred: impl Fn(&u32) -> bool) -> usize {
    let mut k = 0;
    for j in 0..items.len() {
        if pred(&items[j]) {
            items.swap(k, j);
            k += 1;
        }
    }
    k
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn lights(n: usize) -> Vec<LightBounds> {
        let mut rng = Rng::new(3, 0, 0);
        (0..n)
            .map(|_| {
                let c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 10.0;
                let n = crate::sampling::uniform_sphere(rng.next_2d());
                let f = crate::sampling::Frame::new(n);
                let p = [c, c + 0.1 * f.t, c + 0.1 * f.b];
                LightBounds::triangle(p, n, 0.1 + 10.0 * rng.next_f32(), rng.next_f32() < 0.3)
            })
            .collect()
    }

    /// `prob` agrees with `sample`, and the draws follow the probabilities (a chi-square
    /// test over the lights, 200k draws at a point inside the cloud). The probabilities add
    /// up to at most 1: a descent may end at a light facing away from the point (its bound
    /// is zero, as its light there), and then picks none.
    #[test]
    fn samples_match_their_probabilities() {
        let ls = lights(300);
        let bvh = LightBvh::build(&ls).unwrap();
        assert_eq!(bvh.len(), 300);
        let (p, n) = (Vec3::new(5.0, 5.0, 5.0), Vec3::new(0.0, 1.0, 0.0));
        let probs: Vec<f64> = (0..ls.len()).map(|i| bvh.prob(p, n, i) as f64).collect();
        let total: f64 = probs.iter().sum();
        assert!(total <= 1.0 + 1e-4 && total > 0.9, "{total}");
        let draws = 200_000;
        let mut counts = vec![0u32; ls.len()];
        let mut none = 0u32;
        let mut rng = Rng::new(5, 1, 0);
        for _ in 0..draws {
            let Some((i, pr)) = bvh.sample(p, n, rng.next_f32()) else {
                none += 1;
                continue;
            };
            assert!(
                (pr as f64 - probs[i]).abs() < 1e-4 * probs[i].max(1e-3),
                "{pr} {}",
                probs[i]
            );
            counts[i] += 1;
        }
        // Chi-square over the lights expected at least 5 times; the others pooled with the
        // draws that picked none.
        let (mut chi2, mut dof) = (0.0, 0);
        let (mut pool_e, mut pool_o) = ((1.0 - total).max(0.0) * draws as f64, none as f64);
        for (c, pr) in counts.iter().zip(&probs) {
            let e = pr * draws as f64;
            if e >= 5.0 {
                chi2 += (*c as f64 - e).powi(2) / e;
                dof += 1;
            } else {
                pool_e += e;
                pool_o += *c as f64;
            }
        }
        if pool_e > 0.0 {
            chi2 += (pool_o - pool_e).powi(2) / pool_e;
            dof += 1;
        }
        // The 99.9% quantile of chi-square with k − 1 degrees of freedom is below
        // k + 5·√k for k in the hundreds.
        let k = (dof - 1) as f64;
        assert!(chi2 < k + 5.0 * k.sqrt(), "chi2 {chi2} with {k} dof");
    }

    /// A light facing away from a point (one-sided) is never picked for it, and the nearer of
    /// two equal lights is picked more often.
    #[test]
    fn importance_follows_distance_and_orientation() {
        let tri = |c: Vec3, n: Vec3| {
            let f = crate::sampling::Frame::new(n);
            LightBounds::triangle([c, c + 0.1 * f.t, c + 0.1 * f.b], n, 1.0, false)
        };
        let down = Vec3::new(0.0, -1.0, 0.0);
        let ls = vec![
            tri(Vec3::new(0.0, 1.0, 0.0), down),
            tri(Vec3::new(0.0, 4.0, 0.0), down),
            tri(Vec3::new(0.0, 2.0, 0.0), -down),
        ];
        let bvh = LightBvh::build(&ls).unwrap();
        let p = Vec3::ZERO;
        let n = Vec3::Y;
        assert_eq!(bvh.prob(p, n, 2), 0.0, "faces away");
        assert!(bvh.prob(p, n, 0) > 4.0 * bvh.prob(p, n, 1));
    }

    /// 100k lights build in bounded depth (every trail fits).
    #[test]
    fn large_hierarchies_stay_within_the_trail() {
        let ls = lights(100_000);
        let bvh = LightBvh::build(&ls).unwrap();
        let deepest = bvh.trails.iter().map(|t| t.1).max().unwrap();
        assert!(deepest < 64, "{deepest}");
        assert_eq!(bvh.nodes.len(), 2 * ls.len() - 1);
    }
}
