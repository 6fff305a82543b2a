//! Whether a tristimulus reading can be a measurement of light at all. Readings enter from
//! instruments, transcripts and files; one that is NaN, infinite, far brighter than any
//! source an instrument of this kind can face, or whose chromaticity lies outside the
//! triangle x ≥ 0, y ≥ 0, x + y ≤ 1 (a negative tristimulus value) is refused where it
//! enters, instead of becoming a white of 5e307 cd/m² downstream.

use crate::Xyz;

/// Brightest plausible reading, cd/m²: the solar disc is about 1.6·10⁹ cd/m², so 10¹⁰ only
/// refuses numbers no instrument can have measured.
pub const MAX_CD_M2: f64 = 1e10;

/// How negative a component may be before it is not noise: 1 % of the largest component
/// plus 0.01 (a meter's last digit near black), in the reading's own units.
fn negative_tolerance(xyz: [f64; 3]) -> f64 {
    0.01 * xyz.iter().fold(0.0f64, |m, v| m.max(v.abs())) + 0.01
}

/// Why a reading cannot be a measurement.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Implausible {
    #[error("XYZ {0:?} is not a number (NaN or infinite)")]
    NotFinite([f64; 3]),
    #[error("XYZ {xyz:?} exceeds {MAX_CD_M2:e}, brighter than the sun's disc")]
    TooBright { xyz: [f64; 3] },
    #[error(
        "XYZ {xyz:?} has a negative component beyond measurement noise (chromaticity outside \
         x ≥ 0, y ≥ 0, x + y ≤ 1)"
    )]
    Negative { xyz: [f64; 3] },
}

/// Checks one XYZ reading (any unit in which 1 is about 1 cd/m², or white-relative Y = 100).
pub fn check_xyz(xyz: Xyz) -> Result<(), Implausible> {
    // The refusal shows the array as every file writes it.
    let xyz = xyz.to_array();
    if xyz.iter().any(|v| !v.is_finite()) {
        return Err(Implausible::NotFinite(xyz));
    }
    if xyz.iter().any(|v| v.abs() > MAX_CD_M2) {
        return Err(Implausible::TooBright { xyz });
    }
    let tolerance = negative_tolerance(xyz);
    if xyz.iter().any(|&v| v < -tolerance) {
        return Err(Implausible::Negative { xyz });
    }
    Ok(())
}

/// Whether a per-component spread (a standard deviation or standard error of XYZ) can
/// belong to readings: finite, not negative and no larger than the brightest reading.
pub fn plausible_spread(spread: [f64; 3]) -> bool {
    spread.iter().all(|s| (0.0..=MAX_CD_M2).contains(s))
}

/// Checks a luminance and chromaticity as a meter reports them (Y in cd/m², x, y).
pub fn check_yxy(luminance: f64, x: f64, y: f64) -> Result<(), Implausible> {
    let xyz = [luminance, x, y];
    if xyz.iter().any(|v| !v.is_finite()) {
        return Err(Implausible::NotFinite(xyz));
    }
    if luminance.abs() > MAX_CD_M2 {
        return Err(Implausible::TooBright { xyz });
    }
    // Chromaticities have no noise floor in cd/m²: the meter's ±0.001 repeatability.
    if luminance < -0.01 || x < -0.001 || y < -0.001 || x + y > 1.001 {
        return Err(Implausible::Negative { xyz });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_xyz(xyz: [f64; 3]) -> Result<(), Implausible> {
        super::check_xyz(Xyz::from_array(xyz))
    }

    #[test]
    fn real_readings_pass() {
        // D65 at 100 cd/m² (X = 95.047, Z = 108.883), a dark patch with noise below zero.
        check_xyz([95.047, 100.0, 108.883]).unwrap();
        check_xyz([0.004, -0.003, 0.002]).unwrap();
        check_yxy(100.0, 0.3127, 0.3290).unwrap();
    }

    #[test]
    fn spreads_are_finite_non_negative_and_bounded() {
        assert!(plausible_spread([0.0, 0.2, 1e10]));
        assert!(!plausible_spread([0.0, -0.1, 0.0]));
        assert!(!plausible_spread([f64::NAN, 0.0, 0.0]));
        assert!(!plausible_spread([1e308, 0.0, 0.0]));
    }

    #[test]
    fn impossible_readings_are_refused() {
        assert!(matches!(
            check_xyz([f64::NAN, 1.0, 1.0]),
            Err(Implausible::NotFinite(_))
        ));
        assert!(matches!(
            check_xyz([-1e308, 1.0, 1.0]),
            Err(Implausible::TooBright { .. })
        ));
        // x + y = 1.2 needs Z = Y·(1 − x − y)/y = −40 at Y = 100, y = 0.5.
        assert!(matches!(
            check_xyz([140.0, 100.0, -40.0]),
            Err(Implausible::Negative { .. })
        ));
        assert!(check_yxy(100.0, 0.7, 0.5).is_err());
        assert!(check_yxy(-5.0, 0.3, 0.3).is_err());
        assert!(check_yxy(f64::NAN, 0.3, 0.3).is_err());
    }
}
