//! Pearson's chi-square test of a sampler against the density it should follow, over a
//! grid of the sphere: the unit tests of the BSDFs' and the environment's sampling.

/// Standard normal upper tail via erfc (Numerical Recipes' erfcc, |error| < 1.2e-7).
fn normal_upper_tail(z: f64) -> f64 {
    let x = z / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.5 * x.abs());
    let y = t
        * (-x * x - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    let erfc = if x >= 0.0 { y } else { 2.0 - y };
    0.5 * erfc
}

/// p-value of a chi-square statistic with `k` degrees of freedom (Wilson–Hilferty).
fn chi2_p_value(chi2: f64, k: f64) -> f64 {
    let z = ((chi2 / k).powf(1.0 / 3.0) - (1.0 - 2.0 / (9.0 * k))) / (2.0 / (9.0 * k)).sqrt();
    normal_upper_tail(z)
}

/// A grid of the sphere: `rows` bands of equal height along the axis (the axis coordinate
/// in [-1, 1]), `columns` sectors of azimuth φ in [0, 2π), each cell integrated by `sub`²
/// midpoints.
pub struct Grid {
    pub rows: usize,
    pub columns: usize,
    pub sub: usize,
}

impl Grid {
    /// The expected counts of `n` samples per cell (row-major) of a density over solid angle
    /// `density(axis coordinate, φ)`.
    pub fn expected(&self, n: usize, density: impl Fn(f64, f64) -> f64) -> Vec<f64> {
        let (nz, np, sub) = (self.rows, self.columns, self.sub);
        let tau = 2.0 * std::f64::consts::PI;
        let mut expected = vec![0.0f64; nz * np];
        for iz in 0..nz {
            for ip in 0..np {
                let mut e = 0.0;
                for a in 0..sub {
                    for b in 0..sub {
                        let z =
                            -1.0 + 2.0 * (iz as f64 + (a as f64 + 0.5) / sub as f64) / nz as f64;
                        let phi = tau * (ip as f64 + (b as f64 + 0.5) / sub as f64) / np as f64;
                        e += density(z, phi);
                    }
                }
                let cell = (2.0 / nz as f64) * (tau / np as f64) / (sub * sub) as f64;
                expected[iz * np + ip] = e * cell * n as f64;
            }
        }
        expected
    }
}

/// The p-value of the counts `observed` against `expected`, cells with small expectations
/// pooled (pbrt's rule: below 5 counts).
pub fn p_value(observed: &[f64], expected: &[f64]) -> f64 {
    let (mut chi2, mut dof) = (0.0f64, 0usize);
    let (mut pool_o, mut pool_e) = (0.0f64, 0.0f64);
    for (o, e) in observed.iter().zip(expected) {
        if *e < 5.0 {
            pool_o += o;
            pool_e += e;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pool_e >= 5.0 {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof += 1;
    } else {
        assert!(
            pool_o < 20.0,
            "samples where the pdf says there are none: {pool_o}"
        );
    }
    chi2_p_value(chi2, (dof - 1) as f64)
}
