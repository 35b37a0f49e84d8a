//! The low-discrepancy sampler of the path tracer (`Rng::sobol`): its draws are (0,k,2)-nets
//! per pixel and draw, uniform and independent of each other.

use gi_core::sampling::Rng;
use glam::Vec2;

/// Every elementary interval of area 1/2^k (2^a × 2^(k-a) cells) holds exactly one of
/// the first 2^k points of a pixel's 2D draw: the shuffled, scrambled sequence is a
/// (0,k,2)-net for every draw, pixel and power-of-two sample count.
#[test]
fn sobol_draws_are_nets() {
    for k in [2u32, 4, 6, 8] {
        let n = 1u32 << k;
        for (pixel, draws) in [(0u64, 1usize), (17, 3), (123_456, 6)] {
            let points: Vec<Vec<Vec2>> = (0..n)
                .map(|i| {
                    let mut rng = Rng::sobol(5, pixel, i);
                    (0..draws).map(|_| rng.next_2d()).collect()
                })
                .collect();
            for d in 0..draws {
                for a in 0..=k {
                    let (nx, ny) = (1u32 << a, 1u32 << (k - a));
                    let mut cells = vec![0u32; n as usize];
                    for p in &points {
                        let (x, y) = ((p[d].x * nx as f32) as u32, (p[d].y * ny as f32) as u32);
                        cells[(y * nx + x) as usize] += 1;
                    }
                    assert!(
                        cells.iter().all(|&c| c == 1),
                        "2^{k} points, pixel {pixel}, draw {d}, {nx}×{ny} cells: {cells:?}"
                    );
                }
            }
            // 1D draws: one point per interval of 1/2^k.
            let mut cells = vec![0u32; n as usize];
            for i in 0..n {
                let mut rng = Rng::sobol(5, pixel, i);
                rng.start_dimension(7);
                cells[(rng.next_f32() * n as f32) as usize] += 1;
            }
            assert!(cells.iter().all(|&c| c == 1), "1D, 2^{k}: {cells:?}");
        }
    }
}

/// Draws of one sample are independent of each other (products of different draws
/// average 1/4, as for independent uniforms) and uniform over pixels; different pixels
/// and seeds get different points.
#[test]
fn sobol_draws_are_uniform_and_independent() {
    let (mut m, mut xy, mut x1x2, mut xz) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut n = 0.0f64;
    for pixel in 0..4096u64 {
        for i in 0..16u32 {
            let mut rng = Rng::sobol(9, pixel, i);
            let a = rng.next_2d();
            let b = rng.next_f32();
            let c = rng.next_2d();
            m += (a.x + a.y + b + c.x + c.y) as f64 / 5.0;
            xy += (a.x * a.y) as f64;
            x1x2 += (a.x * c.x) as f64;
            xz += (a.y * b) as f64;
            n += 1.0;
        }
    }
    // 65536 samples: sigma of a mean of U(0,1) is 0.0011, of a product of two 0.0009.
    assert!((m / n - 0.5).abs() < 0.004, "mean {}", m / n);
    for (what, v) in [("x·y", xy), ("draw 1 · draw 3", x1x2), ("y · 1D", xz)] {
        assert!((v / n - 0.25).abs() < 0.005, "{what}: {}", v / n);
    }
    let first = |seed, pixel| Rng::sobol(seed, pixel, 0).next_2d();
    assert_ne!(first(1, 0), first(1, 1));
    assert_ne!(first(1, 0), first(2, 0));
    // next_u32 stays the PCG32 stream of Rng::new.
    assert_eq!(Rng::sobol(3, 4, 5).next_u32(), Rng::new(3, 4, 5).next_u32());
}
