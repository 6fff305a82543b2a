//! Fitting a display model to measured patches: each model takes what it needs (black,
//! primaries, ramps, a grid) and is judged on every patch; diagnostics go with the result.

use std::path::Path;

use sha2::{Digest, Sha256};

use super::diagnostics::{mixed_patches, percentile, repeat_noise, Diagnostics, Noise, Residuals};
use super::model::samples::SortedSamples;
use super::model::Sample;
use super::model::{
    default_grid, default_knots, fit_gog, fit_lut, fit_lut_scattered, fit_matrix_lsq, fit_plcc,
    fit_plcc_gamma, fit_plvc, fit_shaper_matrix, is_measured_grid, DisplayModel, FitError,
    ModelKind, ModelParams,
};
use super::profile::{FittedFrom, Profile, PROFILE_FORMAT};
use crate::color::{delta_e2000, Xyz};

/// Choices beyond the model kind.
#[derive(Clone, Debug, Default)]
pub struct FitOptions {
    /// plcc-gamma: use this exponent for every channel instead of fitting (the paper: 2.2).
    pub gamma: Option<f64>,
    /// The instrument's noise, ΔE00 1σ of one reading, when known; otherwise it is estimated
    /// from repeated patches, if any.
    pub noise_de00: Option<f64>,
}

/// Fits `kind` to `patches`; `source` is the measurement file whose hash the profile records.
pub fn fit_profile(
    kind: ModelKind,
    patches: &[Sample],
    source: Option<&Path>,
) -> Result<Profile, FitError> {
    fit_profile_with(kind, patches, source, &FitOptions::default())
}

/// [`fit_profile`] with options.
pub fn fit_profile_with(
    kind: ModelKind,
    patches: &[Sample],
    source: Option<&Path>,
    options: &FitOptions,
) -> Result<Profile, FitError> {
    check_samples(patches)?;
    let set = SortedSamples::new(patches);
    let params = fit_params(kind, &set, patches, options)?;
    let model = params.model();
    let white = set.white.unwrap_or_else(|| model.forward([1.0; 3]));
    let black = set.black.unwrap_or_else(|| model.forward([0.0; 3]));
    if white[1].is_nan() || white[1] <= 0.0 {
        return Err(FitError::Failed {
            model: kind,
            message: format!("the white has no positive luminance (Y = {})", white[1]),
        });
    }
    let residuals = residuals(model, patches, white);
    let noise = match options.noise_de00 {
        Some(de00) => Some(Noise {
            // A given noise figure does not excuse repeats that disagree.
            disagreeing: repeat_noise(patches, white)
                .map(|n| n.disagreeing)
                .unwrap_or_default(),
            de00,
            source: "given".into(),
        }),
        None => repeat_noise(patches, white),
    };
    let folded = match &params {
        ModelParams::Lut(table) => Some(table.folded_tetrahedra()),
        _ => None,
    };
    let diagnostics = Diagnostics::compute(
        &set,
        kind,
        white,
        residuals.clone(),
        noise,
        mixed_patches(patches),
        folded,
    );
    let input = match source {
        Some(path) => {
            let bytes = std::fs::read(path).map_err(|e| FitError::Io {
                file: path.to_path_buf(),
                source: e,
            })?;
            Some(FittedFrom {
                path: path.display().to_string(),
                sha256: format!("{:x}", Sha256::digest(&bytes)),
                patches: patches.len(),
            })
        }
        None => None,
    };
    Ok(Profile {
        format: PROFILE_FORMAT.into(),
        model: kind,
        parameters: params,
        white_xyz: white,
        black_xyz: black,
        residuals,
        diagnostics,
        input,
    })
}

/// Refuses an empty set and patches with drive values outside 0–1 or non-finite XYZ.
pub fn check_samples(patches: &[Sample]) -> Result<(), FitError> {
    if patches.is_empty() {
        return Err(FitError::NoSamples);
    }
    for (index, p) in patches.iter().enumerate() {
        let ok =
            p.rgb.iter().all(|d| (0.0..=1.0).contains(d)) && p.xyz.iter().all(|v| v.is_finite());
        if !ok {
            return Err(FitError::BadSample {
                index: index + 1,
                rgb: p.rgb,
            });
        }
    }
    Ok(())
}

/// The model's parameters alone, without diagnostics (what cross-validation refits).
pub fn fit_params(
    kind: ModelKind,
    set: &SortedSamples,
    patches: &[Sample],
    options: &FitOptions,
) -> Result<ModelParams, FitError> {
    Ok(match kind {
        ModelKind::Plcc => ModelParams::MatrixTrc(fit_plcc(set)?),
        ModelKind::PlccGamma => ModelParams::MatrixTrc(fit_plcc_gamma(set, options.gamma)?),
        ModelKind::Plvc => ModelParams::Lut(fit_plvc(set)?),
        ModelKind::Gog | ModelKind::Gogo => ModelParams::MatrixTrc(fit_gog(set, kind)?),
        ModelKind::MatrixLsq => ModelParams::MatrixTrc(fit_matrix_lsq(set, patches)?),
        ModelKind::Lut if is_measured_grid(set, patches) => {
            ModelParams::Lut(fit_lut(set, patches)?)
        }
        ModelKind::Lut => ModelParams::Lut(
            fit_lut_scattered(set, patches, default_grid(patches.len()), None)?.lut,
        ),
        ModelKind::ShaperMatrix => ModelParams::MatrixTrc(fit_shaper_matrix(
            set,
            patches,
            default_knots(patches.len()),
        )?),
    })
}

/// ΔE00 (relative to `white`) and XYZ differences between the model and every patch.
pub fn residuals(model: &dyn DisplayModel, patches: &[Sample], white: Xyz) -> Residuals {
    let w = white;
    let mut des = Vec::with_capacity(patches.len());
    let mut sq = 0.0;
    let mut worst = (0.0, [0.0; 3]);
    for p in patches {
        let f = model.forward(p.rgb);
        let e = delta_e2000(f.to_lab(w), p.xyz.to_lab(w));
        sq += (0..3).map(|k| (f[k] - p.xyz[k]).powi(2)).sum::<f64>();
        if e > worst.0 || des.is_empty() {
            worst = (e, p.rgb);
        }
        des.push(e);
    }
    let n = des.len() as f64;
    let mut sorted = des.clone();
    sorted.sort_by(f64::total_cmp);
    let p95 = percentile(&sorted, 0.95);
    Residuals {
        patches: des.len(),
        mean_de00: des.iter().sum::<f64>() / n,
        p95_de00: p95,
        max_de00: worst.0,
        worst_rgb: worst.1,
        rms_xyz: (sq / (3.0 * n)).sqrt(),
    }
}
