//! Why an experiment stopped.

use std::path::PathBuf;

use metamer_drivers::DriverError;

use super::cache::CacheError;
use super::readings::ReadingsError;
use crate::display::characterize::{CharacterizeError, SimulatedMeterOnRealScreen};
use crate::display::ProfileError;
use crate::image::ImageError;
use crate::render::image::ImageRenderError;
use crate::render::radiosity::RadiosityError;
use crate::render::spot::SpotError;
use crate::render::SceneError;
use crate::rig::{OpenError, ScreenError};
use crate::session::{OperatorError, SessionError};
use crate::validation::ValidationError;

#[derive(Debug, thiserror::Error)]
pub enum ExperimentError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Spot(#[from] SpotError),
    #[error(transparent)]
    Radiosity(#[from] RadiosityError),
    #[error(transparent)]
    Image(#[from] ImageRenderError),
    #[error(transparent)]
    ImageIo(#[from] ImageError),
    #[error(transparent)]
    Instrument(#[from] DriverError),
    #[error(transparent)]
    Screen(#[from] ScreenError),
    #[error(transparent)]
    OpenScreen(#[from] OpenError),
    #[error(transparent)]
    Characterize(#[from] CharacterizeError),
    #[error(transparent)]
    Profile(#[from] ProfileError),
    #[error(transparent)]
    Session(#[from] SessionError),
    #[error(transparent)]
    Operator(#[from] OperatorError),
    #[error(transparent)]
    Validation(#[from] ValidationError),
    #[error(transparent)]
    Cache(#[from] CacheError),
    #[error(transparent)]
    Readings(#[from] ReadingsError),
    #[error("{}: {source}", file.display())]
    Io {
        file: PathBuf,
        source: std::io::Error,
    },
    #[error("writing JSON: {0}")]
    Json(#[source] serde_json::Error),
    #[error("{}: {message}", file.display())]
    BadFile { file: PathBuf, message: String },
    #[error("{what}: {message}")]
    Option { what: &'static str, message: String },
    #[error("{what} is not a finite number")]
    NotFinite { what: String },
    #[error("the {stage} stage stopped with {done} of {total} readings taken; they are safe in {}; resume the experiment to take the rest", journal.display())]
    Incomplete {
        stage: &'static str,
        done: usize,
        total: usize,
        journal: PathBuf,
    },
    #[error(transparent)]
    SimulatedMeterOnRealScreen(#[from] SimulatedMeterOnRealScreen),
    /// Ctrl-C while a stage that takes no readings ran: its work was cut short and not
    /// recorded, so the next run does it again.
    #[error("interrupted in the {stage} stage, which was stopped and not recorded; run the experiment again to redo it (the stages before it are kept)")]
    Interrupted { stage: &'static str },
    /// Ctrl-C between stages: the finished ones are kept.
    #[error("interrupted before the {stage} stage began; the stages before it are finished and kept: run the experiment again to continue")]
    InterruptedBefore { stage: &'static str },
    /// Another renderer's image does not fit the scene's camera.
    #[error(transparent)]
    ReadBack(#[from] crate::render::spot::cone::ReadBackError),
    /// Another renderer's image lies where the simulation stage writes its own copy.
    #[error("the simulation's image {}: lies in the simulation stage's directory {}, which the experiment replaces: copy it elsewhere and give that copy", file.display(), dir.display())]
    ImageInStage { file: PathBuf, dir: PathBuf },
    #[error("the display's white is {white_cd_m2:.1} cd/m², but the rendering needs at least {needed_cd_m2:.1} cd/m² to be shown without tone mapping: raise the monitor's brightness (backlight) until full white reads at least that, then move {} aside and run the display stage again", dir.display())]
    DisplayTooDim {
        white_cd_m2: f64,
        needed_cd_m2: f64,
        dir: PathBuf,
    },
    #[error("the {stage} stage needs {}, which an earlier stage writes; run the experiment without choosing a stage first", missing.display())]
    MissingInput {
        stage: &'static str,
        missing: PathBuf,
    },
    #[error("the box's {what} {} does not exist (given as measured earlier or elsewhere)", file.display())]
    GivenBoxMissing { what: &'static str, file: PathBuf },
    #[error("the box measurements: {0}")]
    Box(String),
    /// A user's file lies where a stage of this run writes (or moves its directory aside).
    #[error("the box's {what} {} lie in the {stage} stage's directory {}, which the experiment replaces: copy them elsewhere and give that copy", file.display(), dir.display())]
    GivenInStage {
        what: &'static str,
        file: PathBuf,
        stage: &'static str,
        dir: PathBuf,
    },
    #[error("the box's spot readings {} are of patches {read:?}, but its scene {} has patches {in_scene:?}: the simulation renders the scene's patches and the validation compares each with the box's reading, so both must list the same", spots.display(), scene.display())]
    GivenPatchesDiffer {
        spots: PathBuf,
        read: Vec<usize>,
        scene: PathBuf,
        in_scene: Vec<usize>,
    },
}
