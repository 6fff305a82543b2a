//! The box measured adaptively: the tiles and the fall-off read in rounds, each round
//! chosen from the readings before it, until what is not read cannot move the verdicts.
//!
//! - **Tiles**: first the centre, the corners and the edge midpoints (the 3 × 3 subset of
//!   the grid: the smallest symmetric set that fixes the six terms of the quadratic
//!   spatial model, [`spatial`], with three to spare for its leave-one-out residual, and
//!   one that bounds the panel so every other tile is interpolated, not extrapolated).
//!   Then, one tile a round, the unread tile whose predicted error (the tiles' scatter
//!   about the model, widened by the fit's leverage there) weighted by its direct share
//!   of a patch's light is largest, until the unread tiles together move no spot by more
//!   than [`AdaptiveRule::tile_effect_jnd`] JND, or [`AdaptiveRule::max_tiles`] are read.
//!   Unread tiles take the model's spectrum, band by band.
//! - **Fall-off**: first the normal and every second angle of the plan outwards from its
//!   outermost on each side (0°, ±40°, ±80° of the paper's ±20° steps), the normal read
//!   once: it is one direction whatever the C-plane, and the fit takes it in both. Then, one angle a
//!   round, the plan's unread angle where the distribution models the fit finds plausible
//!   ([`angles`]) disagree most, until they agree within
//!   [`AdaptiveRule::angle_agreement`] of the normal luminance everywhere, or
//!   [`AdaptiveRule::max_falloff`] angles are read.
//!
//! Each round is a journal of its own (`tiles.jsonl`, then `tiles.batch-1.jsonl`, …), a
//! session whose steps are a pure function of the journals before it and the plan (whose
//! JSON, the rule with it, is in every journal's options, so its fingerprint): a resume,
//! or a re-run, walks the journals in order, finds the same rounds and continues the
//! first incomplete one. A simulated instrument's noise in round j is drawn from j·2¹⁶
//! onwards, so no two readings of a stage share it.

pub mod angles;
pub mod decision;
pub mod rule;
pub mod shifted;
pub mod spatial;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use decision::RoundDecision;
pub use rule::AdaptiveRule;

use super::plan::{BoxPlan, BoxStage, BoxStep, Plane};
use crate::session::Entry;

/// Round `j`'s journal of `stage` in `dir`: the first pass is the stage's own journal.
pub fn round_journal(dir: &Path, stage: BoxStage, j: usize) -> PathBuf {
    if j == 0 {
        stage.journal(dir)
    } else {
        dir.join(format!("{}.batch-{j}.jsonl", stage.name()))
    }
}

/// Every journal of an earlier measurement of `stage` in `dir` beyond the first, in
/// order: those a measurement of the stage again sets aside with it.
pub fn later_rounds(dir: &Path, stage: BoxStage) -> Vec<PathBuf> {
    (1..)
        .map(|j| round_journal(dir, stage, j))
        .take_while(|p| p.exists())
        .collect()
}

/// The next round of adaptive stage `stage` after the entries `taken` (every round's so
/// far): a pure function of them and the plan.
pub fn next_round(
    plan: &BoxPlan,
    rule: &AdaptiveRule,
    stage: BoxStage,
    taken: &[Entry<BoxStep>],
) -> RoundDecision {
    match stage {
        BoxStage::Tiles => spatial::choose(plan, rule, taken),
        BoxStage::Falloff => angles::choose(plan, rule, taken),
        _ => RoundDecision {
            next: Vec::new(),
            figure: 0.0,
            why: "read in one round".into(),
        },
    }
}

/// How the adaptive plan went, for the summary and the scene's provenance.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveSummary {
    /// The tiles read, [row, col].
    pub tiles_read: Vec<[usize; 2]>,
    /// The tiles that take the spatial model's spectrum.
    pub tiles_predicted: Vec<[usize; 2]>,
    /// The last decision of the tiles' rounds.
    pub tiles: RoundDecision,
    pub tile_rounds: usize,
    /// The fall-off angles read, (plane, signed degrees).
    pub falloff_read: Vec<(Plane, f64)>,
    pub falloff: RoundDecision,
    pub falloff_rounds: usize,
    pub rule: AdaptiveRule,
}
