//! Why a session could not start or go on, with what the operator needs to go on.

use std::path::PathBuf;

use crate::session::journal::JournalError;
use crate::session::plan::Prepare;
use crate::session::step::StepFailure;

/// The session could not start or go on.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The journal's directory cannot be made or used (a file stands where it should be).
    #[error(transparent)]
    Dir(#[from] crate::output::OutputError),
    #[error(transparent)]
    Journal(#[from] JournalError),
    #[error("the plan's steps do not serialize to JSON: {0}")]
    Plan(#[source] serde_json::Error),
    #[error("{}, line {line}: {message}", path.display())]
    Entry {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{} was written with {role} instrument {logged}, this session has {now}; resume with the same instrument model, or choose another output directory", path.display())]
    InstrumentDiffers {
        path: PathBuf,
        role: String,
        logged: String,
        now: String,
    },
    /// The same model, but readings taken another way (another unit, speed, integration
    /// time, or a simulation's seed, noise or time scale) would not be comparable.
    #[error("{} was written with {} instrument {} whose {} was {}; this session's is {}; resume with the settings it was started with, or choose another output directory", .0.path.display(), .0.role, .0.model, .0.setting, .0.logged, .0.now)]
    InstrumentSettingDiffers(Box<SettingDiffers>),
    /// The rig cannot take a step of the plan; found before anything is measured.
    #[error("step {} ({label}) {need}; nothing was measured", index + 1)]
    RigLacks {
        index: usize,
        label: String,
        need: String,
    },
    #[error("step {} of {total} ({label}, {prepare}): {source}\n  {done} of {total} steps are safe in {}; fix the cause and resume the session", index + 1, journal.display())]
    Step {
        index: usize,
        total: usize,
        label: String,
        prepare: Prepare,
        done: usize,
        journal: PathBuf,
        source: Box<StepFailure>,
    },
}

impl SessionError {
    /// For a reading that failed midway: the failure, then that the readings before it are
    /// safe in the journal. The caller puts which reading it was in front and how to go on
    /// after, in its own words and options. None for the other errors.
    pub fn safe_so_far(&self) -> Option<String> {
        let SessionError::Step {
            total,
            done,
            journal,
            source,
            ..
        } = self
        else {
            return None;
        };
        Some(format!(
            "{source}\n  {done} of {total} readings are safe in {}",
            journal.display()
        ))
    }
}

/// Which setting of which instrument differs between a journal and the session resuming it.
#[derive(Debug)]
pub struct SettingDiffers {
    pub path: PathBuf,
    pub role: String,
    pub model: String,
    pub setting: String,
    pub logged: String,
    pub now: String,
}
