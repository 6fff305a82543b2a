//! What an adaptive plan did, as the summary records it.

use serde::{Deserialize, Serialize};

use super::choice::StopReason;
use super::rule::Rule;
use crate::display::model::ModelKind;

/// One batch as chosen.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Batch {
    /// Fit readings before it.
    pub after_readings: usize,
    /// The predicted ΔE*ab at the worst target before it.
    pub predicted_de: f64,
    pub model: ModelKind,
    pub patches: Vec<[u8; 3]>,
}

/// How an adaptive plan went; in the summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveReport {
    pub rule: Rule,
    pub targets: usize,
    pub targets_sha256: String,
    /// `auto`: the model was chosen by cross-validation.
    pub auto: bool,
    pub batches: Vec<Batch>,
    pub stop: StopReason,
    /// The predicted ΔE*ab at the worst target when the plan stopped.
    pub predicted_de: f64,
    /// The models fitted at the end, the reference first.
    pub candidates: Vec<ModelKind>,
    pub fit_readings: usize,
    pub verify_patches: usize,
}
