//! Random numbers and sample warps.
//!
//! The generator is PCG32 seeded from a hash of (seed, stream, index), so every pixel sample
//! and every light path draws from its own reproducible sequence whatever the thread schedule.

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

/// PCG32 (O'Neill), one stream per generator.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

impl Rng {
    /// A generator for sequence `index` of stream `stream` under a user `seed`.
    pub fn new(seed: u64, stream: u64, index: u64) -> Self {
        let s = splitmix64(seed ^ splitmix64(stream.wrapping_add(0x9e37_79b9_7f4a_7c15)));
        let mut rng = Rng {
            state: 0,
            inc: (splitmix64(index ^ s) << 1) | 1,
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

    /// Uniform in [0, 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        Vec2::new(self.next_f32(), self.next_f32())
    }
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

#[cfg(test)]
mod tests {
    use super::*;

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
