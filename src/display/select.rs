//! `--model auto`: k-fold cross-validation over the patches picks the model that predicts
//! patches it was not fitted to best (mean ΔE00), and keeps every candidate's score so the
//! choice can be explained.
//!
//! The patches at the corners of the drive cube (black, primaries, secondaries, white)
//! stay in every training set: the ramp and primary models cannot be fitted without them,
//! and a profile is always fitted with them. Every other patch is held out exactly once.
//! CIELAB is relative to the training set's white, as the fitted profile's would be.

use super::fit::{check_samples, fit_params, FitOptions};
use super::model::samples::{SortedSamples, SAME_DRIVE};
use super::model::{fold_of, FitError, ModelKind, Sample};
use crate::color::{delta_e2000, Xyz};

/// One candidate's cross-validated score, or why it could not be fitted.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate {
    pub model: ModelKind,
    /// Mean ΔE00 over every held-out patch.
    pub cv_mean_de00: Result<f64, String>,
}

/// The chosen model and every candidate's score, in [`ModelKind::ALL`] order.
#[derive(Clone, Debug)]
pub struct Selection {
    pub model: ModelKind,
    pub folds: usize,
    pub held_out: usize,
    pub candidates: Vec<Candidate>,
}

impl std::fmt::Display for Selection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "model selection: {}-fold cross-validation, {} patches held out once each \
             (cube corners always fitted)",
            self.folds, self.held_out
        )?;
        for c in &self.candidates {
            let mark = if c.model == self.model { "*" } else { " " };
            match &c.cv_mean_de00 {
                Ok(de) => writeln!(f, "{mark} {:<14} CV mean ΔE00 {de:.3}", c.model.name())?,
                Err(why) => writeln!(f, "  {:<14} not fitted: {why}", c.model.name())?,
            }
        }
        write!(
            f,
            "chose {}: the lowest cross-validated mean ΔE00",
            self.model
        )
    }
}

/// Cross-validates every model of [`ModelKind::ALL`] with `folds` folds (≥ 2).
pub fn select_model(
    patches: &[Sample],
    folds: usize,
    options: &FitOptions,
) -> Result<Selection, FitError> {
    check_samples(patches)?;
    let folds = folds.max(2);
    let corner = |p: &Sample| {
        p.rgb
            .iter()
            .all(|&d| !(SAME_DRIVE..=1.0 - SAME_DRIVE).contains(&d))
    };
    let rotating: Vec<usize> = (0..patches.len())
        .filter(|&i| !corner(&patches[i]))
        .collect();
    if rotating.len() < folds {
        return Err(FitError::Failed {
            model: ModelKind::ShaperMatrix,
            message: format!(
                "cross-validation needs at least {folds} patches besides the cube's corners \
                 (found {})",
                rotating.len()
            ),
        });
    }
    let fold = |i: usize| fold_of(i) % folds;
    let mut candidates = Vec::new();
    for kind in ModelKind::ALL {
        candidates.push(Candidate {
            model: kind,
            cv_mean_de00: cross_validate(kind, patches, &rotating, folds, &fold, options),
        });
    }
    let best = candidates
        .iter()
        .filter_map(|c| c.cv_mean_de00.as_ref().ok().map(|e| (c.model, *e)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .ok_or_else(|| FitError::Failed {
            model: ModelKind::ShaperMatrix,
            message: format!(
                "no model could be fitted: {}",
                candidates
                    .iter()
                    .map(|c| format!(
                        "{}: {}",
                        c.model,
                        c.cv_mean_de00.as_ref().err().map_or("", String::as_str)
                    ))
                    .collect::<Vec<_>>()
                    .join("; ")
            ),
        })?;
    Ok(Selection {
        model: best.0,
        folds,
        held_out: rotating.len(),
        candidates,
    })
}

fn cross_validate(
    kind: ModelKind,
    patches: &[Sample],
    rotating: &[usize],
    folds: usize,
    fold: &dyn Fn(usize) -> usize,
    options: &FitOptions,
) -> Result<f64, String> {
    let mut held_out = vec![false; patches.len()];
    let mut sum = 0.0;
    let mut count = 0usize;
    for f in 0..folds {
        held_out.iter_mut().for_each(|h| *h = false);
        for &i in rotating {
            held_out[i] = fold(i) == f;
        }
        let train: Vec<Sample> = patches
            .iter()
            .zip(&held_out)
            .filter(|(_, h)| !**h)
            .map(|(p, _)| *p)
            .collect();
        let set = SortedSamples::new(&train);
        let params = fit_params(kind, &set, &train, options).map_err(|e| e.to_string())?;
        let model = params.model();
        let white = Xyz::from_array(set.white.unwrap_or_else(|| model.forward([1.0; 3])));
        for (p, _) in patches.iter().zip(&held_out).filter(|(_, h)| **h) {
            sum += delta_e2000(
                Xyz::from_array(model.forward(p.rgb)).to_lab(white),
                Xyz::from_array(p.xyz).to_lab(white),
            );
            count += 1;
        }
    }
    let mean = sum / count.max(1) as f64;
    if mean.is_finite() {
        Ok(mean)
    } else {
        Err("its predictions are not finite".into())
    }
}
