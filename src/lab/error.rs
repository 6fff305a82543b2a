//! Why a lab run failed.

use std::path::PathBuf;

use metamer_drivers::DriverError;

use crate::display::characterize::CharacterizeError;
use crate::display::ProfileError;
use crate::output::OutputError;
use crate::render::spot::SpotError;
use crate::render::SceneError;
use crate::rig::sim_box::SimBoxError;
use crate::rig::ScreenError;
use crate::validation::ValidationError;

/// Why a lab run failed.
#[derive(Debug, thiserror::Error)]
pub enum LabError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Spot(#[from] SpotError),
    #[error(transparent)]
    Box(#[from] SimBoxError),
    #[error("the simulated meter: {0}")]
    Meter(#[from] DriverError),
    #[error(transparent)]
    Display(#[from] ScreenError),
    #[error(transparent)]
    Characterize(#[from] CharacterizeError),
    #[error(transparent)]
    Profile(#[from] ProfileError),
    #[error(transparent)]
    Validation(#[from] ValidationError),
    #[error("the display characterization stopped with {missing} readings missing; resume the lab run to take them")]
    Incomplete { missing: usize },
    #[error("the lab needs a simulated display that a simulated meter can see")]
    NotSimulated,
    #[error("{} holds an earlier lab run; choose another directory or resume that run", dir.display())]
    Exists { dir: PathBuf },
    /// Resuming a finished run with other options: its results answer another question.
    #[error("{} holds a finished lab run whose {option} is {logged}, this one's is {now}; run with the options it was made with, or choose another directory", dir.display())]
    OptionDiffers {
        dir: PathBuf,
        option: String,
        logged: String,
        now: String,
    },
    #[error("{}: not a lab result: {message}", file.display())]
    BadResult { file: PathBuf, message: String },
    #[error("{0}")]
    Output(#[from] OutputError),
}
