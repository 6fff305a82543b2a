//! A resampling filter built from a cell → wavelength mapping, as an i1Pro 2 (Rev E) needs:
//! its EEPROM stores the factory mapping as a cubic in the cell index (keys 0x2F63 /
//! 0x2F62), and the 36 output bands are built from it rather than trusted from the Rev A–D
//! filter tables.
//!
//! Each band `w` (centre `380 + 10·w` nm) is a triangle of 10 nm half-width over the cells'
//! centre wavelengths, normalised to sum 1: a flat spectrum stays flat, and neighbouring
//! bands overlap as a 10 nm bandpass does. The triangle is our choice [I]; the Rev E
//! wavelength re-calibration with its LED (which shifts the mapping) is not implemented.

use super::calibration::{CalibrationError, Filter};
use super::{BANDS, CELLS, START_NM, STEP_NM};

/// Half-width of each band's triangle, nm.
pub const HALF_WIDTH_NM: f64 = 10.0;

/// The centre wavelength of cell `cell` by the cubic `p[0] + p[1]·c + p[2]·c² + p[3]·c³`.
pub fn cell_nm(poly: &[f64; 4], cell: usize) -> f64 {
    let c = cell as f64;
    poly[0] + c * (poly[1] + c * (poly[2] + c * poly[3]))
}

/// The triangular filter for the cell wavelengths `poly` gives. An error names the band
/// that no cell covers (a mapping that does not span 380–730 nm).
pub fn filter_from_poly(poly: &[f64; 4]) -> Result<Filter, CalibrationError> {
    let nm: Vec<f64> = (0..CELLS).map(|c| cell_nm(poly, c)).collect();
    let mut starts = Vec::with_capacity(BANDS);
    let mut coefficients = Vec::with_capacity(BANDS);
    for w in 0..BANDS {
        let centre = START_NM + STEP_NM * w as f64;
        let weights: Vec<(usize, f64)> = nm
            .iter()
            .enumerate()
            .map(|(c, &l)| (c, (1.0 - (l - centre).abs() / HALF_WIDTH_NM).max(0.0)))
            .filter(|&(_, v)| v > 0.0)
            .collect();
        let (Some(first), Some(last)) = (weights.first(), weights.last()) else {
            return Err(CalibrationError::FilterRange {
                band: w,
                start: -1,
                end: -1,
            });
        };
        let sum: f64 = weights.iter().map(|&(_, v)| v).sum();
        let mut c = vec![0.0; last.0 - first.0 + 1];
        for &(cell, v) in &weights {
            c[cell - first.0] = v / sum;
        }
        starts.push(first.0);
        coefficients.push(c);
    }
    Filter::new(starts, coefficients)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_linear_mapping_gives_normalised_triangles_centred_on_each_band() {
        // Cells 5 nm apart from 340 nm: band w (380 + 10w nm) is centred on cell 8 + 2w,
        // and its neighbours at ±5 nm weigh 1 − 5/10 = 0.5 (those at ±10 nm weigh 0), so
        // by hand the weights are 0.5, 1, 0.5 over 2: 0.25, 0.5, 0.25 from cell 7 + 2w.
        let poly = [340.0, 5.0, 0.0, 0.0];
        let f = filter_from_poly(&poly).unwrap();
        for w in 0..BANDS {
            assert_eq!(f.starts()[w], 7 + 2 * w, "{w}");
            assert_eq!(f.coefficients()[w], vec![0.25, 0.5, 0.25], "{w}");
        }
        // A cubic bends the mapping; the weights still sum to 1.
        let f = filter_from_poly(&[343.5, 3.2, -0.0005, 0.0]).unwrap();
        for c in f.coefficients() {
            assert!((c.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn a_mapping_that_misses_the_range_is_refused() {
        let e = filter_from_poly(&[500.0, 1.0, 0.0, 0.0]).unwrap_err();
        assert!(
            matches!(e, CalibrationError::FilterRange { band: 0, .. }),
            "{e}"
        );
    }
}
