//! Random numbers and sample warps.
//!
//! The generator is PCG32 seeded from a hash of (seed, stream, index), so every pixel sample
//! and every light path draws from its own reproducible sequence whatever the thread schedule.
//! A generator made by [`Rng::sobol`] instead draws its `next_f32`/`next_2d` values from a
//! padded, Owen-scrambled Sobol sequence ([`SobolSampler`]): low-discrepancy per pixel, for
//! the path tracer's camera and bounce dimensions.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// 32-bit integer hash (Wang/"lowbias32").
#[inline]
pub fn hash_u32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// Hash of three words, for seeding.
#[inline]
pub fn hash3(a: u32, b: u32, c: u32) -> u32 {
    hash_u32(a ^ hash_u32(b ^ hash_u32(c)))
}

/// PCG32 (O'Neill), one stream per generator; optionally a low-discrepancy sampler for the
/// `f32` draws ([`Rng::sobol`]).
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
    sobol: Option<SobolSampler>,
}

impl Rng {
    /// A generator for sequence `index` of stream `stream` under a user `seed`.
    pub fn new(seed: u64, stream: u64, index: u64) -> Self {
        let s = splitmix64(seed ^ splitmix64(stream.wrapping_add(0x9e37_79b9_7f4a_7c15)));
        let mut rng = Rng {
            state: 0,
            inc: (splitmix64(index ^ s) << 1) | 1,
            sobol: None,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(s);
        rng.next_u32();
        rng
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// A generator whose `next_f32` and `next_2d` draw sample `index` of pixel `pixel` from
    /// a padded Owen-scrambled Sobol sequence ([`SobolSampler`]) under `seed`; `next_u32`
    /// stays PCG32 (the generator of [`Rng::new`] for the same arguments).
    pub fn sobol(seed: u64, pixel: u64, index: u32) -> Self {
        let mut rng = Rng::new(seed, pixel, index as u64);
        rng.sobol = Some(SobolSampler::new(seed, pixel, index));
        rng
    }

    /// Moves a low-discrepancy generator to dimension `dim` (or leaves it where it is when
    /// it has already passed it, so that no dimension is drawn twice); the path tracer gives
    /// each bounce its own dimensions so that bounce `k` of every sample of a pixel draws
    /// from the same well-distributed point set. A plain PCG32 generator ignores it.
    #[inline]
    pub fn start_dimension(&mut self, dim: u32) {
        if let Some(s) = &mut self.sobol {
            s.dim = s.dim.max(dim);
        }
    }

    /// Uniform in [0, 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        if let Some(s) = &mut self.sobol {
            return s.next_1d();
        }
        u32_to_unit(self.next_u32())
    }

    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        if let Some(s) = &mut self.sobol {
            return s.next_2d();
        }
        Vec2::new(self.next_f32(), self.next_f32())
    }
}

#[inline]
fn u32_to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// A padded Owen-scrambled Sobol sampler (Burley 2020, "Practical Hash-based Owen
/// Scrambling"; pbrt-v4's `PaddedSobolSampler`): every 1D or 2D draw takes the first one or
/// two Sobol dimensions (a (0,2)-sequence) of the sample's index, the index shuffled per
/// pixel and draw by a nested uniform scramble (so that the first 2^k samples of a pixel are
/// an aligned block of the sequence, a (0,k,2)-net) and the point Owen-scrambled per pixel
/// and draw. Each draw is thus uniform and independent of the other draws of the sample,
/// while the `spp` samples of one draw are stratified: for power-of-two sample counts, every
/// elementary interval of area 1/spp holds one point.
#[derive(Clone, Debug)]
pub struct SobolSampler {
    seed: u32,
    /// The sample's index with its bits reversed (the scrambles work on reversed bits).
    index_reversed: u32,
    dim: u32,
}

impl SobolSampler {
    pub fn new(seed: u64, pixel: u64, index: u32) -> Self {
        let h = splitmix64(seed ^ splitmix64(pixel ^ 0x5851_f42d_4c95_7f2d));
        SobolSampler {
            seed: (h ^ (h >> 32)) as u32,
            index_reversed: index.reverse_bits(),
            dim: 0,
        }
    }

    /// The shuffled index and two scrambling seeds of the next draw: the index is
    /// `nested_uniform_scramble(index, h)`, written without the bit reversals that cancel
    /// (x86 has no bit-reverse instruction; each costs about a dozen operations).
    #[inline]
    fn draw(&mut self) -> (u32, u32, u32) {
        let h = hash3(self.seed, self.dim, 0x68e3_1da4);
        let index = laine_karras(self.index_reversed, h).reverse_bits();
        (index, hash_u32(h ^ 0xb529_7a4d), hash_u32(h ^ 0x1b56_c4e9))
    }

    /// Dimension 0 of the Sobol sequence is the radical inverse of the index: its
    /// Owen-scrambled value is `nested_uniform_scramble(i.reverse_bits(), s0)`, in which the
    /// two reversals of `i` cancel.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        let (i, s0, _) = self.draw();
        self.dim += 1;
        u32_to_unit(laine_karras(i, s0).reverse_bits())
    }

    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let (i, s0, s1) = self.draw();
        self.dim += 2;
        Vec2::new(
            u32_to_unit(laine_karras(i, s0).reverse_bits()),
            u32_to_unit(laine_karras(sobol_dim1_reversed(i), s1).reverse_bits()),
        )
    }
}

/// The second dimension of the Sobol sequence (primitive polynomial x + 1, all initial
/// direction numbers 1) at `index`, as a 32-bit binary fraction.
#[inline]
pub fn sobol_dim1(mut index: u32) -> u32 {
    let mut v = 1u32 << 31;
    let mut x = 0;
    while index != 0 {
        if index & 1 != 0 {
            x ^= v;
        }
        index >>= 1;
        v ^= v >> 1;
    }
    x
}

/// [`sobol_dim1`] with its bits reversed, from four byte tables: the sequence is linear over
/// GF(2) in the index's bits (bit b adds column b, reversed: c₀ = 1, c_{b+1} = c_b ⊕ c_b·2),
/// so each byte of the index adds one precomputed XOR of eight columns. No loop over the
/// index's (scrambled, so up to 32) bits, no data-dependent branch.
#[inline]
fn sobol_dim1_reversed(index: u32) -> u32 {
    let t = &SOBOL_DIM1_REVERSED;
    t[0][(index & 0xff) as usize]
        ^ t[1][((index >> 8) & 0xff) as usize]
        ^ t[2][((index >> 16) & 0xff) as usize]
        ^ t[3][(index >> 24) as usize]
}

static SOBOL_DIM1_REVERSED: [[u32; 256]; 4] = sobol_dim1_tables();

const fn sobol_dim1_tables() -> [[u32; 256]; 4] {
    let mut columns = [0u32; 32];
    let mut c = 1u32;
    let mut b = 0;
    while b < 32 {
        columns[b] = c;
        c ^= c << 1;
        b += 1;
    }
    let mut tables = [[0u32; 256]; 4];
    let mut k = 0;
    while k < 4 {
        let mut byte = 0;
        while byte < 256 {
            let mut x = 0;
            let mut j = 0;
            while j < 8 {
                if byte & (1 << j) != 0 {
                    x ^= columns[8 * k + j];
                }
                j += 1;
            }
            tables[k][byte] = x;
            byte += 1;
        }
        k += 1;
    }
    tables
}

/// Owen scrambling of a 32-bit binary fraction: each bit flipped by a hash of `seed` and
/// the bits above it (Burley 2020's hash-based nested uniform scramble: a Laine-Karras style
/// permutation, in which every bit depends only on the bits below it, of the reversed bits).
#[inline]
pub fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// The Laine-Karras permutation of [`nested_uniform_scramble`] on bit-reversed values (each
/// bit depends only on the bits below it).
#[inline(always)]
fn laine_karras(mut v: u32, seed: u32) -> u32 {
    v = v.wrapping_add(seed);
    v ^= v.wrapping_mul(0x6c50_b47c);
    v ^= v.wrapping_mul(0xb82f_1e52);
    v ^= v.wrapping_mul(0xc7af_e638);
    v ^= v.wrapping_mul(0x8d22_f6e6);
    v
}

fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Cosine-weighted direction about +z; pdf = cos(theta) / pi.
#[inline]
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u.x).max(0.0).sqrt())
}

/// Uniform direction on the unit sphere; pdf = 1 / (4 pi).
#[inline]
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction in the cone of half-angle acos(cos_max) about +z; pdf = 1 / (2 pi (1 - cos_max)).
#[inline]
pub fn uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let z = 1.0 - u.x * (1.0 - cos_max);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Orthonormal basis with `n` as its z axis (Duff et al. 2017).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub t: Vec3,
    pub b: Vec3,
    pub n: Vec3,
}

impl Frame {
    pub fn new(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Frame {
            t: Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            b: Vec3::new(b, sign + n.y * n.y * a, -n.y),
            n,
        }
    }
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }
}

/// Walker's alias table (Vose's construction): draws index `i` with probability
/// `weights[i] / Σ weights` in constant time.
#[derive(Clone, Debug, Default)]
pub struct AliasTable {
    /// Per bin: the probability of keeping the bin, and its alias.
    bins: Vec<(f32, u32)>,
    /// The normalised probability of each index.
    probs: Vec<f32>,
}

impl AliasTable {
    /// The table of `weights` (non-negative, finite); `None` when they sum to zero (or are
    /// invalid).
    pub fn new(weights: &[f32]) -> Option<AliasTable> {
        let total: f64 = weights.iter().map(|&w| w as f64).sum();
        if weights.is_empty()
            || !(total > 0.0 && total.is_finite())
            || weights.iter().any(|w| w.is_nan() || *w < 0.0)
        {
            return None;
        }
        let n = weights.len();
        let probs: Vec<f32> = weights.iter().map(|&w| (w as f64 / total) as f32).collect();
        let mut scaled: Vec<f64> = weights
            .iter()
            .map(|&w| w as f64 / total * n as f64)
            .collect();
        let mut bins = vec![(1.0f32, 0u32); n];
        let (mut small, mut large): (Vec<usize>, Vec<usize>) =
            (0..n).partition(|&i| scaled[i] < 1.0);
        while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
            bins[s] = (scaled[s] as f32, l as u32);
            scaled[l] -= 1.0 - scaled[s];
            if scaled[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // What is left keeps its bin (round-off).
        for i in small.into_iter().chain(large) {
            bins[i] = (1.0, i as u32);
        }
        Some(AliasTable { bins, probs })
    }

    /// An index drawn from `u` in [0, 1), and its probability.
    #[inline]
    pub fn sample(&self, u: f32) -> (usize, f32) {
        let n = self.bins.len();
        let x = u * n as f32;
        let i = (x as usize).min(n - 1);
        let (keep, alias) = self.bins[i];
        let j = if (x - i as f32) < keep {
            i
        } else {
            alias as usize
        };
        (j, self.probs[j])
    }

    /// The probability of index `i`.
    #[inline]
    pub fn prob(&self, i: usize) -> f32 {
        self.probs.get(i).copied().unwrap_or(0.0)
    }

    pub fn len(&self) -> usize {
        self.bins.len()
    }

    pub fn is_empty(&self) -> bool {
        self.bins.is_empty()
    }
}

/// A uniformly random point of a triangle, as barycentrics (b1, b2) of corners 1 and 2.
#[inline]
pub fn uniform_triangle(u: Vec2) -> (f32, f32) {
    // Heitz 2019, "A low-distortion map between triangle and square".
    if u.y > u.x {
        let b0 = u.x * 0.5;
        let b1 = u.y - b0;
        (b1, 1.0 - b0 - b1)
    } else {
        let b1 = u.y * 0.5;
        let b0 = u.x - b1;
        (b1, 1.0 - b0 - b1)
    }
}

#[cfg(test)]
pub(crate) mod chi_square;

#[cfg(test)]
mod tests {
    use super::*;

    /// The sampler's draws, written without the bit reversals that cancel and with the
    /// table form of Sobol dimension 1, equal the direct formulation (Burley 2020: index
    /// shuffled by a nested uniform scramble, each dimension's value Owen-scrambled) bit for
    /// bit, for full 32-bit indices as the shuffle produces.
    #[test]
    fn sobol_draws_equal_the_direct_formulation() {
        let mut r = Rng::new(3, 4, 5);
        for _ in 0..20_000 {
            let i = r.next_u32();
            assert_eq!(
                sobol_dim1_reversed(i),
                sobol_dim1(i).reverse_bits(),
                "{i:#x}"
            );
        }
        for pixel in [0u64, 7, 4095] {
            for index in [0u32, 1, 2, 63, 255, 1 << 20] {
                let mut s = SobolSampler::new(9, pixel, index);
                let seed = s.seed;
                for dim in (0..24).step_by(2) {
                    let h = hash3(seed, dim, 0x68e3_1da4);
                    let i = nested_uniform_scramble(index, h);
                    let (s0, s1) = (hash_u32(h ^ 0xb529_7a4d), hash_u32(h ^ 0x1b56_c4e9));
                    let x = u32_to_unit(nested_uniform_scramble(i.reverse_bits(), s0));
                    let y = u32_to_unit(nested_uniform_scramble(sobol_dim1(i), s1));
                    assert_eq!(s.next_2d(), Vec2::new(x, y), "pixel {pixel} index {index}");
                }
                let h = hash3(seed, 24, 0x68e3_1da4);
                let i = nested_uniform_scramble(index, h);
                let x = nested_uniform_scramble(i.reverse_bits(), hash_u32(h ^ 0xb529_7a4d));
                assert_eq!(s.next_1d(), u32_to_unit(x));
            }
        }
    }

    /// Indices are drawn with their weights' probabilities (chi-square, 9 bins, 1e5 draws,
    /// threshold 27.9 = the 99.9% quantile of χ²(8)).
    #[test]
    fn alias_table_draws_by_weight() {
        let weights = [1.0f32, 0.0, 3.0, 0.5, 2.0, 7.0, 0.25, 1.0, 4.0];
        let t = AliasTable::new(&weights).expect("table");
        let total: f32 = weights.iter().sum();
        let mut rng = Rng::new(5, 0, 0);
        let n = 100_000;
        let mut counts = [0u32; 9];
        for _ in 0..n {
            let (i, p) = t.sample(rng.next_f32());
            assert!((p - weights[i] / total).abs() < 1e-6);
            counts[i] += 1;
        }
        assert_eq!(counts[1], 0);
        let chi2: f64 = weights
            .iter()
            .zip(counts)
            .filter(|(w, _)| **w > 0.0)
            .map(|(w, c)| {
                let e = n as f64 * (*w / total) as f64;
                (c as f64 - e).powi(2) / e
            })
            .sum();
        assert!(chi2 < 27.9, "{chi2} {counts:?}");
        assert!(AliasTable::new(&[0.0, 0.0]).is_none());
        assert!(AliasTable::new(&[1.0, f32::NAN]).is_none());
    }

    /// Triangle samples are uniform: the mean of the barycentrics is (1/3, 1/3) and they
    /// stay inside.
    #[test]
    fn triangle_samples_are_uniform() {
        let mut rng = Rng::new(6, 0, 0);
        let n = 200_000;
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let (b1, b2) = uniform_triangle(rng.next_2d());
            assert!(b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 + 1e-6);
            s1 += b1 as f64;
            s2 += b2 as f64;
        }
        // Standard error of a barycentric's mean: sqrt(1/18 / n) ≈ 5e-4.
        assert!((s1 / n as f64 - 1.0 / 3.0).abs() < 3e-3);
        assert!((s2 / n as f64 - 1.0 / 3.0).abs() < 3e-3);
    }

    #[test]
    fn rng_is_uniform_and_reproducible() {
        let mut a = Rng::new(1, 2, 3);
        let mut b = Rng::new(1, 2, 3);
        let mut c = Rng::new(1, 2, 4);
        let n = 100_000;
        let mut mean = 0.0f64;
        let mut same_as_c = 0;
        for _ in 0..n {
            let x = a.next_f32();
            assert_eq!(x, b.next_f32());
            assert!((0.0..1.0).contains(&x));
            if x == c.next_f32() {
                same_as_c += 1;
            }
            mean += x as f64;
        }
        // Mean of U(0,1): sigma = 1/sqrt(12 n) ~ 0.0009; allow 5 sigma.
        assert!((mean / n as f64 - 0.5).abs() < 0.0046);
        assert!(same_as_c < 10);
    }

    #[test]
    fn frame_is_orthonormal() {
        let mut rng = Rng::new(7, 0, 0);
        for _ in 0..1000 {
            let n = uniform_sphere(rng.next_2d());
            let f = Frame::new(n);
            assert!((f.t.length() - 1.0).abs() < 1e-4 && (f.b.length() - 1.0).abs() < 1e-4);
            assert!(
                f.t.dot(f.b).abs() < 1e-4 && f.t.dot(n).abs() < 1e-4 && f.b.dot(n).abs() < 1e-4
            );
            let v = uniform_sphere(rng.next_2d());
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-4);
        }
    }
}
