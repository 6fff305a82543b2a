//! The ICC profile connection space: D50-relative XYZ with the display white mapped to the
//! PCS illuminant by the linearised Bradford transform, as ICC.1:2010 Annex E recommends
//! for the chromaticAdaptationTag.

use crate::color::Xyz;

/// The PCS illuminant, ICC.1:2010 7.2.16 (s15Fixed16 values 0x0000F6D6, 0x00010000,
/// 0x0000D32D).
pub const D50: Xyz = Xyz::new(0.9642, 1.0, 0.8249);

/// Lam's cone-response matrix of the Bradford transform (ICC.1:2010 Annex E, Eq. E.3).
const BRADFORD: [[f64; 3]; 3] = [
    [0.8951, 0.2664, -0.1614],
    [-0.7502, 1.7135, 0.0367],
    [0.0389, -0.0685, 1.0296],
];

pub type Mat3 = [[f64; 3]; 3];

/// `m·v` for a column `v` given as an array or as [`Xyz`].
pub fn mul(m: &Mat3, v: impl std::ops::Index<usize, Output = f64>) -> [f64; 3] {
    std::array::from_fn(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

pub fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    std::array::from_fn(|r| std::array::from_fn(|c| (0..3).map(|k| a[r][k] * b[k][c]).sum()))
}

pub fn inverse(m: &Mat3) -> Option<Mat3> {
    let inv = nalgebra::Matrix3::from_fn(|r, c| m[r][c]).try_inverse()?;
    Some(std::array::from_fn(|r| {
        std::array::from_fn(|c| inv[(r, c)])
    }))
}

/// The linearised Bradford matrix taking colours seen under `source` white to those seen
/// under `target` white (both XYZ with any scale; only their chromaticities matter after
/// Y normalisation).
pub fn bradford(source: Xyz, target: Xyz) -> Mat3 {
    let inv = inverse(&BRADFORD).expect("Bradford's matrix is regular");
    let s = mul(&BRADFORD, source.map(|v| v / source.y));
    let t = mul(&BRADFORD, target.map(|v| v / target.y));
    let gain: Mat3 =
        std::array::from_fn(|r| std::array::from_fn(|c| if r == c { t[r] / s[r] } else { 0.0 }));
    mat_mul(&inv, &mat_mul(&gain, &BRADFORD))
}

/// Absolute XYZ (cd/m²) to PCS XYZ and back for one display white.
#[derive(Clone, Debug)]
pub struct Pcs {
    /// The chromaticAdaptationTag: display white (Y = 1) → D50.
    pub chad: Mat3,
    /// Absolute XYZ → PCS XYZ: `chad / Y_white`.
    to_pcs: Mat3,
    from_pcs: Mat3,
}

impl Pcs {
    /// `white`: the display white, cd/m²; its luminance must be positive.
    pub fn new(white: Xyz) -> Option<Pcs> {
        if !(white.y > 0.0 && white.is_finite()) {
            return None;
        }
        let chad = bradford(white, D50);
        let to_pcs = chad.map(|row| row.map(|v| v / white[1]));
        let from_pcs = inverse(&to_pcs)?;
        Some(Pcs {
            chad,
            to_pcs,
            from_pcs,
        })
    }

    pub fn to_pcs(&self, xyz: Xyz) -> Xyz {
        mul(&self.to_pcs, xyz).into()
    }

    pub fn from_pcs(&self, pcs: Xyz) -> Xyz {
        mul(&self.from_pcs, pcs).into()
    }

    /// The matrix absolute XYZ → PCS XYZ.
    pub fn matrix(&self) -> &Mat3 {
        &self.to_pcs
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lindbloom's published Bradford D65 → D50 matrix (brucelindbloom.com, "Chromatic
    /// Adaptation", with his D65 0.95047/1/1.08883 and D50 0.96422/1/0.82521).
    #[test]
    fn bradford_d65_to_d50_matches_the_published_matrix() {
        let m = bradford(
            Xyz::new(0.95047, 1.0, 1.08883),
            Xyz::new(0.96422, 1.0, 0.82521),
        );
        let published = [
            [1.0478112, 0.0228866, -0.0501270],
            [0.0295424, 0.9904844, -0.0170491],
            [-0.0092345, 0.0150436, 0.7521316],
        ];
        for r in 0..3 {
            for c in 0..3 {
                assert!(
                    (m[r][c] - published[r][c]).abs() < 2e-7,
                    "{r},{c}: {}",
                    m[r][c]
                );
            }
        }
    }

    #[test]
    fn the_white_maps_to_d50_and_back() {
        let white = Xyz::new(180.0, 200.0, 230.0);
        let pcs = Pcs::new(white).unwrap();
        let w = pcs.to_pcs(white);
        for c in 0..3 {
            assert!((w[c] - D50[c]).abs() < 1e-12);
        }
        let back = pcs.from_pcs(w);
        for c in 0..3 {
            assert!((back[c] - white[c]).abs() < 1e-9);
        }
        assert!(Pcs::new(Xyz::new(1.0, 0.0, 1.0)).is_none());
    }
}
