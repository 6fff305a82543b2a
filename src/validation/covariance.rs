//! The uncertainty of one patch's XYZ as a full 3×3 covariance: estimated from repeated
//! readings (their X, Y and Z scatter together: a meter's repeats mostly move luminance
//! and chromaticity, not one axis at a time), or, for a single reading, the instrument's
//! stated repeatability in Y and in x, y carried to X, Y, Z to first order
//! ([`super::repeatability::covariance`]).

use nalgebra::{Matrix3, SymmetricEigen};

use crate::color::Xyz;

/// A covariance of X, Y and Z, row-major.
pub type Cov3 = [[f64; 3]; 3];

/// No uncertainty.
pub const ZERO: Cov3 = [[0.0; 3]; 3];

/// The mean of `readings` and their sample covariance (divisor k − 1; zero for fewer than
/// two readings).
pub fn sample(readings: &[Xyz]) -> (Xyz, Cov3) {
    let (mean, c) = mean_and_covariance(readings);
    (mean.into(), c)
}

/// The sample covariance of triples other than an XYZ (CIELAB differences), as
/// [`sample`]'s.
pub fn spread(rows: &[[f64; 3]]) -> Cov3 {
    mean_and_covariance(rows).1
}

fn mean_and_covariance<T: Copy + Into<[f64; 3]>>(rows: &[T]) -> ([f64; 3], Cov3) {
    let k = rows.len();
    let mut mean = [0.0; 3];
    for r in rows {
        let r: [f64; 3] = (*r).into();
        for (m, v) in mean.iter_mut().zip(r) {
            *m += v / k.max(1) as f64;
        }
    }
    let mut c = ZERO;
    if k > 1 {
        for r in rows {
            let r: [f64; 3] = (*r).into();
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sample_covariance_by_hand() {
        // X: 1, 2, 3; Y: 2, 4, 6 (= 2X); Z: 0, 0, 3. Means 2, 4, 1. Deviations
        // X −1, 0, 1; Y −2, 0, 2; Z −1, −1, 2: var X 1, var Y 4, cov XY 2, var Z 3,
        // cov XZ (1 + 0 + 2)/2 = 1.5, cov YZ 3.
        let (m, c) = sample(&[
            Xyz::new(1.0, 2.0, 0.0),
            Xyz::new(2.0, 4.0, 0.0),
            Xyz::new(3.0, 6.0, 3.0),
        ]);
        let near = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
        assert!(near(&m.to_array(), &[2.0, 4.0, 1.0]), "{m:?}");
        let want = [[1.0, 2.0, 1.5], [2.0, 4.0, 3.0], [1.5, 3.0, 3.0]];
        assert!(near(c.as_flattened(), want.as_flattened()), "{c:?}");
        assert!(near(&sd(&c), &[1.0, 2.0, 3f64.sqrt()]));
        assert!(near(&off_diagonal(&c), &[2.0, 1.5, 3.0]));
        let back = from_parts(sd(&c), off_diagonal(&c));
        assert!(near(back.as_flattened(), c.as_flattened()));
        assert_eq!(sample(&[Xyz::new(1.0, 2.0, 3.0)]).1, ZERO);
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
        assert_eq!(
            factors(&[[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 0.0]]).len(),
            1
        );
        // |cov XY| = 3 > sd X · sd Y = 2: no such covariance.
        let e = check(&[[1.0, 3.0, 0.0], [3.0, 4.0, 0.0], [0.0, 0.0, 1.0]]).unwrap_err();
        assert!(e.contains("negative variance"), "{e}");
        assert!(check(&[[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).is_err());
        assert!(check(&[[f64::NAN, 0.0, 0.0], [0.0; 3], [0.0; 3]]).is_err());
    }
}
