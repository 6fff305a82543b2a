//! PLCC with black correction (paper Eq. 9; Post & Calhoun, "An evaluation of methods for
//! producing desired colors on CRT monitors", Color Res. Appl. 14(4), 1989): the columns of M
//! are the full-on primaries minus black, and each channel's TRC comes from its ramp —
//! interpolated through every measured level (true PLCC; piecewise linear in the ramp's
//! power-law domain, see [`super::Trc::Table`]) or as a fitted or given power law (the paper
//! used 2.2).
//!
//! A ramp patch's normalised output is its black-corrected XYZ projected on the primary's
//! column (least squares), not its Y alone: blue has little Y, so Y alone would be noisy.

use super::error::FitError;
use super::samples::{SortedSamples, CHANNEL_NAMES};
use super::trc::fit_power_gamma;
use super::{MatrixTrc, ModelKind, Trc};
use crate::color::Xyz;

/// Black and the Eq. 9 matrix (columns: full-on primaries minus black).
pub fn black_and_primaries(
    set: &SortedSamples,
    kind: ModelKind,
) -> Result<(Xyz, [[f64; 3]; 3]), FitError> {
    let black = set.black.ok_or_else(|| FitError::Missing {
        model: kind,
        what: "the black patch (r,g,b = 0,0,0)".into(),
    })?;
    let mut m = [[0.0; 3]; 3];
    for c in 0..3 {
        let p = set.primaries[c].ok_or_else(|| FitError::Missing {
            model: kind,
            what: format!("the full-on {} patch", CHANNEL_NAMES[c]),
        })?;
        for r in 0..3 {
            m[r][c] = p[r] - black[r];
        }
    }
    Ok((black, m))
}

/// The ramp of channel `c` as (drive, R′) points including (0, 0), R′ being the
/// black-corrected XYZ projected on M's column `c`.
pub fn ramp_points(
    set: &SortedSamples,
    black: Xyz,
    m: &[[f64; 3]; 3],
    c: usize,
) -> Vec<(f64, f64)> {
    let col = [m[0][c], m[1][c], m[2][c]];
    let norm2: f64 = col.iter().map(|v| v * v).sum();
    let mut pts = vec![(0.0, 0.0)];
    pts.extend(set.ramps[c].iter().map(|(d, xyz)| {
        let dot: f64 = (0..3).map(|k| (xyz[k] - black[k]) * col[k]).sum();
        (*d, dot / norm2)
    }));
    pts
}

pub(crate) fn singular(condition: f64) -> FitError {
    FitError::SingularPrimaries {
        condition,
        limit: super::MAX_CONDITION,
    }
}

/// Paper Eq. 9 with TRCs interpolated through the measured ramps (see [`Trc::Table`]).
pub fn fit_plcc(set: &SortedSamples) -> Result<MatrixTrc, FitError> {
    let kind = ModelKind::Plcc;
    let (black, m) = black_and_primaries(set, kind)?;
    let trc = ramp_tables(set, kind, black, &m)?;
    MatrixTrc::new(kind, black, m, trc).map_err(singular)
}

/// Each channel's TRC interpolated through its measured ramp (black-corrected against
/// `black` and the primaries' matrix `m`); a channel without a ramp is an error for `kind`.
pub fn ramp_tables(
    set: &SortedSamples,
    kind: ModelKind,
    black: Xyz,
    m: &[[f64; 3]; 3],
) -> Result<[Trc; 3], FitError> {
    if let Some(c) = (0..3).find(|&c| set.intermediate_levels(c) == 0) {
        let hint = if kind == ModelKind::Plcc {
            "; use plcc-gamma with a given exponent to assume a power law instead"
        } else {
            ""
        };
        return Err(FitError::Missing {
            model: kind,
            what: format!(
                "a {} ramp (patches with only {} on, between 0 and 1) to interpolate its \
                 TRC{hint}",
                CHANNEL_NAMES[c], CHANNEL_NAMES[c]
            ),
        });
    }
    Ok(std::array::from_fn(|c| {
        Trc::table_from_ramp(&ramp_points(set, black, m, c))
    }))
}

/// Paper Eq. 9 with a power-law TRC per channel: `gamma` given (the paper's 2.2) or fitted
/// to each ramp.
pub fn fit_plcc_gamma(set: &SortedSamples, gamma: Option<f64>) -> Result<MatrixTrc, FitError> {
    let kind = ModelKind::PlccGamma;
    let (black, m) = black_and_primaries(set, kind)?;
    let mut trc: [Trc; 3] = std::array::from_fn(|_| Trc::Power { gamma: 1.0 });
    for (c, t) in trc.iter_mut().enumerate() {
        let g = match gamma {
            Some(g) => g,
            None => {
                if set.intermediate_levels(c) == 0 {
                    return Err(FitError::Missing {
                        model: kind,
                        what: format!(
                            "a {} ramp to fit its exponent (or give it one)",
                            CHANNEL_NAMES[c]
                        ),
                    });
                }
                fit_power_gamma(&ramp_points(set, black, &m, c))
            }
        };
        *t = Trc::Power { gamma: g };
    }
    MatrixTrc::new(kind, black, m, trc).map_err(singular)
}
