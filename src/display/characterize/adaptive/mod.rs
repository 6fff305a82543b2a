//! The adaptive characterization plan: a first pass (black, the primaries, white, the
//! ramps, a sparse 3³ grid and the key patches read again), then batches of patches where
//! the candidate display models disagree most at and around the colours to reproduce,
//! until the error predicted at those colours is below a stated figure or a cap on
//! readings is reached; then a held-out set at and around them.
//!
//! The predicted error is the disagreement of the display models fitted to the readings
//! so far: the largest ΔE*ab between the reference model's colour (the requested model, or
//! `auto`'s choice) and another model's, leaving out a model the readings near that colour
//! contradict ([`choice::predicted_error`]). Every choice is a
//! function of the readings already journalled, the targets and the rule ([`Rule`], its
//! seed included), so a resumed session and a re-run choose the same patches; the first
//! journal's fingerprint covers the rule and the targets' SHA-256. Each batch has its own
//! journal (`log.batch-N.jsonl`, the held-out set `log.verify.jsonl`) beside `log.jsonl`
//! ([`run`]).

pub mod choice;
pub mod fitted;
pub mod report;
pub mod rule;
pub mod run;

pub use choice::{Decision, StopReason};
pub use fitted::Fitted;
pub use report::{AdaptiveReport, Batch};
pub use rule::{
    read_targets, Adaptive, AdaptiveError, Rule, DEFAULT_BATCH, DEFAULT_MAX_READINGS,
    DEFAULT_STOP_DE, MAX_TARGETS,
};
pub use run::run;
