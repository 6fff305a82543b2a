//! `metamer measure-box`'s whole job as one library call: the plan loaded, the rig checked
//! and opened ([`super::setup`]), the stages measured and the scene written
//! ([`super::run`]). Everything that can be refused without an instrument is refused
//! before one is opened.

use std::path::PathBuf;

use metamer_drivers::Spec;

use super::plan::{BoxPlan, PlanError, Stage};
use super::run::{run, Instruments, MeasureBoxError, Options, Outcome};
use super::setup::{self, BoxLightError, RigError, RigRequest};
use super::BoxDetails;
use crate::output::OutputPolicy;
use crate::session::{attendance, Attendance, NobodyAtTheRig, ProgressSink, RunOptions};

/// What `measure-box` is asked to do.
#[derive(Clone, Debug, Default)]
pub struct MeasureBoxRequest {
    /// Output directory: the stage journals, scene, light files and summary.
    pub out: PathBuf,
    /// The spectral instrument's spec.
    pub spectral: String,
    /// The spot meter's spec.
    pub spot: String,
    /// A plan file; `None`: the paper's plan.
    pub plan: Option<PathBuf>,
    /// Readings of each tile and each spot; `None`: the plan's.
    pub repeats: Option<usize>,
    /// Continue the journals in `out`.
    pub resume: bool,
    /// Only this stage, by name (tiles, falloff, materials, spots). A name, not a
    /// [`Stage`], because it is checked after the plan, as the command always did.
    pub stage: Option<String>,
    /// Seed of the simulated box and its instruments' noise.
    pub seed: u64,
    /// The simulated box's light, by name; checked once the rig is known to be simulated.
    pub scenario: Option<String>,
    /// Replace an existing scene, light files or summary in `out`.
    pub force: bool,
    /// Nobody is at the rig: take every reading without asking anyone.
    pub unattended: bool,
    /// When to stop early (a reading count, a Ctrl-C flag).
    pub run: RunOptions,
}

/// Why [`measure`] did not finish. Each refusal of the request has its own variant, so a
/// caller can say it in the words of its own options.
#[derive(Debug, thiserror::Error)]
pub enum MeasureBoxJobError {
    /// The plan file cannot be read or is not a valid plan.
    #[error(transparent)]
    Plan(#[from] PlanError),
    /// The repeat count asked for ([`MeasureBoxRequest::repeats`]) is out of range.
    #[error("repeats {0}")]
    Repeats(String),
    /// No stage has this name.
    #[error("{0}")]
    UnknownStage(String),
    #[error(transparent)]
    BoxLight(#[from] BoxLightError),
    #[error(transparent)]
    Nobody(#[from] NobodyAtTheRig),
    #[error(transparent)]
    Rig(#[from] RigError),
    #[error(transparent)]
    Measure(#[from] MeasureBoxError),
}

/// Measures the box `request` names: what its journals lack, then, when every stage is
/// complete, the measured scene and its files. `note` hears what is simulated before the
/// instruments open; `progress` makes the progress sink, told whether somebody at a
/// terminal follows a real rig.
///
/// # Examples
///
/// One stage of the simulated box, one reading per tile, at no simulated time:
///
/// ```
/// use metamer::measure_box::job::{measure, MeasureBoxRequest};
/// use metamer::measure_box::Outcome;
/// use metamer::session::NoProgress;
///
/// let out = std::env::temp_dir().join(format!("metamer-doc-box-{}", std::process::id()));
/// let request = MeasureBoxRequest {
///     out: out.clone(),
///     spectral: "sim:i1pro?time_scale=0".into(),
///     spot: "sim:cs100a?time_scale=0".into(),
///     repeats: Some(1),
///     stage: Some("tiles".into()),
///     seed: 1,
///     ..MeasureBoxRequest::default()
/// };
/// let outcome = measure(&request, &|_| {}, &mut |_| Box::new(NoProgress)).unwrap();
/// // The other stages are still to measure before the scene can be assembled.
/// assert!(matches!(outcome, Outcome::StagesMissing(ref s) if s.len() == 3));
/// assert!(out.join("tiles.jsonl").exists());
/// # std::fs::remove_dir_all(&out).unwrap();
/// ```
pub fn measure(
    request: &MeasureBoxRequest,
    note: &dyn Fn(String),
    progress: &mut dyn FnMut(bool) -> Box<dyn ProgressSink>,
) -> Result<Outcome, MeasureBoxJobError> {
    let plan = plan(request)?;
    let stage: Option<Stage> = request
        .stage
        .as_deref()
        .map(str::parse)
        .transpose()
        .map_err(MeasureBoxJobError::UnknownStage)?;
    let (spectral, spot) = (
        Spec::new(request.spectral.as_str()),
        Spec::new(request.spot.as_str()),
    );
    let simulated = setup::is_simulated(&spectral, &spot)?;
    let light = setup::box_light(request.scenario.as_deref(), simulated)?;
    // Before anything is opened: a real rig with nobody to ask is refused.
    let attended = attendance(&[&request.spectral, &request.spot], request.unattended)?;
    let rig_request = RigRequest {
        plan: &plan,
        spectral: &spectral,
        spot: &spot,
        seed: request.seed,
        light,
    };
    let mut rig = setup::open(&rig_request, || attended.operator(), note)?;
    let mut output = OutputPolicy::new(request.force);
    if let Some(p) = &request.plan {
        output.input(p);
    }
    let options = Options {
        output,
        dir: request.out.clone(),
        plan,
        stage,
        resume: request.resume,
        rig_options: std::mem::take(&mut rig.rig_options),
        details: BoxDetails {
            spectral: request.spectral.clone(),
            spot: request.spot.clone(),
        },
        run: request.run.clone(),
    };
    let mut sink = progress(!rig.simulated && attended == Attendance::Terminal);
    Ok(run(
        &options,
        Instruments {
            spectral: rig.spectral.as_mut(),
            spot: rig.spot.as_mut(),
        },
        rig.operator.as_mut(),
        sink.as_mut(),
    )?)
}

/// The plan file's plan (checked as it is read), or the paper's, with the repeat count
/// asked for: a count out of range is told apart from a bad plan file.
fn plan(request: &MeasureBoxRequest) -> Result<BoxPlan, MeasureBoxJobError> {
    let mut plan = match &request.plan {
        Some(p) => BoxPlan::load(p)?,
        None => BoxPlan::default(),
    };
    if let Some(n) = request.repeats {
        plan.repeats = n;
    }
    plan.validate().map_err(|e| match e {
        PlanError::Invalid { field, message } if field == "repeats" => {
            MeasureBoxJobError::Repeats(message)
        }
        e => e.into(),
    })?;
    Ok(plan)
}
