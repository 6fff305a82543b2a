//! The RGB → XYZ matrix an OpenEXR file's `chromaticities` attribute defines, so that an
//! image another renderer wrote in an RGB space (pbrt-v4 writes its film's colour space,
//! e.g. ACES2065-1, and names its primaries in that attribute) is read as the XYZ it holds.
//!
//! The derivation is the usual one (SMPTE RP 177-1993 §3.3; OpenEXR's `RGBtoXYZ` in
//! `ImfChromaticities.cpp` does the same): each primary's XYZ is its chromaticity (x, y,
//! 1 − x − y) / y scaled by an unknown factor; the three factors are those for which
//! (1, 1, 1) is the white point with Y = 1. OpenEXR defines the attribute so that RGB
//! (1, 1, 1) is that white, and `whiteLuminance` its luminance in cd/m² (the reader asks it
//! to be 1 or absent where it reads absolute images).

use nalgebra::{Matrix3, Vector3};

/// The CIE xy of the red, green and blue primaries and of the white.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chromaticities {
    pub red: [f64; 2],
    pub green: [f64; 2],
    pub blue: [f64; 2],
    pub white: [f64; 2],
}

/// XYZ's own: R = (1, 0), G = (0, 1), B = (0, 0), white (1/3, 1/3); the matrix is the
/// identity.
pub const XYZ_CHROMATICITIES: Chromaticities = Chromaticities {
    red: [1.0, 0.0],
    green: [0.0, 1.0],
    blue: [0.0, 0.0],
    white: [1.0 / 3.0, 1.0 / 3.0],
};

impl Chromaticities {
    /// The matrix M with XYZ = M · RGB, or None when the attribute cannot define one (a
    /// white with y ≤ 0, primaries on one line, a white the primaries cannot make with
    /// positive amounts of each).
    pub fn rgb_to_xyz(&self) -> Option<[[f64; 3]; 3]> {
        // Each primary at X + Y + Z = 1, not at Y = 1: XYZ's own blue has y = 0 and ACES's
        // AP0 blue y < 0, and the scale factor absorbs the choice.
        let column = |[x, y]: [f64; 2]| -> Option<Vector3<f64>> {
            if !(x.is_finite() && y.is_finite()) {
                return None;
            }
            Some(Vector3::new(x, y, 1.0 - x - y))
        };
        let p =
            Matrix3::from_columns(&[column(self.red)?, column(self.green)?, column(self.blue)?]);
        let [xw, yw] = self.white;
        if !(xw.is_finite() && yw.is_finite()) || yw <= 0.0 {
            return None;
        }
        let white = Vector3::new(xw / yw, 1.0, (1.0 - xw - yw) / yw);
        // Primaries on one line (or nearly) define no RGB space; the determinant of
        // chromaticities is at most ~0.5, a real space's a few tenths.
        if p.determinant().abs() < 1e-9 {
            return None;
        }
        let scale = p.try_inverse()? * white;
        if scale.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
            return None;
        }
        let m = p * Matrix3::from_diagonal(&scale);
        Some(std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)])))
    }
}

/// `m · rgb`.
pub fn apply(m: &[[f64; 3]; 3], rgb: [f32; 3]) -> [f32; 3] {
    std::array::from_fn(|r| {
        (m[r][0] * f64::from(rgb[0]) + m[r][1] * f64::from(rgb[1]) + m[r][2] * f64::from(rgb[2]))
            as f32
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [[f64; 3]; 3], b: [[f64; 3]; 3], tol: f64) {
        for r in 0..3 {
            for c in 0..3 {
                assert!((a[r][c] - b[r][c]).abs() < tol, "{a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn xyz_chromaticities_give_the_identity() {
        let m = XYZ_CHROMATICITIES.rgb_to_xyz().unwrap();
        close(
            m,
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            1e-12,
        );
    }

    #[test]
    fn rec709_primaries_give_iec_61966_2_1s_matrix() {
        // IEC 61966-2-1 (sRGB) §5.2's matrix as printed to four decimals, from the BT.709
        // primaries and D65 (0.3127, 0.3290); the standard rounded it after inverting its
        // XYZ → RGB matrix, so its last digit differs by up to 2 from the exact derivation.
        let srgb = Chromaticities {
            red: [0.64, 0.33],
            green: [0.30, 0.60],
            blue: [0.15, 0.06],
            white: [0.3127, 0.3290],
        };
        let m = srgb.rgb_to_xyz().unwrap();
        close(
            m,
            [
                [0.4124, 0.3576, 0.1805],
                [0.2126, 0.7152, 0.0722],
                [0.0193, 0.1192, 0.9505],
            ],
            3e-4,
        );
    }

    #[test]
    fn aces_ap0_gives_smpte_st_2065_1s_matrix() {
        // SMPTE ST 2065-1:2012 §4.1.2 (ACES2065-1): AP0 primaries, white (0.32168, 0.33767),
        // and its published NPM to ten digits.
        let ap0 = Chromaticities {
            red: [0.7347, 0.2653],
            green: [0.0, 1.0],
            blue: [0.0001, -0.077],
            white: [0.32168, 0.33767],
        };
        // AP0's blue has y < 0: a real attribute, and a valid matrix.
        close(
            ap0.rgb_to_xyz().unwrap(),
            [
                [0.9525523959, 0.0, 0.0000936786],
                [0.3439664498, 0.7281660966, -0.0721325464],
                [0.0, 0.0, 1.0088251844],
            ],
            1e-9,
        );
    }

    #[test]
    fn degenerate_attributes_define_no_matrix() {
        let line = Chromaticities {
            red: [0.2, 0.2],
            green: [0.3, 0.3],
            blue: [0.4, 0.4],
            white: [0.3127, 0.329],
        };
        assert!(line.rgb_to_xyz().is_none());
        let no_white = Chromaticities {
            white: [0.3, 0.0],
            ..XYZ_CHROMATICITIES
        };
        assert!(no_white.rgb_to_xyz().is_none());
        let nan = Chromaticities {
            red: [f64::NAN, 0.3],
            ..XYZ_CHROMATICITIES
        };
        assert!(nan.rgb_to_xyz().is_none());
    }
}
