//! An instrument's stated repeatability carried to the covariance of one reading's X, Y
//! and Z, beside the covariance arithmetic. The figures are data in the driver registry's
//! row of each model (`metamer_drivers::registry`), asked by model: the session's re-aim
//! flags, the box's outlier and spread tests, the box's spot readings and a single reading's
//! uncertainty in `validate` all read them here.

use metamer_drivers::registry;
use metamer_drivers::spec::model_named;
use metamer_drivers::MeasureMode;

use super::covariance::{Cov3, ZERO};
use crate::color::Xyz;
pub use registry::{LevelNoise, Repeatability, XyNoise};

/// The stated repeatability of the model named `model` (a reading's instrument, `cs100a`)
/// in `mode`: its registry row's, else the figure taken for a model that states none.
pub fn stated(model: &str, mode: MeasureMode) -> Repeatability {
    registry::stated_repeatability(model, mode)
}

/// The emissive repeatability of the model an instrument name or spec names (`cs100a`,
/// `sim:i1pro?seed=2`, `CS-100A`); None for a name that names no model with a stated
/// emissive figure (a transcript, whose model only its header says, among them).
pub fn emissive_of(name: &str) -> Option<Repeatability> {
    model_named(name)?.stated_repeatability(MeasureMode::Emissive)
}

/// The figure `r` with every σ times `factor`: what a factor pooled on the stated
/// figure's shape (its readings' whitened scatter) says one reading scatters.
pub fn scaled(r: &Repeatability, factor: f64) -> Repeatability {
    let level = match r.level {
        LevelNoise::Flat => LevelNoise::Flat,
        LevelNoise::Shot {
            full_signal_cd_m2,
            dark_cd_m2,
        } => LevelNoise::Shot {
            full_signal_cd_m2,
            dark_cd_m2: dark_cd_m2 * factor,
        },
    };
    let xy = r.xy.map(|xy| match xy {
        XyNoise::Fixed(s) => XyNoise::Fixed(s * factor),
        // Already relative to Y's figure, which scales.
        XyNoise::PerRelativeY(k) => XyNoise::PerRelativeY(k),
    });
    Repeatability {
        y_relative: r.y_relative * factor,
        y_absolute: r.y_absolute * factor,
        level,
        xy,
        ..*r
    }
}

/// The covariance of X, Y, Z of one reading of `xyz`: with X = xY/y and
/// Z = (1 − x − y)Y/y, J·diag(σx², σy², σY²)·Jᵀ with J the derivatives of (X, Y, Z) by
/// (x, y, Y), the last digit's rounding counted as a uniform error (variance d²/12).
/// None without a chromaticity (X + Y + Z ≤ 0, Y ≤ 0) or without a stated x, y figure.
pub fn covariance(r: &Repeatability, xyz: Xyz) -> Option<Cov3> {
    let s = xyz[0] + xyz[1] + xyz[2];
    if !(s > 0.0 && xyz[1] > 0.0) {
        return None;
    }
    let (x, y, big_y) = (xyz[0] / s, xyz[1] / s, xyz[1]);
    let xy = r.sigma_xy(big_y)?;
    let digit = r.digit_y(big_y);
    // Columns: ∂/∂x, ∂/∂y, ∂/∂Y.
    let j = [
        [big_y / y, -x * big_y / (y * y), x / y],
        [0.0, 0.0, 1.0],
        [-big_y / y, -(1.0 - x) * big_y / (y * y), (1.0 - x - y) / y],
    ];
    let var = [
        xy * xy,
        xy * xy,
        r.sigma_y(big_y).powi(2) + digit * digit / 12.0,
    ];
    let mut c = ZERO;
    for (a, row) in c.iter_mut().enumerate() {
        for (b, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| j[a][k] * var[k] * j[b][k]).sum();
        }
    }
    Some(c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::validation::covariance::sample;

    /// The stated repeatability carried to X, Y, Z matches the scatter of readings drawn
    /// as the CS-100A's noise is (Y and x, y independent normals, Y's last digit as its
    /// variance d²/12), to within the sampling error of 200 000 draws.
    #[test]
    fn stated_repeatability_carries_to_xyz_as_sampled() {
        let r = emissive_of("sim:cs100a?seed=2").unwrap();
        assert_eq!(r, stated("cs100a", MeasureMode::Emissive));
        assert_eq!(emissive_of("spectralon"), None);
        // A saturated yellow (ColorChecker 16 under a white display): x 0.45, y 0.50,
        // where Z = (1 − x − y)Y/y is small and chromaticity noise moves it by a lot.
        let (x, y, big_y) = (0.45, 0.50, 10.0);
        let xyz = Xyz::new(x * big_y / y, big_y, (1.0 - x - y) * big_y / y);
        let c = covariance(&r, xyz).unwrap();
        // By hand: σY² = (0.1 % of 10)² + 0.01²/12 (four digits of 10.00) = 1.08333e-4;
        // σZ from x and y: ∂Z/∂x = −Y/y = −20, ∂Z/∂y = −(1−x)Y/y² = −22, ∂Z/∂Y = 0.1:
        // σZ² = 0.0005²·(400 + 484) + 1.08333e-4·0.01 = 2.22083e-4.
        assert!((c[1][1] - 1.083_333e-4).abs() < 1e-10, "{}", c[1][1]);
        assert!((c[2][2] - 2.220_833e-4).abs() < 1e-9, "{}", c[2][2]);
        let (sxy, sy) = (0.0005, c[1][1].sqrt());
        let mut rng = metamer_drivers::noise::SplitMix64::new(7);
        let draws: Vec<Xyz> = (0..200_000)
            .map(|_| {
                let (xx, yy, ly) = (
                    x + sxy * rng.normal(),
                    y + sxy * rng.normal(),
                    big_y + sy * rng.normal(),
                );
                Xyz::new(xx * ly / yy, ly, (1.0 - xx - yy) * ly / yy)
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
        assert_eq!(covariance(&r, Xyz::default()), None);
    }

    /// A scaled figure scales σ of Y and of x, y at every level by the factor, the
    /// CS-100A's (flat) and the i1Pro's (shot noise below full signal) alike.
    #[test]
    fn a_scaled_figure_scales_every_sigma() {
        for model in ["cs100a", "i1pro"] {
            let r = stated(model, MeasureMode::Emissive);
            let s = scaled(&r, 1.5);
            for y in [0.5, 3.0, 25.0, 400.0] {
                assert!(
                    (s.sigma_y(y) - 1.5 * r.sigma_y(y)).abs() < 1e-12 * y,
                    "{model} {y}"
                );
                let (a, b) = (s.sigma_xy(y).unwrap(), r.sigma_xy(y).unwrap());
                assert!((a - 1.5 * b).abs() < 1e-12, "{model} {y}");
            }
        }
    }

    /// The i1Pro's figure depends on the level: at 25 cd/m² σY/Y is 0.30447 % (0.15 % ·
    /// √(100/25) with 0.013/25 in quadrature), x, y 0.3 times that; its covariance uses the
    /// same figure.
    #[test]
    fn the_i1pros_figure_follows_the_level() {
        let r = emissive_of("sim:i1pro?time_scale=0").unwrap();
        assert_eq!(r, stated("i1pro", MeasureMode::Emissive));
        assert!((r.sigma_y(25.0) - 25.0 * 0.003_044_7).abs() < 1e-5);
        assert!((r.sigma_y(400.0) / 400.0 - 0.0015).abs() < 1e-6);
        assert!((r.sigma_xy(25.0).unwrap() - 0.3 * 0.003_044_7).abs() < 1e-7);
        let c = covariance(&r, Xyz::new(20.0, 25.0, 30.0)).unwrap();
        assert!((c[1][1] - r.sigma_y(25.0).powi(2)).abs() < 1e-12);
    }
}
