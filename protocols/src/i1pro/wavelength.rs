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
        // Cells 3.125 nm apart from 345 nm: band 0 (380 nm) is centred on cell 11.2.
        let poly = [345.0, 3.125, 0.0, 0.0];
        let f = filter_from_poly(&poly).unwrap();
        for w in 0..BANDS {
            let c = &f.coefficients()[w];
            let s = f.starts()[w];
            assert!((c.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            // The weighted mean wavelength is the band centre (a symmetric triangle on an
            // even grid), by hand: Σ c_k λ_k = 380 + 10 w.
            let mean: f64 = c
                .iter()
                .enumerate()
                .map(|(k, v)| v * cell_nm(&poly, s + k))
                .sum();
            assert!((mean - (380.0 + 10.0 * w as f64)).abs() < 1e-9, "{w}: {mean}");
        }
        // Cells within 10 nm of 380: (370, 390) → cells 8.0 (excluded, weight 0) … 14.4.
        assert_eq!(f.starts()[0], 9);
        assert_eq!(f.coefficients()[0].len(), 6);
    }

    #[test]
    fn a_mapping_that_misses_the_range_is_refused() {
        let e = filter_from_poly(&[500.0, 1.0, 0.0, 0.0]).unwrap_err();
        assert!(matches!(e, CalibrationError::FilterRange { band: 0, .. }), "{e}");
    }
}
