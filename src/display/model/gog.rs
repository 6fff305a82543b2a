//! GOG and GOGO (Berns, "Methods for characterizing CRT displays", Displays 16(4), 1996):
//! the Eq. 9 matrix of full-on primaries minus black, with each channel's TRC a
//! gain-offset-gamma curve `max(gain·d + offset, 0)^γ` (GOG, normalised so gain + offset =
//! 1) or with an extra additive offset (GOGO), fitted by least squares to the channel's ramp.

use super::error::FitError;
use super::least_squares::levenberg_marquardt;
use super::plcc::{black_and_primaries, ramp_points, singular};
use super::samples::{SortedSamples, CHANNEL_NAMES};
use super::trc::fit_power_gamma;
use super::{MatrixTrc, ModelKind, Trc};

/// The residuals of a parameter vector.
pub type ResidualFn = dyn Fn(&[f64]) -> Vec<f64> + Send + Sync;

/// One channel's GOG (`flare` false) or GOGO curve fit as a least-squares problem: the
/// residual, the start and the box bounds of its parameters (see [`gog_curve`]).
pub struct GogProblem {
    pub residual: Box<ResidualFn>,
    pub start: Vec<f64>,
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
}

/// The curve of parameters `p`: GOG as (offset, γ) with gain = 1 − offset, GOGO as (gain,
/// offset, γ, flare).
pub fn gog_curve(p: &[f64], flare: bool) -> Trc {
    if flare {
        Trc::Gog {
            gain: p[0],
            offset: p[1],
            gamma: p[2],
            flare: p[3],
        }
    } else {
        Trc::Gog {
            gain: 1.0 - p[0],
            offset: p[0],
            gamma: p[1],
            flare: 0.0,
        }
    }
}

/// The fit of one channel's curve to (drive, R′) points as a problem any solver can take.
pub fn gog_problem(points: &[(f64, f64)], flare: bool) -> GogProblem {
    let gamma0 = fit_power_gamma(points);
    let points = points.to_vec();
    // Residuals in cube-root output: CIELAB lightness goes as Y^(1/3), so equal residuals
    // are roughly equal lightness errors. In linear output the fit gives up the dark end of
    // the ramp for the bright one, and reproduction pays for it in ΔE00 (on the LCD presets
    // of `metamer budget` the max error fell from ≈9 to ≈3.5 ΔE00).
    let residual = move |p: &[f64]| -> Vec<f64> {
        let t = gog_curve(p, flare);
        points
            .iter()
            .map(|&(d, s)| t.eval(d).cbrt() - s.cbrt())
            .collect()
    };
    let (start, lower, upper) = if flare {
        (
            vec![1.0, 0.0, gamma0, 0.0],
            vec![0.2, -0.5, 0.3, -0.2],
            vec![2.0, 0.8, 6.0, 0.2],
        )
    } else {
        (vec![0.0, gamma0], vec![-0.5, 0.3], vec![0.8, 6.0])
    };
    GogProblem {
        residual: Box::new(residual),
        start,
        lower,
        upper,
    }
}

/// Fits one channel's GOG (`flare` false) or GOGO curve to (drive, R′) points.
pub fn fit_gog_curve(points: &[(f64, f64)], flare: bool) -> Trc {
    let problem = gog_problem(points, flare);
    let p = levenberg_marquardt(
        &*problem.residual,
        &problem.start,
        &problem.lower,
        &problem.upper,
    );
    gog_curve(&p, flare)
}

/// GOG (`kind` Gog) or GOGO (`kind` Gogo).
pub fn fit_gog(set: &SortedSamples, kind: ModelKind) -> Result<MatrixTrc, FitError> {
    let flare = kind == ModelKind::Gogo;
    let (black, m) = black_and_primaries(set, kind)?;
    let need = if flare { 3 } else { 2 };
    let mut trc: [Trc; 3] = std::array::from_fn(|_| Trc::Power { gamma: 1.0 });
    for (c, t) in trc.iter_mut().enumerate() {
        if set.intermediate_levels(c) < need {
            return Err(FitError::Missing {
                model: kind,
                what: format!(
                    "a {} ramp with at least {need} levels between 0 and 1 to fit its curve",
                    CHANNEL_NAMES[c]
                ),
            });
        }
        *t = fit_gog_curve(&ramp_points(set, black, &m, c), flare);
    }
    MatrixTrc::new(kind, black, m, trc).map_err(singular)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_gain_offset_gamma() {
        let truth = Trc::Gog {
            gain: 1.1,
            offset: -0.1,
            gamma: 2.4,
            flare: 0.0,
        };
        let pts: Vec<(f64, f64)> = (0..=16)
            .map(|i| {
                let d = i as f64 / 16.0;
                (d, truth.eval(d))
            })
            .collect();
        let Trc::Gog {
            gain,
            offset,
            gamma,
            ..
        } = fit_gog_curve(&pts, false)
        else {
            panic!("a GOG curve")
        };
        assert!((gain - 1.1).abs() < 1e-5, "{gain}");
        assert!((offset + 0.1).abs() < 1e-5, "{offset}");
        assert!((gamma - 2.4).abs() < 1e-4, "{gamma}");
        let with_flare = Trc::Gog {
            gain: 0.9,
            offset: 0.05,
            gamma: 2.0,
            flare: 0.02,
        };
        let pts: Vec<(f64, f64)> = (0..=16)
            .map(|i| {
                let d = i as f64 / 16.0;
                (d, with_flare.eval(d))
            })
            .collect();
        let fitted = fit_gog_curve(&pts, true);
        for (d, s) in pts {
            assert!((fitted.eval(d) - s).abs() < 1e-6, "{d}");
        }
    }
}
