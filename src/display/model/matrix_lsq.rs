//! A matrix and black offset fitted over all measured patches, after per-channel TRCs from
//! the measured ramps: XYZ = b + M·[R′ G′ B′]ᵀ in weighted least squares. Where PLCC takes
//! M from three patches, this averages the noise of every patch, and where channels interact
//! mildly it finds the best single matrix. Each patch is weighted by 1 / max(Y, 1 % of
//! white) so that dark patches count by their relative (closer to perceptual) error.

use nalgebra::{DMatrix, DVector};

use super::error::FitError;
use super::plcc::{black_and_primaries, ramp_tables, singular};
use super::samples::Sample;
use super::samples::SortedSamples;
use super::{MatrixTrc, ModelKind};

pub fn fit_matrix_lsq(set: &SortedSamples, patches: &[Sample]) -> Result<MatrixTrc, FitError> {
    let kind = ModelKind::MatrixLsq;
    let (black, m) = black_and_primaries(set, kind)?;
    let trc = ramp_tables(set, kind, black, &m)?;
    let white_y = set
        .white
        .map_or_else(|| black[1] + m[1].iter().sum::<f64>(), |w| w[1]);
    let n = patches.len();
    if n < 4 {
        return Err(FitError::Missing {
            model: kind,
            what: "at least 4 patches for 12 unknowns in 3 equations each".into(),
        });
    }
    let mut a = DMatrix::<f64>::zeros(n, 4);
    let mut rhs = DMatrix::<f64>::zeros(n, 3);
    for (i, p) in patches.iter().enumerate() {
        let w = 1.0 / p.xyz[1].max(0.01 * white_y);
        for c in 0..3 {
            a[(i, c)] = w * trc[c].eval(p.rgb[c]);
            rhs[(i, c)] = w * p.xyz[c];
        }
        a[(i, 3)] = w;
    }
    let svd = a.svd(true, true);
    let mut fitted = [[0.0; 3]; 3];
    let mut offset = [0.0; 3];
    for k in 0..3 {
        let col = DVector::from_iterator(n, rhs.column(k).iter().copied());
        let x = svd.solve(&col, 1e-12).map_err(|e| FitError::Failed {
            model: kind,
            message: format!("least squares failed: {e}"),
        })?;
        for c in 0..3 {
            fitted[k][c] = x[c];
        }
        offset[k] = x[3];
    }
    MatrixTrc::new(kind, offset.into(), fitted, trc).map_err(singular)
}
