//! Display models behind one trait: forward (drive RGB 0–1 → absolute XYZ cd/m²) and inverse
//! (XYZ → drive RGB, reporting out-of-gamut targets instead of clipping silently).
//!
//! The paper's model is Eq. 9, inverse PLCC with black correction; [`ModelKind`] lists it and
//! the richer models offered where its assumptions fail.

mod display_model;
mod error;
mod gog;
mod kind;
mod least_squares;
mod lut;
mod lut_scattered;
mod lut_unfold;
mod matrix_lsq;
mod matrix_trc;
mod plcc;
mod plvc;
pub mod samples;
mod shaper_matrix;
mod trc;

pub use display_model::{DisplayModel, Inverse, GAMUT_TOLERANCE};
pub use error::FitError;
pub use gog::{fit_gog, fit_gog_curve, gog_curve, gog_problem, GogProblem};
pub use kind::ModelKind;
pub use least_squares::levenberg_marquardt;
pub use lut::{fit_lut, has_full_grid, is_measured_grid, Lut3d};
pub use lut_scattered::{default_grid, fit_lut_scattered, ScatteredLut, LAMBDAS};
pub use matrix_lsq::fit_matrix_lsq;
pub use matrix_trc::{condition_number, MatrixTrc, MAX_CONDITION};
pub use plcc::{fit_plcc, fit_plcc_gamma};
pub use plvc::fit_plvc;
pub use samples::{fold_of, Sample};
pub use shaper_matrix::{default_knots, fit_shaper_matrix};
pub use trc::{fit_power_gamma, FastInverse, Trc};

use samples::CHANNEL_NAMES;
use serde::{Deserialize, Serialize};

/// A fitted model's parameters, as saved in a profile.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "form", rename_all = "kebab-case")]
pub enum ModelParams {
    /// XYZ = XYZ₀ + M·TRC(rgb) (plcc, plcc-gamma, gog, gogo, matrix-lsq).
    MatrixTrc(MatrixTrc),
    /// A 3D LUT with per-channel shapers (lut, and plvc as the grid of its additive sums).
    Lut(Lut3d),
}

impl ModelParams {
    pub fn model(&self) -> &dyn DisplayModel {
        match self {
            ModelParams::MatrixTrc(m) => m,
            ModelParams::Lut(l) => l,
        }
    }

    /// Rebuilds derived data after loading; the error says what is inconsistent.
    pub fn prepare(&mut self, kind: ModelKind) -> Result<(), String> {
        match self {
            ModelParams::MatrixTrc(m) => {
                for (curve, name) in m.trc.iter().zip(CHANNEL_NAMES) {
                    curve
                        .check()
                        .map_err(|e| format!("the {name} tone curve is unusable: {e}"))?;
                }
                let numbers = m.black.iter().chain(m.matrix.iter().flatten().copied());
                if let Some(v) = numbers.into_iter().find(|v| !v.is_finite()) {
                    return Err(format!(
                        "the model's black or matrix holds {v}, not a finite number"
                    ));
                }
                m.prepare(kind).map_err(|condition| {
                    format!(
                        "the model's matrix cannot be inverted (condition number {condition:.3e})"
                    )
                })
            }
            ModelParams::Lut(l) => l.prepare(),
        }
    }
}
