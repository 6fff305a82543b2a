//! The experiment as one call: what `metamer experiment` (and the lab, its preset) asks,
//! the checks made before the first stage in the order a user meets them, the options the
//! stages read, and what the run leaves for the caller to show.

use std::path::{Path, PathBuf};

use metamer_drivers::{DriverError, Spec};

use super::display::DisplayOptions;
use super::display_spots::SpotsShown;
use super::error::ExperimentError;
use super::measure_box::MeasureBox;
use super::measuring::{nominal_white, MeasuringPlan};
use super::options::{BoxSource, ExperimentOptions};
use super::progress::Progress;
use super::readings::{read_readings, ReadingSet, ReadingsError};
use super::reproduction::ReproductionOptions;
use super::run::{run, StageOutcome};
use super::simulation::SimulationOptions;
use super::stage::Stage;
use super::validate::{ValidationResult, FILE as COMPARISONS_FILE};
use crate::measure_box::setup::{box_light, BoxLightError};
use crate::render::{Scene, SceneError};
use crate::rig::Scenario;
use crate::session::{NobodyAtTheRig, RunOptions};
use crate::validation::export::HTML_FILE;
use crate::validation::sequential::RepeatRule;

/// The spot meter of `metamer experiment` when `--spot` is not given: the simulated CS-100A
/// at once, so the experiment runs on the simulated rig with no flags.
pub const DEFAULT_SPOT: &str = "sim:cs100a?time_scale=0";

/// The largest camera image the experiment renders, a side in pixels.
pub const MAX_IMAGE_SIZE: usize = 8192;

/// Where the box's measurements come from, as asked.
#[derive(Clone, Debug)]
pub enum BoxRequest {
    /// Measure the box here with these instruments (both simulated: the simulated box).
    Measure {
        spectral: Spec,
        /// The spot meter that reads the box's fall-off and spots.
        spot: Spec,
        /// A plan file; None: the paper's plan.
        plan: Option<PathBuf>,
        /// Readings per target; None: the plan's.
        repeats: Option<usize>,
        /// Read the tiles and the fall-off adaptively.
        adaptive: bool,
        /// How each spot is read where the plan file names no rule (the measuring plan's
        /// [`box_spot_rule`](super::measuring::Measures::box_spot_rule)); a width rule's CIELAB is relative to the
        /// plan file's `spot_white`, or else a simulated monitor's nominal white
        /// ([`super::measuring::nominal_white`]).
        spot_rule: Option<RepeatRule>,
        /// The simulated box's seed (and its instruments').
        seed: u64,
        /// The simulated box's light, refused with real instruments, whose box has its own
        /// light ([`box_light`]). None on a simulated rig: the default light.
        light: Option<Scenario>,
    },
    /// The box measured earlier or elsewhere: its measured scene and spot readings.
    Given { scene: PathBuf, spots: PathBuf },
}

/// What an experiment is asked: the stages' options before the checks and defaults the
/// library applies ([`Request::run`]).
#[derive(Clone, Debug)]
pub struct Request {
    /// Each stage writes into its own subdirectory of this.
    pub dir: PathBuf,
    /// The measuring plan the options below were expanded from
    /// ([`MeasuringPlan::expand`]), recorded in each stage's record; the options, not the
    /// name, are what the stages' hashes cover.
    pub measuring: MeasuringPlan,
    pub box_source: BoxRequest,
    pub simulation: SimulationOptions,
    /// The monitor, the meter that reads it, and the display model. The command reads the
    /// display with the box's spot meter; the lab gives that meter its own seed, so its
    /// noise is independent of the box readings'.
    pub display: DisplayOptions,
    pub reproduction: ReproductionOptions,
    /// Spot readings averaged per patch on the display: with `until_decided`, the most.
    pub repeats: usize,
    /// Read each patch on the display until its ΔE*ab against the box is decided, this
    /// margin beyond the JND; None: always `repeats` readings.
    pub until_decided: Option<f64>,
    /// How each patch is put in front of the meter on the display: the paper's aimed
    /// image, the image moved under a meter that stays put, or each patch full-screen.
    pub spots_shown: SpotsShown,
    /// Another run's folder, measured with another plan on the same rig: the report's
    /// cost section sets its measuring cost and accuracy beside this run's, from its saved
    /// files alone.
    pub compare_with: Option<PathBuf>,
    /// Run only this stage (again, even if its inputs are unchanged).
    pub stage: Option<Stage>,
    /// Every stage again, one at a time, even those whose inputs are unchanged (earlier
    /// measurements are moved aside, never deleted): the lab's `--force`; the command
    /// `experiment` re-runs a single stage with [`Request::stage`] instead.
    pub rerun_all: bool,
    /// Continue an interrupted measuring stage from its journal.
    pub resume: bool,
    /// Nobody at the rig: take every reading without asking anyone. Without it and without
    /// a terminal on stdin, a real instrument is refused before any stage runs.
    pub unattended: bool,
    pub run: RunOptions,
}

/// How an experiment went.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Each stage run or re-used, in order.
    pub stages: Vec<StageOutcome>,
    /// The box's spot readings when the box was given as files (its stage then neither
    /// ran nor was re-used).
    pub given_box: Option<PathBuf>,
    /// The validation's result as its stage left it in the directory (this run's or an
    /// earlier one's); None when there is none or it cannot be read.
    pub validation: Option<ValidationResult>,
    /// The validation report, when it exists.
    pub report: Option<PathBuf>,
    /// Each measuring stage's budget before its first reading and what it took, as the
    /// stage's files keep them (a stage they keep none for: its plan's budget, nothing
    /// taken).
    pub budget: Vec<super::budget::StageBudget>,
}

impl Outcome {
    /// The validation's three comparisons in a line each, in the report's words.
    pub fn comparison_lines(&self) -> Vec<String> {
        self.validation
            .iter()
            .flat_map(|v| {
                [
                    &v.display_vs_box,
                    &v.simulation_vs_box,
                    &v.display_vs_simulation,
                ]
                .map(|c| c.summary())
            })
            .collect()
    }
}

/// `--target-de`: a ΔE*ab the simulation can reach.
pub(super) fn check_target_de(target_de: f64) -> Result<(), RequestError> {
    if target_de > 0.0 && target_de.is_finite() {
        Ok(())
    } else {
        Err(RequestError::TargetDe)
    }
}

/// A verdict rule on the display's patches: its margin below the JND and at least two
/// readings to stop at.
pub(super) fn check_until_decided(margin: Option<f64>, repeats: usize) -> Result<(), RequestError> {
    let Some(margin) = margin else {
        return Ok(());
    };
    RepeatRule::Verdict {
        margin,
        most: repeats,
    }
    .check(crate::measure_box::plan::MAX_REPEATS)
    .map_err(RequestError::UntilDecided)
}

/// Readings per patch on the display: as many as a box plan allows a reading of one thing
/// (a billion was accepted and measured for days).
pub(super) fn check_repeats(repeats: usize) -> Result<(), RequestError> {
    let most = crate::measure_box::plan::MAX_REPEATS;
    if (1..=most).contains(&repeats) {
        Ok(())
    } else {
        Err(RequestError::Repeats { most, got: repeats })
    }
}

pub(super) fn check_image_size(size: usize) -> Result<(), RequestError> {
    if size > MAX_IMAGE_SIZE {
        Err(RequestError::ImageSize)
    } else {
        Ok(())
    }
}

/// The output directory may be new, but not a file.
pub(super) fn check_dir(dir: &Path) -> Result<(), RequestError> {
    if dir.exists() && !dir.is_dir() {
        Err(RequestError::OutNotDir(dir.to_path_buf()))
    } else {
        Ok(())
    }
}

impl Request {
    /// Checks the request, then runs the stages in order into [`Request::dir`], re-using
    /// each whose inputs are unchanged. The checks run in a fixed order and the first
    /// failure is the one reported: the numbers and the output directory, then what the
    /// stages would read or open only after minutes of work (a given box's files, the
    /// instruments' specs), the box's light, and a real instrument with nobody at the rig.
    ///
    /// # Examples
    ///
    /// The box stage alone on the simulated rig, one reading per target:
    ///
    /// ```
    /// use metamer::display::gamut::GamutMapping;
    /// use metamer::display::ModelKind;
    /// use metamer::experiment::display::DisplayOptions;
    /// use metamer::experiment::reproduction::ReproductionOptions;
    /// use metamer::experiment::simulation::SimulationOptions;
    /// use metamer::experiment::{BoxRequest, Request, Stage};
    /// use metamer::session::RunOptions;
    /// use metamer_drivers::Spec;
    ///
    /// let dir = std::env::temp_dir().join(format!("metamer-doc-experiment-{}", std::process::id()));
    /// let meter = Spec::new("sim:cs100a?time_scale=0");
    /// let request = Request {
    ///     dir: dir.clone(),
    ///     measuring: Default::default(),
    ///     box_source: BoxRequest::Measure {
    ///         spectral: Spec::new("sim:i1pro?time_scale=0"),
    ///         spot: meter.clone(),
    ///         plan: None,
    ///         repeats: Some(1),
    ///         adaptive: false,
    ///         spot_rule: None,
    ///         seed: 1,
    ///         light: None,
    ///     },
    ///     simulation: SimulationOptions::new(0.1, 1, 0, 16, None),
    ///     display: DisplayOptions { screen: "virtual:ips-lcd".parse()?, spot: meter, model: ModelKind::Lut, adaptive: None },
    ///     reproduction: ReproductionOptions { gamut: GamutMapping::NearestLab, mirror: true },
    ///     repeats: 3,
    ///     until_decided: None,
    ///     spots_shown: Default::default(),
    ///     compare_with: None,
    ///     stage: Some(Stage::Box),
    ///     rerun_all: false,
    ///     resume: false,
    ///     unattended: true,
    ///     run: RunOptions::default(),
    /// };
    /// let outcome = request.run(&|_| {})?;
    /// assert_eq!(outcome.stages.len(), 1);
    /// assert!(dir.join("box/scene.json").exists());
    /// # std::fs::remove_dir_all(&dir).ok();
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn run(&self, progress: &dyn Fn(Progress)) -> Result<Outcome, RequestError> {
        let options = self.options()?;
        let stages = if self.rerun_all {
            let mut all = Vec::new();
            for stage in Stage::ALL {
                if self.stage.is_some_and(|s| s != stage) {
                    continue;
                }
                let one = ExperimentOptions {
                    stage: Some(stage),
                    ..options.clone()
                };
                all.extend(run(&one, progress)?);
            }
            all
        } else {
            run(&options, progress)?
        };
        let validation = self.dir.join(Stage::Validation.name());
        let report = validation.join(HTML_FILE);
        let budget = super::budget::recorded(&self.dir, &super::budget::budget(&options));
        Ok(Outcome {
            budget,
            stages,
            given_box: match &self.box_source {
                BoxRequest::Given { spots, .. } => Some(spots.clone()),
                BoxRequest::Measure { .. } => None,
            },
            validation: std::fs::read_to_string(validation.join(COMPARISONS_FILE))
                .ok()
                .and_then(|text| serde_json::from_str(&text).ok()),
            report: report.exists().then_some(report),
        })
    }

    /// The checks, in order, and the options every stage reads.
    pub(crate) fn options(&self) -> Result<ExperimentOptions, RequestError> {
        check_target_de(self.simulation.target_de)?;
        check_repeats(self.repeats)?;
        if let Some(image) = &self.simulation.image {
            check_image_size(image.size)?;
            if image.spp == 0 {
                return Err(RequestError::ImageSpp);
            }
        }
        check_dir(&self.dir)?;
        check_until_decided(self.until_decided, self.repeats)?;
        if let Some(d) = self.compare_with.as_ref().filter(|d| !d.is_dir()) {
            return Err(RequestError::CompareWith(d.clone()));
        }
        let given_readings = self.check_inputs()?;
        let box_source = match &self.box_source {
            BoxRequest::Given { scene, spots } => BoxSource::Existing {
                scene: scene.clone(),
                spots: spots.clone(),
            },
            BoxRequest::Measure {
                spectral,
                spot,
                plan,
                repeats,
                adaptive,
                spot_rule,
                seed,
                light,
            } => BoxSource::Measure(MeasureBox {
                adaptive: *adaptive,
                spot_rule: spot_rule.clone(),
                // Only a width rule's stopping needs a white; a fixed count needs none.
                spot_white: match spot_rule {
                    Some(RepeatRule::Width { .. }) => nominal_white(&self.display.screen),
                    _ => None,
                },
                spectral: spectral.clone(),
                spot: spot.clone(),
                plan: plan.clone(),
                repeats: *repeats,
                seed: *seed,
                light: box_light(spectral, spot, *light)?,
            }),
        };
        let specs: Vec<&Spec> = match &box_source {
            BoxSource::Measure(m) => vec![&m.spectral, &m.spot, &self.display.spot],
            BoxSource::Existing { .. } => vec![&self.display.spot],
        };
        crate::session::attendance(&specs, self.unattended)?;
        Ok(ExperimentOptions {
            dir: self.dir.clone(),
            measuring: self.measuring,
            box_source,
            given_readings,
            simulation: self.simulation.clone(),
            display: self.display.clone(),
            reproduction: self.reproduction.clone(),
            repeats: self.repeats,
            until_decided: self.until_decided,
            spots_shown: self.spots_shown,
            compare_with: self.compare_with.clone(),
            stage: self.stage,
            resume: self.resume,
            unattended: self.unattended,
            run: self.run.clone(),
        })
    }

    /// What the stages would read or open only after minutes of rendering and measuring:
    /// a given box's scene and readings, and the instruments' specs. Returns a given box's
    /// readings as read, for the checks before the first stage.
    fn check_inputs(&self) -> Result<Option<ReadingSet>, RequestError> {
        let mut specs = vec![&self.display.spot];
        let mut given = None;
        match &self.box_source {
            BoxRequest::Given { scene, spots } => {
                Scene::load(scene)?;
                // Read by the reader the validation stage reads them with, so a file is
                // accepted here exactly when that stage will accept it; the reader
                // refuses readings no instrument takes (X = −1e308 made every stage run
                // and the validation draw an infinite colour difference).
                given = Some(read_readings(spots)?);
            }
            BoxRequest::Measure { spectral, spot, .. } => specs.extend([spectral, spot]),
        }
        for spec in specs {
            spec.check()?;
        }
        Ok(given)
    }
}

/// Why an experiment was refused before its first stage, or stopped in one. The refusals
/// of the request's own values say which value is wrong (see [`RequestError::is_usage`]);
/// a command names its flag.
#[derive(Debug, thiserror::Error)]
pub enum RequestError {
    #[error("the simulation's ΔE*ab target must be above 0")]
    TargetDe,
    #[error("the readings per display patch must be from 1 to {most}, got {got}")]
    Repeats { most: usize, got: usize },
    #[error("the readings per box spot must be at least 1")]
    BoxRepeats,
    /// The verdict rule on the display's patches cannot work: the margin, or the readings
    /// per patch as its most readings.
    #[error("reading each display patch until decided: {0}")]
    UntilDecided(String),
    #[error("the instruments' time scale must be 0 or more")]
    TimeScale,
    #[error("the simulation image's size must be at most {}", MAX_IMAGE_SIZE)]
    ImageSize,
    #[error("the simulation image's samples per pixel must be at least 1")]
    ImageSpp,
    #[error("-o {}: exists and is not a directory", .0.display())]
    OutNotDir(PathBuf),
    #[error("the run to compare with, {}, is not a directory", .0.display())]
    CompareWith(PathBuf),
    /// The instruments and the box's light make no rig.
    #[error(transparent)]
    BoxLight(#[from] BoxLightError),
    /// A real instrument with nobody to place, aim or calibrate it.
    #[error(transparent)]
    NobodyAtTheRig(#[from] NobodyAtTheRig),
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Readings(#[from] ReadingsError),
    #[error(transparent)]
    Instrument(#[from] DriverError),
    #[error(transparent)]
    Experiment(#[from] ExperimentError),
}

impl RequestError {
    /// A refusal of the request's own values or of its rig (nothing was read or opened),
    /// rather than of a file, an instrument or a stage.
    pub fn is_usage(&self) -> bool {
        matches!(
            self,
            RequestError::TargetDe
                | RequestError::CompareWith(_)
                | RequestError::Repeats { .. }
                | RequestError::BoxRepeats
                | RequestError::UntilDecided(_)
                | RequestError::TimeScale
                | RequestError::ImageSize
                | RequestError::ImageSpp
                | RequestError::OutNotDir(_)
                | RequestError::BoxLight(_)
                | RequestError::NobodyAtTheRig(_)
        )
    }
}
