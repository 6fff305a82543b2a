//! What went wrong, said for the caller to word with its own options: the journal in
//! the way of a measurement, the reading that failed, what is left to measure.

use std::path::PathBuf;

use super::{MeasureBoxError, Outcome};
use crate::measure_box::plan::BoxStage;
use crate::session::{JournalError, RunEnd, SessionError};

/// A stage's journal in the output directory that this measurement cannot continue as
/// asked: what is wrong, for the command to say what to do with its own options.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum JournalConflict {
    /// A journal of an earlier session is there and continuing it was not asked for.
    #[error("stage {stage}: {} exists with {entries} reading(s) of an earlier session", path.display())]
    Earlier {
        stage: BoxStage,
        path: PathBuf,
        entries: usize,
    },
    /// The journal was written by a session with another plan, repeat count or seed.
    #[error("stage {stage}: {} was written by another session: its {option} is {logged}, this one's is {now}", path.display())]
    OtherSession {
        stage: BoxStage,
        path: PathBuf,
        option: String,
        logged: String,
        now: String,
    },
}

impl MeasureBoxError {
    /// The journal in the way, where that is what failed.
    pub fn conflict(&self) -> Option<JournalConflict> {
        let MeasureBoxError::Session { stage, source } = self else {
            return None;
        };
        match source {
            SessionError::Journal(JournalError::Exists { path, entries }) => {
                Some(JournalConflict::Earlier {
                    stage: *stage,
                    path: path.clone(),
                    entries: *entries,
                })
            }
            SessionError::Journal(JournalError::OptionDiffers {
                path,
                option,
                logged,
                now,
            }) => Some(JournalConflict::OtherSession {
                stage: *stage,
                path: path.clone(),
                option: option.clone(),
                logged: logged.clone(),
                now: now.clone(),
            }),
            _ => None,
        }
    }

    /// Which reading failed midway and what is safe (the others are in the journal),
    /// where the session engine's own message cannot say it.
    pub fn advice(&self) -> Option<String> {
        let MeasureBoxError::Session { stage, source } = self else {
            return None;
        };
        match source {
            SessionError::Step {
                index,
                total,
                label,
                prepare,
                ..
            } => Some(format!(
                "stage {stage}, reading {} of {total} ({label}: {prepare}): {}",
                index + 1,
                source.safe_so_far()?
            )),
            _ => None,
        }
    }
}

impl Outcome {
    /// Whether the session was interrupted (Ctrl-C, a signal): a failure to the caller,
    /// though every reading taken is safe.
    pub fn is_interrupted(&self) -> bool {
        matches!(self, Outcome::Incomplete { end, .. } if end.is_interrupted())
    }

    /// What is still to measure, and where the readings taken are; None when finished.
    /// Continuing is the caller's to say, in its own options.
    pub fn left_to_do(&self) -> Option<String> {
        let (stage, end, done, total, log) = match self {
            Outcome::Finished(_) => return None,
            Outcome::StagesMissing(stages) => {
                let names: Vec<&str> = stages.iter().map(|s| s.name()).collect();
                return Some(format!(
                    "stage(s) {} still to measure before the scene can be assembled",
                    names.join(", ")
                ));
            }
            Outcome::Incomplete {
                stage,
                end,
                done,
                total,
                log,
            } => (stage, end, *done, *total, log),
        };
        let text = if done == 0 {
            format!("stage {stage}: none of its {total} readings taken yet")
        } else {
            format!(
                "stage {stage}: {} of {total} readings still to take; the others are safe in {}",
                total - done,
                log.display()
            )
        };
        Some(match end {
            RunEnd::Interrupted { .. } => format!("interrupted: {text}"),
            RunEnd::Aborted { .. } => format!("stopped at your request: {text}"),
            RunEnd::Stopped { .. } | RunEnd::Complete => format!("stopped: {text}"),
        })
    }
}
