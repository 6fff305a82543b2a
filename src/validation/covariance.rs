//! The uncertainty of one patch's XYZ as a full 3×3 covariance: estimated from repeated
//! readings (their X, Y and Z scatter together: a meter's repeats mostly move luminance
//! and chromaticity, not one axis at a time), or, for a single reading, the instrument's
//! stated repeatability in Y and in x, y carried to X, Y, Z to first order.

use nalgebra::{Matrix3, SymmetricEigen};

/// A covariance of X, Y and Z, row-major.
pub type Cov3 = [[f64; 3]; 3];

/// No uncertainty.
pub const ZERO: Cov3 = [[0.0; 3]; 3];

/// The mean of `readings` and their sample covariance (divisor k − 1; zero for fewer than
/// two readings).
pub fn sample(readings: &[[f64; 3]]) -> ([f64; 3], Cov3) {
    let k = readings.len();
    let mut mean = [0.0; 3];
    for r in readings {
        for (m, v) in mean.iter_mut().zip(r) {
            *m += v / k.max(1) as f64;
        }
    }
    let mut c = ZERO;
    if k > 1 {
        for r in readings {
            let d = [0, 1, 2].map(|i| r[i] - mean[i]);
            for (i, row) in c.iter_mut().enumerate() {
                for (j, v) in row.iter_mut().enumerate() {
                    *v += d[i] * d[j] / (k - 1) as f64;
                }
            }
        }
    }
    (mean, c)
}

/// The standard deviations (square roots of the diagonal).
pub fn sd(c: &Cov3) -> [f64; 3] {
    [0, 1, 2].map(|i| c[i][i].max(0.0).sqrt())
}

/// The covariances XY, XZ, YZ.
pub fn off_diagonal(c: &Cov3) -> [f64; 3] {
    [c[0][1], c[0][2], c[1][2]]
}

/// The covariance of standard deviations `sd` and covariances XY, XZ, YZ `off`.
pub fn from_parts(sd: [f64; 3], off: [f64; 3]) -> Cov3 {
    let [xy, xz, yz] = off;
    [
        [sd[0] * sd[0], xy, xz],
        [xy, sd[1] * sd[1], yz],
        [xz, yz, sd[2] * sd[2]],
    ]
}

/// `c` times `s`.
pub fn scaled(c: &Cov3, s: f64) -> Cov3 {
    c.map(|row| row.map(|v| v * s))
}

/// The sum of two covariances.
pub fn sum(a: &Cov3, b: &Cov3) -> Cov3 {
    let mut c = *a;
    for (i, row) in c.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v += b[i][j];
        }
    }
    c
}

fn eigen(c: &Cov3) -> SymmetricEigen<f64, nalgebra::U3> {
    let m = Matrix3::from_fn(|i, j| 0.5 * (c[i][j] + c[j][i]));
    m.symmetric_eigen()
}

/// The eigenvalues of `c` and its eigenvectors (as columns: `vectors[i][k]` is component i
/// of vector k).
pub fn eigen_decomposition(c: &Cov3) -> ([f64; 3], [[f64; 3]; 3]) {
    let e = eigen(c);
    (
        [0, 1, 2].map(|k| e.eigenvalues[k]),
        [0, 1, 2].map(|i| [0, 1, 2].map(|k| e.eigenvectors[(i, k)])),
    )
}

/// Why `c` is not a covariance, if it is not: every entry finite, symmetric, and no
/// direction of negative variance beyond rounding (a millionth of the largest variance, so
/// a covariance written to a file with a few digits still reads).
pub fn check(c: &Cov3) -> Result<(), String> {
    if c.iter().flatten().any(|v| !v.is_finite()) {
        return Err("a covariance must be finite".into());
    }
    let scale = (0..3).map(|i| c[i][i].abs()).fold(0.0, f64::max);
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        if (c[i][j] - c[j][i]).abs() > 1e-9 * scale.max(f64::MIN_POSITIVE) {
            return Err("a covariance must be symmetric".into());
        }
    }
    let least = eigen(c).eigenvalues.min();
    if least < -1e-6 * scale {
        return Err(format!(
            "not a covariance: some combination of X, Y, Z would have the negative variance {least:.3e} (a covariance exceeds the product of its two standard deviations)"
        ));
    }
    Ok(())
}

/// Vectors f with Σ f fᵀ = `c`: its eigenvectors scaled by the square roots of their
/// eigenvalues (a rounding's small negative eigenvalue counts as 0). Moving XYZ by Σ zₖ fₖ
/// with independent standard normals zₖ gives exactly this covariance.
pub fn factors(c: &Cov3) -> Vec<[f64; 3]> {
    let e = eigen(c);
    (0..3)
        .filter(|&k| e.eigenvalues[k] > 0.0)
        .map(|k| {
            let s = e.eigenvalues[k].sqrt();
            let v = e.eigenvectors.column(k);
            [v[0] * s, v[1] * s, v[2] * s]
        })
        .collect()
}

/// The covariance Σ f fᵀ of factors.
pub fn of_factors(factors: &[[f64; 3]]) -> Cov3 {
    let mut c = ZERO;
    for f in factors {
        for (i, row) in c.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v += f[i] * f[j];
            }
        }
    }
    c
}

/// An instrument's stated repeatability of one emissive reading (1σ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Repeatability {
    /// Of Y, relative.
    pub y_rel: f64,
    /// Of x and of y, absolute (taken as independent).
    pub xy: f64,
}

impl Repeatability {
    /// What the instrument named `model` states, for the instruments this program drives:
    /// the CS-100A ±0.2 % in Y and ±0.001 in x, y (Konica Minolta's data sheet, taken as
    /// 2σ); the i1Pro emissive 0.1 % in Y (the unit's declared figure) and, as no x, y
    /// figure is stated for it here, the CS-100A's. None for any other name.
    pub fn of(model: &str) -> Option<Repeatability> {
        let m = model.trim().to_ascii_lowercase();
        if m.contains("cs100a") || m.contains("cs-100a") || m.contains("i1pro") {
            Some(Repeatability {
                y_rel: 0.001,
                xy: 0.0005,
            })
        } else {
            None
        }
    }

    /// The covariance of X, Y, Z of one reading of `xyz`: with X = xY/y and
    /// Z = (1 − x − y)Y/y, J·diag(σx², σy², σY²)·Jᵀ with J the derivatives of (X, Y, Z) by
    /// (x, y, Y). None without a chromaticity (X + Y + Z ≤ 0).
    pub fn covariance(&self, xyz: [f64; 3]) -> Option<Cov3> {
        let s = xyz[0] + xyz[1] + xyz[2];
        if !(s > 0.0 && xyz[1] > 0.0) {
            return None;
        }
        let (x, y, big_y) = (xyz[0] / s, xyz[1] / s, xyz[1]);
        // Columns: ∂/∂x, ∂/∂y, ∂/∂Y.
        let j = [
            [big_y / y, -x * big_y / (y * y), x / y],
            [0.0, 0.0, 1.0],
            [-big_y / y, -(1.0 - x) * big_y / (y * y), (1.0 - x - y) / y],
        ];
        let var = [
            self.xy * self.xy,
            self.xy * self.xy,
            (self.y_rel * big_y).powi(2),
        ];
        let mut c = ZERO;
        for (a, row) in c.iter_mut().enumerate() {
            for (b, v) in row.iter_mut().enumerate() {
                *v = (0..3).map(|k| j[a][k] * var[k] * j[b][k]).sum();
            }
        }
        Some(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sample_covariance_by_hand() {
        // X: 1, 2, 3; Y: 2, 4, 6 (= 2X); Z: 0, 0, 3. Means 2, 4, 1. Deviations
        // X −1, 0, 1; Y −2, 0, 2; Z −1, −1, 2: var X 1, var Y 4, cov XY 2, var Z 3,
        // cov XZ (1 + 0 + 2)/2 = 1.5, cov YZ 3.
        let (m, c) = sample(&[[1.0, 2.0, 0.0], [2.0, 4.0, 0.0], [3.0, 6.0, 3.0]]);
        let near = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
        assert!(near(&m, &[2.0, 4.0, 1.0]), "{m:?}");
        let want = [[1.0, 2.0, 1.5], [2.0, 4.0, 3.0], [1.5, 3.0, 3.0]];
        assert!(near(c.as_flattened(), want.as_flattened()), "{c:?}");
        assert!(near(&sd(&c), &[1.0, 2.0, 3f64.sqrt()]));
        assert!(near(&off_diagonal(&c), &[2.0, 1.5, 3.0]));
        let back = from_parts(sd(&c), off_diagonal(&c));
        assert!(near(back.as_flattened(), c.as_flattened()));
        assert_eq!(sample(&[[1.0, 2.0, 3.0]]).1, ZERO);
    }

    #[test]
    fn factors_rebuild_the_covariance_and_bad_ones_are_named() {
        let c = [[1.0, 2.0, 1.5], [2.0, 4.0, 3.0], [1.5, 3.0, 3.0]];
        check(&c).unwrap();
        let back = of_factors(&factors(&c));
        for i in 0..3 {
            for j in 0..3 {
                assert!((back[i][j] - c[i][j]).abs() < 1e-12, "{back:?}");
            }
        }
        // X and Y perfectly correlated: one direction has no variance; two factors.
        assert_eq!(factors(&[[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 0.0]]).len(), 1);
        // |cov XY| = 3 > sd X · sd Y = 2: no such covariance.
        let e = check(&[[1.0, 3.0, 0.0], [3.0, 4.0, 0.0], [0.0, 0.0, 1.0]]).unwrap_err();
        assert!(e.contains("negative variance"), "{e}");
        assert!(check(&[[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).is_err());
        assert!(check(&[[f64::NAN, 0.0, 0.0], [0.0; 3], [0.0; 3]]).is_err());
    }

    /// The stated repeatability carried to X, Y, Z matches the scatter of readings drawn
    /// as the CS-100A's noise is (Y and x, y independent normals), to within the sampling
    /// error of 200 000 draws.
    #[test]
    fn stated_repeatability_carries_to_xyz_as_sampled() {
        let r = Repeatability::of("cs100a").unwrap();
        assert_eq!(Repeatability::of("spectralon"), None);
        // A saturated yellow (ColorChecker 16 under a white display): x 0.45, y 0.50,
        // where Z = (1 − x − y)Y/y is small and chromaticity noise moves it by a lot.
        let (x, y, big_y) = (0.45, 0.50, 10.0);
        let xyz = [x * big_y / y, big_y, (1.0 - x - y) * big_y / y];
        let c = r.covariance(xyz).unwrap();
        let mut rng = metamer_drivers::noise::SplitMix64::new(7);
        let draws: Vec<[f64; 3]> = (0..200_000)
            .map(|_| {
                let (xx, yy, ly) = (
                    x + r.xy * rng.normal(),
                    y + r.xy * rng.normal(),
                    big_y * (1.0 + r.y_rel * rng.normal()),
                );
                [xx * ly / yy, ly, (1.0 - xx - yy) * ly / yy]
            })
            .collect();
        let (_, s) = sample(&draws);
        for i in 0..3 {
            for j in 0..3 {
                let scale = (c[i][i] * c[j][j]).sqrt();
                assert!(
                    (s[i][j] - c[i][j]).abs() < 0.02 * scale,
                    "{i}{j}: sampled {} vs {}",
                    s[i][j],
                    c[i][j]
                );
            }
        }
        // By hand: σY = 0.01; σZ from x and y: ∂Z/∂x = −Y/y = −20, ∂Z/∂y = −(1−x)Y/y² =
        // −22, ∂Z/∂Y = 0.1: σZ² = 0.0005²·(400 + 484) + 0.01²·0.01 = 2.22e-4.
        assert!((c[1][1] - 1e-4).abs() < 1e-15);
        assert!((c[2][2] - 2.22e-4).abs() < 1e-12, "{}", c[2][2]);
        assert_eq!(r.covariance([0.0, 0.0, 0.0]), None);
    }
}
