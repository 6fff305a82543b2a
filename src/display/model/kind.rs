//! The models `fit` offers, by name.

use serde::{Deserialize, Serialize};

/// The models `fit` offers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ModelKind {
    /// Paper Eq. 9 with TRCs interpolated through the measured ramps.
    Plcc,
    /// Paper Eq. 9 with a power-law TRC per channel (fitted, or given as the paper's 2.2).
    PlccGamma,
    /// Post & Calhoun's PLVC: each channel adds its own measured ramp light (XYZ, not a
    /// scalar times its primary), so chromaticity may drift along a ramp; additive.
    Plvc,
    /// Gain-offset-gamma per channel + primaries matrix, least squares.
    Gog,
    /// GOG with an extra additive offset per channel.
    Gogo,
    /// A 3D LUT over a measured grid, tetrahedral interpolation: no constant-chromaticity or
    /// additivity assumption.
    Lut,
    /// Measured-ramp TRCs and a matrix + black offset fitted over all patches.
    MatrixLsq,
    /// Monotone per-channel curves and a matrix + black offset fitted jointly over every
    /// patch in CIELAB (needs no ramps).
    ShaperMatrix,
}

impl ModelKind {
    pub const ALL: [ModelKind; 8] = [
        ModelKind::Plcc,
        ModelKind::PlccGamma,
        ModelKind::Plvc,
        ModelKind::Gog,
        ModelKind::Gogo,
        ModelKind::Lut,
        ModelKind::MatrixLsq,
        ModelKind::ShaperMatrix,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Plcc => "plcc",
            ModelKind::PlccGamma => "plcc-gamma",
            ModelKind::Plvc => "plvc",
            ModelKind::Gog => "gog",
            ModelKind::Gogo => "gogo",
            ModelKind::Lut => "lut",
            ModelKind::MatrixLsq => "matrix-lsq",
            ModelKind::ShaperMatrix => "shaper-matrix",
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
