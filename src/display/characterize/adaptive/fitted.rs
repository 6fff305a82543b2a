//! The display models fitted to the readings so far, and the error they predict.

use super::choice;
use crate::color::Xyz;
use crate::display::gamut::GamutMapping;
use crate::display::model::samples::SortedSamples;
use crate::display::model::{FitError, ModelKind, ModelParams, Sample};
use crate::display::reproduce::reproduce_targets;
use crate::display::{fit_profile, select_model, FitOptions, Profile};

/// Cross-validation folds of `auto`'s choice.
pub const FOLDS: usize = 5;

/// The models fitted to the readings so far.
pub struct Fitted {
    /// The model the profile will be: the request's, or `auto`'s choice.
    pub model: ModelKind,
    pub reference: Profile,
    /// Every other model of [`ModelKind::ALL`] that could be fitted, fitted to every patch.
    pub candidates: Vec<(ModelKind, ModelParams)>,
    /// The readings they were fitted to.
    pub samples: Vec<Sample>,
    /// How far a candidate may miss the readings near a drive value beyond the reference's
    /// miss and still count there (see [`choice::predicted_error`]).
    pub slack: f64,
}

impl Fitted {
    /// Fits the reference (`model`, or with `auto` the model `fit --model auto` chooses)
    /// and every other model to `samples`; `slack` as [`Fitted::slack`].
    pub fn new(
        samples: &[Sample],
        model: ModelKind,
        auto: bool,
        slack: f64,
    ) -> Result<Fitted, FitError> {
        let model = if auto {
            select_model(samples, FOLDS, &FitOptions::default())?.model
        } else {
            model
        };
        let reference = fit_profile(model, samples, None)?;
        let set = SortedSamples::new(samples);
        let candidates = ModelKind::ALL
            .into_iter()
            .filter(|k| *k != model)
            .filter_map(|k| {
                crate::display::fit::fit_params(k, &set, samples, &FitOptions::default())
                    .ok()
                    .map(|p| (k, p))
            })
            .collect();
        Ok(Fitted {
            model,
            reference,
            candidates,
            samples: samples.to_vec(),
            slack,
        })
    }

    /// The error predicted at drive value `rgb` (see [`choice::predicted_error`]).
    pub fn predicted(&self, rgb: [f64; 3]) -> f64 {
        let models: Vec<&dyn crate::display::DisplayModel> =
            self.candidates.iter().map(|(_, p)| p.model()).collect();
        choice::predicted_error(
            rgb,
            self.reference.model(),
            &models,
            &self.samples,
            self.slack,
            self.reference.white_xyz,
        )
    }

    /// The drive values the reference gives the targets, as the reproduction maps them.
    pub fn target_drives(&self, targets: &[Xyz]) -> Vec<[f64; 3]> {
        reproduce_targets(&self.reference, targets, GamutMapping::default())
            .into_iter()
            .map(|d| d.rgb)
            .collect()
    }
}
