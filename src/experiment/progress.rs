//! What an experiment reports as it goes.

use super::stage::Stage;

/// Where an experiment is, for a progress display.
#[derive(Clone, Debug)]
pub enum Progress {
    /// A stage begins (or is re-used).
    Stage { stage: Stage, reused: bool },
    /// Readings done of a measuring stage.
    Readings { done: usize, total: usize },
    /// A line for the user.
    Note(String),
}
