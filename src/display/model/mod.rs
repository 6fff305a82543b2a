//! Display models behind one trait: forward (drive RGB 0–1 → absolute XYZ cd/m²) and inverse
//! (XYZ → drive RGB, reporting out-of-gamut targets instead of clipping silently).
//!
//! The paper's model is Eq. 9, inverse PLCC with black correction; [`ModelKind`] lists it and
//! the richer models offered where its assumptions fail.

mod gog;
mod least_squares;
mod lut;
mod matrix_lsq;
mod matrix_trc;
mod plcc;
pub mod samples;
mod trc;

pub use gog::{fit_gog, fit_gog_curve};
pub use least_squares::levenberg_marquardt;
pub use lut::{fit_lut, Lut3d};
pub use matrix_lsq::fit_matrix_lsq;
pub use matrix_trc::{condition_number, MatrixTrc, MAX_CONDITION};
pub use plcc::{fit_plcc, fit_plcc_gamma, fit_power_gamma};
pub use trc::{FastInverse, Trc};

use serde::{Deserialize, Serialize};

/// A target whose channel output (R′, G′, B′ in Eq. 9, normalised so full drive gives 1)
/// lies further than this outside the range that drive values 0–1 produce is out of gamut.
/// It is judged on the output, not on the drive value, because a TRC's inverse magnifies
/// rounding near black (d = v^(1/γ) turns −10⁻⁷ into −7·10⁻⁴ for γ = 2.2); 10⁻⁵ of full
/// output is above float32 image precision and measurement rounding, far below a visible
/// difference.
pub const GAMUT_TOLERANCE: f64 = 1e-5;

/// A display's colorimetric behaviour.
pub trait DisplayModel: Send + Sync {
    fn name(&self) -> &'static str;
    /// Drive values 0–1 → absolute XYZ, cd/m².
    fn forward(&self, rgb: [f64; 3]) -> [f64; 3];
    /// XYZ → drive values; never clips silently (see [`Inverse`]).
    fn inverse(&self, xyz: [f64; 3]) -> Inverse;
}

/// The drive values for a target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inverse {
    /// Clipped to 0..=1.
    pub rgb: [f64; 3],
    /// The model's solution before clipping.
    pub unclipped: [f64; 3],
    /// The target needs a channel output outside what drive values 0–1 give, by more than
    /// [`GAMUT_TOLERANCE`] of full output.
    pub out_of_gamut: bool,
}

/// The models `fit` offers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ModelKind {
    /// Paper Eq. 9 with TRCs interpolated through the measured ramps.
    Plcc,
    /// Paper Eq. 9 with a power-law TRC per channel (fitted, or given as the paper's 2.2).
    PlccGamma,
    /// Gain-offset-gamma per channel + primaries matrix, least squares.
    Gog,
    /// GOG with an extra additive offset per channel.
    Gogo,
    /// A 3D LUT over a measured grid, tetrahedral interpolation: no constant-chromaticity or
    /// additivity assumption.
    Lut,
    /// Measured-ramp TRCs and a matrix + black offset fitted over all patches.
    MatrixLsq,
}

impl ModelKind {
    pub const ALL: [ModelKind; 6] = [
        ModelKind::Plcc,
        ModelKind::PlccGamma,
        ModelKind::Gog,
        ModelKind::Gogo,
        ModelKind::Lut,
        ModelKind::MatrixLsq,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Plcc => "plcc",
            ModelKind::PlccGamma => "plcc-gamma",
            ModelKind::Gog => "gog",
            ModelKind::Gogo => "gogo",
            ModelKind::Lut => "lut",
            ModelKind::MatrixLsq => "matrix-lsq",
        }
    }
}

impl std::fmt::Display for ModelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for ModelKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        ModelKind::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| {
                let names: Vec<&str> = ModelKind::ALL.iter().map(|k| k.name()).collect();
                format!("unknown model '{s}' (known: {})", names.join(", "))
            })
    }
}

/// A fitted model's parameters, as saved in a profile.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "form", rename_all = "kebab-case")]
pub enum ModelParams {
    /// XYZ = XYZ₀ + M·TRC(rgb) (plcc, plcc-gamma, gog, gogo, matrix-lsq).
    MatrixTrc(MatrixTrc),
    /// A 3D LUT with per-channel shapers (lut).
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
            ModelParams::MatrixTrc(m) => m.prepare(kind).map_err(|condition| {
                format!("the model's matrix cannot be inverted (condition number {condition:.3e})")
            }),
            ModelParams::Lut(l) => l.prepare(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kind_names_round_trip() {
        for k in ModelKind::ALL {
            assert_eq!(k.to_string().parse::<ModelKind>().unwrap(), k);
            assert_eq!(
                serde_json::to_string(&k).unwrap(),
                format!("\"{}\"", k.name())
            );
        }
        assert!("plc"
            .parse::<ModelKind>()
            .unwrap_err()
            .contains("plcc-gamma"));
    }
}
