//! `--model auto`: k-fold cross-validation over the patches picks the model that predicts
//! patches it was not fitted to best (mean ΔE00), and keeps every candidate's score so the
//! choice can be explained.
//!
//! The patches at the corners of the drive cube (black, primaries, secondaries, white)
//! stay in every training set: the ramp and primary models cannot be fitted without them,
//! and a profile is always fitted with them. Every other patch is held out exactly once.
//! CIELAB is relative to the training set's white, as the fitted profile's would be.
//!
//! The held-out readings carry the meter's noise, so two models whose scores differ by
//! less than that noise allows are not told apart by them: then the simpler model is
//! chosen (the one-standard-error rule), since the one with more freedom is as likely to
//! have followed the noise. The standard error is that of the paired per-patch differences.

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
    /// Each held-out patch's ΔE00, in the order of the rotating patches (empty if not fitted).
    pub held_out_de00: Vec<f64>,
}

/// The chosen model and every candidate's score, in [`ModelKind::ALL`] order.
#[derive(Clone, Debug)]
pub struct Selection {
    pub model: ModelKind,
    /// The model with the lowest cross-validated mean, when a simpler one within one
    /// standard error of it was chosen instead.
    pub lowest: Option<ModelKind>,
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
        match self.lowest {
            Some(lowest) => write!(
                f,
                "chose {}: simpler than {lowest}, whose lower cross-validated mean ΔE00 is \
                 within one standard error of the paired differences",
                self.model
            ),
            None => write!(
                f,
                "chose {}: the lowest cross-validated mean ΔE00",
                self.model
            ),
        }
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
        let scores = cross_validate(kind, patches, &rotating, folds, &fold, options);
        candidates.push(Candidate {
            model: kind,
            cv_mean_de00: scores.as_ref().map(|s| s.0).map_err(Clone::clone),
            held_out_de00: scores.map(|s| s.1).unwrap_or_default(),
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
    let chosen = simplest_within_one_se(&candidates, best.0);
    Ok(Selection {
        model: chosen,
        lowest: (chosen != best.0).then_some(best.0),
        folds,
        held_out: rotating.len(),
        candidates,
    })
}

/// Fewest free parameters first: a power law, gain-offset-gamma (two, three per channel),
/// the ramp-interpolating TRCs with the primaries' or a fitted matrix, the knotted shapers,
/// and the LUT with thousands of nodes.
fn complexity(kind: ModelKind) -> usize {
    match kind {
        ModelKind::PlccGamma => 0,
        ModelKind::Gog => 1,
        ModelKind::Gogo => 2,
        ModelKind::Plcc => 3,
        ModelKind::MatrixLsq => 4,
        ModelKind::ShaperMatrix => 5,
        ModelKind::Plvc => 6,
        ModelKind::Lut => 7,
    }
}

/// The simplest candidate whose held-out errors exceed the best's by less than one
/// standard error of their paired differences; `best` if none is simpler.
fn simplest_within_one_se(candidates: &[Candidate], best: ModelKind) -> ModelKind {
    let Some(top) = candidates.iter().find(|c| c.model == best) else {
        return best;
    };
    let n = top.held_out_de00.len();
    let mut pick = best;
    for c in candidates {
        if complexity(c.model) >= complexity(pick) || c.held_out_de00.len() != n || n < 2 {
            continue;
        }
        let d: Vec<f64> = c
            .held_out_de00
            .iter()
            .zip(&top.held_out_de00)
            .map(|(a, b)| a - b)
            .collect();
        let mean = d.iter().sum::<f64>() / n as f64;
        let var = d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        if mean <= (var / n as f64).sqrt() {
            pick = c.model;
        }
    }
    pick
}

fn cross_validate(
    kind: ModelKind,
    patches: &[Sample],
    rotating: &[usize],
    folds: usize,
    fold: &dyn Fn(usize) -> usize,
    options: &FitOptions,
) -> Result<(f64, Vec<f64>), String> {
    let mut per_patch = vec![f64::NAN; patches.len()];
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
        for (i, p) in patches.iter().enumerate().filter(|(i, _)| held_out[*i]) {
            let e = delta_e2000(
                Xyz::from_array(model.forward(p.rgb)).to_lab(white),
                Xyz::from_array(p.xyz).to_lab(white),
            );
            per_patch[i] = e;
            sum += e;
            count += 1;
        }
    }
    let mean = sum / count.max(1) as f64;
    if mean.is_finite() {
        Ok((mean, rotating.iter().map(|&i| per_patch[i]).collect()))
    } else {
        Err("its predictions are not finite".into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn candidate(model: ModelKind, de: &[f64]) -> Candidate {
        Candidate {
            model,
            cv_mean_de00: Ok(de.iter().sum::<f64>() / de.len() as f64),
            held_out_de00: de.to_vec(),
        }
    }

    /// By hand: shaper-matrix minus lut per patch is 0.01, −0.01, 0.02: mean 0.00667,
    /// sample variance 0.000233, standard error √(0.000233/3) = 0.0088 > 0.00667, so the
    /// simpler shaper-matrix is chosen. With differences of 0.4 each (no scatter) the lut
    /// is kept.
    #[test]
    fn the_simpler_model_wins_only_within_one_standard_error() {
        let lut = candidate(ModelKind::Lut, &[0.1, 0.2, 0.3]);
        let close = candidate(ModelKind::ShaperMatrix, &[0.11, 0.19, 0.32]);
        assert_eq!(
            simplest_within_one_se(&[lut.clone(), close], ModelKind::Lut),
            ModelKind::ShaperMatrix
        );
        let far = candidate(ModelKind::ShaperMatrix, &[0.5, 0.6, 0.7]);
        assert_eq!(
            simplest_within_one_se(&[lut, far], ModelKind::Lut),
            ModelKind::Lut
        );
    }
}
