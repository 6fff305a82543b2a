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
//!
//! A set with fewer than [`MIN_MIXED`] mixed patches (two or more channels on; the white
//! is a corner) says little about mixtures, which is what a rendering shows: its held-out
//! patches are ramp readings, which judge each channel's curve and nothing else (the
//! paper's and PsychoPy's plans, black, white and ramps, hold no mixture at all). There the
//! measured mixtures decide which candidates may compete: a candidate whose fit misses the
//! measured white by more than the verdict's tolerance plus twice what noise alone makes
//! of that miss is set aside, since its mixtures are not held by the one mixture that was
//! measured. The noise is that of the white against the sum of four readings, propagated
//! from the readings' noise (repeats, or the ramps' smoothness; see
//! [`super::additivity_noise`]), and it is large: one reading per patch with a CS-100A's
//! noise moves a perfectly additive display's check by ΔE00 0.8 rms. The LUT is not a
//! candidate, since between the ramps its colours would be its smoothness prior.
//! Cross-validation then ranks the rest (any greys are held out as usual). Among the
//! candidates within one standard error of the best, the ramps cannot tell which mixes
//! right, and the white can: when its check is known to better than the verdict's
//! tolerance, those whose miss of it is within that noise of the smallest miss remain, and
//! the simplest of them is chosen; otherwise the plain one-standard-error rule applies. On
//! the single-channel patches of 34 DisplayCAL files of real monitors this changed two
//! picks, both for the better (benches/argyll/README.md).

use super::additivity_noise::{check_noise_de00, ramp_noise, repeat_reading_noise, NoiseSource};
use super::diagnostics::{mixed_patches, repeat_noise, Additivity, TOLERANCE_DE00};
use super::fit::{check_samples, fit_params, FitOptions};
use super::model::samples::{SortedSamples, SAME_DRIVE};
use super::model::{fold_of, FitError, ModelKind, Sample};
use crate::color::{delta_e2000, Xyz};

pub use super::diagnostics::MIN_MIXED;

/// One candidate's cross-validated score, or why it could not be fitted.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate {
    pub model: ModelKind,
    /// Mean ΔE00 over every held-out patch.
    pub cv_mean_de00: Result<f64, String>,
    /// Each held-out patch's ΔE00, in the order of the rotating patches (empty if not fitted).
    pub held_out_de00: Vec<f64>,
    /// On a set with few mixtures: ΔE00 between the measured white and the candidate's
    /// white, fitted to every patch.
    pub white_de00: Option<f64>,
    /// Why the candidate does not compete although it was fitted (on a set with few
    /// mixtures).
    pub set_aside: Option<String>,
}

/// What the patch set says about mixtures.
#[derive(Clone, Debug, PartialEq)]
pub struct MixtureEvidence {
    /// Mixed patches (two or more channels on, the white not counted).
    pub mixed: usize,
    /// Fewer than [`MIN_MIXED`] mixed patches: the white decides which candidates compete.
    pub few: bool,
    /// ΔE00 between the measured white and black + the three primaries' contributions
    /// (R + G + B − 2K), when all five were measured.
    pub additivity_de00: Option<f64>,
    /// How far noise alone moves the white against that sum (root mean square ΔE00), with
    /// what the reading noise was estimated from (see [`super::additivity_noise`]).
    pub additivity_noise_de00: Option<(f64, NoiseSource)>,
    /// The largest miss of the white a candidate may have on a set with few mixtures.
    pub allowance_de00: f64,
}

/// The chosen model and every candidate's score, in [`ModelKind::ALL`] order.
#[derive(Clone, Debug)]
pub struct Selection {
    pub model: ModelKind,
    /// The model with the lowest cross-validated mean, when a simpler one within one
    /// standard error of it was chosen instead.
    pub lowest: Option<ModelKind>,
    /// On a set with few mixtures, `lowest` was passed over for a candidate whose fit misses
    /// the measured white less (beyond the white's noise), not for a simpler one.
    pub white_decided: bool,
    pub folds: usize,
    pub held_out: usize,
    pub mixtures: MixtureEvidence,
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
        let m = &self.mixtures;
        if m.few {
            writeln!(
                f,
                "the set holds {} mixed patch{} (fewer than {MIN_MIXED}): held out, its \
                 patches judge the channels' curves, not how they mix; candidates whose fit \
                 misses the measured white by more than ΔE00 {:.2} are set aside{}",
                m.mixed,
                if m.mixed == 1 { "" } else { "es" },
                m.allowance_de00,
                match (m.additivity_de00, m.additivity_noise_de00) {
                    (Some(a), Some((n, source))) => format!(
                        " (the additive sum R+G+B−2K misses it by {a:.2}; the meter's noise, \
                         {source}, moves that by {n:.2} rms)"
                    ),
                    (Some(a), None) => {
                        format!(" (the additive sum R+G+B−2K misses it by {a:.2})")
                    }
                    _ => String::new(),
                }
            )?;
        }
        for c in &self.candidates {
            let mark = if c.model == self.model { "*" } else { " " };
            let white = c
                .white_de00
                .map(|w| format!(", white ΔE00 {w:.2}"))
                .unwrap_or_default();
            match (&c.cv_mean_de00, &c.set_aside) {
                (Ok(de), None) => writeln!(
                    f,
                    "{mark} {:<14} CV mean ΔE00 {de:.3}{white}",
                    c.model.name()
                )?,
                (Ok(de), Some(why)) => writeln!(
                    f,
                    "  {:<14} CV mean ΔE00 {de:.3}{white}: set aside, {why}",
                    c.model.name()
                )?,
                (Err(why), _) => writeln!(f, "  {:<14} not fitted: {why}", c.model.name())?,
            }
        }
        match self.lowest {
            Some(lowest) if self.white_decided => write!(
                f,
                "chose {}: {lowest}'s lower cross-validated mean ΔE00 is within one standard \
                 error of the paired differences, and of the candidates the ramps cannot tell \
                 apart, {} misses the measured white least (within the white's noise)",
                self.model, self.model
            ),
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
    let rotating = rotating_patches(patches, folds)?;
    let fold = |i: usize| fold_of(i) % folds;
    let full = SortedSamples::new(patches);
    let mixtures = mixture_evidence(patches, &full, options);
    let candidates: Vec<Candidate> = ModelKind::ALL
        .into_iter()
        .map(|kind| {
            if mixtures.few && kind == ModelKind::Lut {
                return Candidate {
                    model: kind,
                    cv_mean_de00: Err("not a candidate on a set with few mixed patches: its \
                                       colours between the ramps would be its smoothness \
                                       prior, not a measurement"
                        .into()),
                    held_out_de00: Vec::new(),
                    white_de00: None,
                    set_aside: None,
                };
            }
            let scores = cross_validate(kind, patches, &rotating, folds, &fold, options);
            score(kind, scores, &full, patches, options, &mixtures)
        })
        .collect();
    let (chosen, best, white_decides) = choose(&candidates, &mixtures)?;
    Ok(Selection {
        model: chosen,
        lowest: (chosen != best).then_some(best),
        white_decided: white_decides && chosen != best,
        folds,
        held_out: rotating.len(),
        mixtures,
        candidates,
    })
}

/// The patches that take turns in being held out: all but the cube's corners, which every
/// fit keeps. At least one per fold.
fn rotating_patches(patches: &[Sample], folds: usize) -> Result<Vec<usize>, FitError> {
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
    Ok(rotating)
}

/// What the set says about mixtures: how many it has, how well the measured white is the
/// sum of the channels, with what noise, and the white's allowance that follows.
fn mixture_evidence(
    patches: &[Sample],
    full: &SortedSamples,
    options: &FitOptions,
) -> MixtureEvidence {
    let n_mixed = mixed_patches(patches);
    let white = full.white;
    let sigma = options
        .noise_de00
        .or_else(|| white.and_then(|w| repeat_noise(patches, w).map(|n| n.de00)));
    let reading_noise = repeat_reading_noise(patches).or_else(|| ramp_noise(full));
    let additivity_noise_de00 = white
        .zip(reading_noise)
        .and_then(|(w, n)| check_noise_de00(full, n, w).map(|e| (e, n.source)));
    // Two white readings differ by σ√2, and the white and the sum of four readings by what
    // the ramps' noise propagates to; beyond twice the larger the model, not the meter, is
    // to blame.
    let spread = sigma
        .map(|s| s * 2f64.sqrt())
        .into_iter()
        .chain(additivity_noise_de00.map(|n| n.0))
        .fold(0.0, f64::max);
    MixtureEvidence {
        mixed: n_mixed,
        few: n_mixed < MIN_MIXED,
        additivity_de00: white.and_then(|w| Additivity::check(full, w).map(|a| a.de00)),
        additivity_noise_de00,
        allowance_de00: TOLERANCE_DE00 + 2.0 * spread,
    }
}

/// A candidate of its cross-validation `scores` (mean and per-patch ΔE00): on a set with
/// few mixtures, also how far its fit misses the measured white, and whether that sets it
/// aside.
fn score(
    kind: ModelKind,
    scores: Result<(f64, Vec<f64>), String>,
    full: &SortedSamples,
    patches: &[Sample],
    options: &FitOptions,
    mixtures: &MixtureEvidence,
) -> Candidate {
    let white_de00 = match (&scores, full.white, mixtures.few) {
        (Ok(_), Some(w), true) => fit_params(kind, full, patches, options)
            .ok()
            .map(|p| de(p.model().forward([1.0; 3]), w, w))
            .filter(|e| e.is_finite()),
        _ => None,
    };
    let set_aside = white_de00
        .filter(|&e| e > mixtures.allowance_de00)
        .map(|e| {
            format!(
                "its fit misses the measured white by ΔE00 {e:.2}, more than {:.2}: its \
                 mixtures are not held by the measurements",
                mixtures.allowance_de00
            )
        });
    Candidate {
        model: kind,
        cv_mean_de00: scores.as_ref().map(|s| s.0).map_err(Clone::clone),
        held_out_de00: scores.map(|s| s.1).unwrap_or_default(),
        white_de00,
        set_aside,
    }
}

/// The model chosen, the one of lowest held-out error, and whether the white decided.
fn choose(
    candidates: &[Candidate],
    mixtures: &MixtureEvidence,
) -> Result<(ModelKind, ModelKind, bool), FitError> {
    // Those the white sets aside compete only if it sets aside every candidate.
    let competing: Vec<Candidate> = if candidates
        .iter()
        .any(|c| c.cv_mean_de00.is_ok() && c.set_aside.is_none())
    {
        candidates
            .iter()
            .filter(|c| c.set_aside.is_none())
            .cloned()
            .collect()
    } else {
        candidates.to_vec()
    };
    let best = competing
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
    // The white breaks a tie on the ramps only when it is known to better than a verdict's
    // tolerance: a white whose repeats scatter by more says little about mixtures.
    let white_decides = match mixtures.additivity_noise_de00 {
        Some((noise, _)) if mixtures.few && noise < TOLERANCE_DE00 => Some(noise),
        _ => None,
    };
    let chosen = match white_decides {
        Some(noise) => holding_white_within_one_se(&competing, best.0, noise),
        None => simplest_within_one_se(&competing, best.0),
    };
    Ok((chosen, best.0, white_decides.is_some()))
}

/// ΔE00 between two XYZ, CIELAB relative to `white`.
fn de(a: Xyz, b: Xyz, white: Xyz) -> f64 {
    delta_e2000(a.to_lab(white), b.to_lab(white))
}

/// Fewest free parameters first: a power law, gain-offset-gamma (two, three per channel),
/// the shapers (a power law per channel, knots only where cross-validation keeps them),
/// the ramp tables (one value per measured level) with the primaries' or a fitted matrix,
/// PLVC's tables of XYZ per level, and the LUT with hundreds of nodes.
fn complexity(kind: ModelKind) -> usize {
    match kind {
        ModelKind::PlccGamma => 0,
        ModelKind::Gog => 1,
        ModelKind::Gogo => 2,
        ModelKind::ShaperMatrix => 3,
        ModelKind::Plcc => 4,
        ModelKind::MatrixLsq => 5,
        ModelKind::Plvc => 6,
        ModelKind::Lut => 7,
    }
}

/// The simplest candidate whose held-out errors exceed the best's by less than one
/// standard error of their paired differences; `best` if none is simpler.
fn simplest_within_one_se(candidates: &[Candidate], best: ModelKind) -> ModelKind {
    tied_with(candidates, best)
        .into_iter()
        .min_by_key(|c| complexity(c.model))
        .map_or(best, |c| c.model)
}

/// The scored candidates within one standard error of `best` (it among them); none when
/// `best` is not a candidate.
fn tied_with(candidates: &[Candidate], best: ModelKind) -> Vec<&Candidate> {
    let Some(top) = candidates.iter().find(|c| c.model == best) else {
        return Vec::new();
    };
    candidates
        .iter()
        .filter(|c| c.cv_mean_de00.is_ok() && within_one_se(c, top))
        .collect()
}

/// Whether `c`'s held-out errors exceed `top`'s by less than one standard error of their
/// paired differences.
fn within_one_se(c: &Candidate, top: &Candidate) -> bool {
    let n = top.held_out_de00.len();
    if c.model == top.model {
        return true;
    }
    if c.held_out_de00.len() != n || n < 2 {
        return false;
    }
    let d: Vec<f64> = c
        .held_out_de00
        .iter()
        .zip(&top.held_out_de00)
        .map(|(a, b)| a - b)
        .collect();
    let mean = d.iter().sum::<f64>() / n as f64;
    let var = d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    mean <= (var / n as f64).sqrt()
}

/// On a set with few mixtures: among the candidates the held-out ramps cannot tell from the
/// best (within one standard error), those whose miss of the measured white is within
/// `noise` of the smallest miss, and of those the simplest.
fn holding_white_within_one_se(candidates: &[Candidate], best: ModelKind, noise: f64) -> ModelKind {
    let tied = tied_with(candidates, best);
    let miss = |c: &Candidate| c.white_de00.unwrap_or(f64::INFINITY);
    let least = tied.iter().map(|c| miss(c)).fold(f64::INFINITY, f64::min);
    tied.iter()
        .filter(|c| miss(c) <= least + noise)
        .min_by_key(|c| complexity(c.model))
        .map_or(best, |c| c.model)
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
        let white = set.white.unwrap_or_else(|| model.forward([1.0; 3]));
        for (i, p) in patches.iter().enumerate().filter(|(i, _)| held_out[*i]) {
            let e = delta_e2000(model.forward(p.rgb).to_lab(white), p.xyz.to_lab(white));
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
            white_de00: None,
            set_aside: None,
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

    /// By hand: plcc minus plvc per patch is 0.02, −0.02, 0.02: mean 0.00667, standard error
    /// √(0.000533/3) = 0.0133, so the ramps cannot tell them apart. plcc misses the white by
    /// 0.37, plvc by 0: with the white's noise at 0.27 plcc's miss is beyond it and PLVC is
    /// chosen although plcc is simpler (and whichever of the two scored lower); at 0.5 the
    /// two hold the white alike and the simpler plcc is chosen. A candidate the ramps do
    /// tell apart (matrix-lsq, 0.4 worse on each) is not chosen for holding the white.
    #[test]
    fn on_few_mixtures_the_white_breaks_a_tie_on_the_ramps() {
        let with_white = |model, de: &[f64], white| Candidate {
            white_de00: Some(white),
            ..candidate(model, de)
        };
        let plvc = with_white(ModelKind::Plvc, &[0.50, 0.60, 0.70], 0.0);
        let plcc = with_white(ModelKind::Plcc, &[0.52, 0.58, 0.72], 0.37);
        let far = with_white(ModelKind::MatrixLsq, &[0.9, 1.0, 1.1], 0.0);
        let all = [plvc, plcc, far];
        for lowest in [ModelKind::Plvc, ModelKind::Plcc] {
            assert_eq!(
                holding_white_within_one_se(&all, lowest, 0.27),
                ModelKind::Plvc
            );
            assert_eq!(
                holding_white_within_one_se(&all, lowest, 0.5),
                ModelKind::Plcc
            );
        }
    }
}
