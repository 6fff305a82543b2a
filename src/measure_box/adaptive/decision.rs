//! What a round of an adaptive stage decides.

use serde::{Deserialize, Serialize};

use crate::measure_box::plan::Target;

/// What the rounds of a stage decided: the targets of the next round (empty: the stage is
/// complete) and the figure the decision rests on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RoundDecision {
    pub next: Vec<Target>,
    /// Tiles: the unread tiles' predicted effect on the spots, JND. Fall-off: the largest
    /// disagreement of the plausible models at an unread angle, relative luminance.
    pub figure: f64,
    /// Why the stage stops, or what the next round reads.
    pub why: String,
}
