//! sRGB as IEC 61966-2-1:1999 defines it: the matrix from CIE XYZ (D65 white at Y = 1) to
//! linear sRGB and the transfer function that encodes a linear value. Previews, swatches
//! and test patches use it to show a colour; nothing measured passes through it.

/// CIE XYZ → linear sRGB (IEC 61966-2-1:1999 §5.2, the rounded matrix the standard gives).
pub const XYZ_TO_LINEAR_SRGB: [[f64; 3]; 3] = [
    [3.2406, -1.5372, -0.4986],
    [-0.9689, 1.8758, 0.0415],
    [0.0557, -0.2040, 1.0570],
];

/// Linear sRGB of `xyz` (D65 white at Y = 1), not clipped: a channel outside 0–1 is a
/// colour outside the sRGB gamut.
pub fn xyz_to_linear_srgb(xyz: [f64; 3]) -> [f64; 3] {
    XYZ_TO_LINEAR_SRGB.map(|row| row.iter().zip(xyz).map(|(m, v)| m * v).sum())
}

/// The sRGB encoding of a linear value (IEC 61966-2-1:1999 §5.2): linear below 0.0031308,
/// a 1/2.4 power above. Not clipped; callers clip where they quantize.
pub fn srgb_encode(v: f64) -> f64 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_encoding_by_hand() {
        // 12.92 · 0.002 = 0.02584; 1.055 · 0.5^(1/2.4) − 0.055 = 1.055 · 0.7491535 − 0.055.
        assert!((srgb_encode(0.002) - 0.025_84).abs() < 1e-12);
        assert!((srgb_encode(0.5) - 0.735_356_98).abs() < 1e-8);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-12);
        // The two pieces meet at the break point to within the standard's rounding.
        assert!((12.92 * 0.003_130_8 - srgb_encode(0.003_130_9)).abs() < 1e-5);
    }

    #[test]
    fn d65_white_is_white() {
        // D65 at Y = 1 (CIE 15:2018 Table T.3: x 0.31272, y 0.32903 → X 0.95047, Z 1.08883).
        let rgb = xyz_to_linear_srgb([0.950_47, 1.0, 1.088_83]);
        for c in rgb {
            assert!((c - 1.0).abs() < 1e-3, "{rgb:?}");
        }
    }
}
