//! What an experiment is made of: the options every stage and the checks before the first
//! stage read.

use std::path::PathBuf;

use serde::Serialize;

use super::display::DisplayOptions;
use super::display_spots::SpotsShown;
use super::measure_box::MeasureBox;
use super::measuring::MeasuringPlan;
use super::reproduction::ReproductionOptions;
use super::simulation::SimulationOptions;
use super::stage::Stage;
use crate::session::RunOptions;
use crate::validation::readings::ReadingSet;

/// Where the box's measurements come from.
// One per experiment, never in a collection: its size costs nothing worth a box.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum BoxSource {
    /// Measured here, by the `measure-box` session into `box/`.
    Measure(MeasureBox),
    /// Measurements taken earlier or elsewhere: the measured scene and the spot readings.
    Existing { scene: PathBuf, spots: PathBuf },
}

/// What an experiment is made of.
#[derive(Clone, Debug)]
pub struct ExperimentOptions {
    pub dir: PathBuf,
    /// The measuring plan the options were expanded from: each stage's record names it.
    pub measuring: MeasuringPlan,
    pub box_source: BoxSource,
    /// A given box's spot readings as [`Request`](super::Request) read them in its checks,
    /// so the checks before the first stage use them rather than read the file again.
    /// None for a measured box, or for options made without a request: those checks
    /// then read the file themselves.
    pub given_readings: Option<ReadingSet>,
    pub simulation: SimulationOptions,
    pub display: DisplayOptions,
    pub reproduction: ReproductionOptions,
    /// Spot readings averaged per patch on the display: with `until_decided`, the most.
    pub repeats: usize,
    /// Read each patch on the display until its ΔE*ab against the box is decided, this
    /// margin (ΔE*ab) beyond the JND at 95 % (the verdict rule of
    /// [`crate::validation::sequential`]); None: always `repeats` readings.
    pub until_decided: Option<f64>,
    /// How each patch is put in front of the meter on the display.
    pub spots_shown: SpotsShown,
    /// Another run's folder, measured with another plan on the same rig: the report's
    /// cost section sets its measuring cost and accuracy beside this run's, from its saved
    /// files alone.
    pub compare_with: Option<PathBuf>,
    /// Run only this stage (again, even if its inputs are unchanged).
    pub stage: Option<Stage>,
    /// Continue an interrupted measuring stage's journal.
    pub resume: bool,
    /// Nobody at the rig: every operator request counts as done (simulated rigs).
    pub unattended: bool,
    pub run: RunOptions,
}
