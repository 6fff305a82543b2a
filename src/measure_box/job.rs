//! The box measurement as one library call, [`measure`]: `metamer measure-box` and the
//! experiment's box stage both make it. The plan loaded, the rig checked and opened
//! ([`super::setup`]), the stages measured and the scene written ([`super::run`]), and for
//! the experiment each spot's readings as the file its later stages read. Everything that
//! can be refused without an instrument is refused before one is opened.
//!
//! Where the command and the stage behave differently, the difference is a field of
//! [`MeasureBoxRequest`] that each sets: [`MeasureBoxRequest::attendance`] (who answers a
//! real rig), [`MeasureBoxRequest::spot_readings`] (the stage's `spots.csv`),
//! [`MeasureBoxRequest::force`] (the stage's directory is its own) and
//! [`MeasureBoxRequest::stage`] (the command may measure one stage). Progress and notes
//! are the caller's callbacks; a failure is a [`MeasureBoxJobError`] each words itself.

use std::path::PathBuf;

use metamer_drivers::Spec;

use super::plan::{BoxPlan, BoxPlanError, BoxStage};
use super::run::{run, BoxOptions, Instruments, MeasureBoxError, Outcome};
use super::setup::{self, BoxLightError, RigError, RigRequest};
use super::spot_rule;
use super::{BoxDetails, Summary};
use crate::output::OutputPolicy;
use crate::rig::Scenario;
use crate::session::{attendance, Attendance, NobodyAtTheRig, ProgressSink, RunOptions};
use crate::validation::readings::{write_readings, PatchReading, ReadingsError};
use crate::validation::repeatability;
use crate::validation::sequential::RepeatRule;

/// The spots' readings file in the output directory, with
/// [`MeasureBoxRequest::spot_readings`].
pub const SPOTS_FILE: &str = "spots.csv";

/// What `measure-box` is asked to do.
#[derive(Clone, Debug)]
pub struct MeasureBoxRequest {
    /// Output directory: the stage journals, scene, light files and summary.
    pub out: PathBuf,
    /// The spectral instrument.
    pub spectral: Spec,
    /// The spot meter.
    pub spot: Spec,
    /// A plan file; `None`: the paper's plan.
    pub plan: Option<PathBuf>,
    /// Readings of each tile and each spot; `None`: the plan's.
    pub repeats: Option<usize>,
    /// Read the tiles and the fall-off adaptively ([`crate::measure_box::adaptive`]) with
    /// the default rule where the plan names none.
    pub adaptive: bool,
    /// How each spot is read where the plan file names no rule (the experiment's measuring
    /// plan), and the white its CIELAB is relative to where the plan names none: a plan
    /// file's own `spot_rule` and `spot_white` stay. None: the plan's.
    pub spot_rule: Option<RepeatRule>,
    pub spot_white: Option<[f64; 3]>,
    /// Continue the journals in `out`.
    pub resume: bool,
    /// Only this stage, by name (tiles, falloff, materials, spots). A name, not a
    /// [`BoxStage`], because it is checked after the plan, as the command always did. The
    /// experiment's box stage measures them all (None).
    pub stage: Option<String>,
    /// Seed of the simulated box and its instruments' noise.
    pub seed: u64,
    /// The simulated box's light (None: the default); refused on a real rig
    /// ([`setup::box_light`]).
    pub scenario: Option<Scenario>,
    /// Replace an existing scene, light files or summary in `out`: the command's
    /// `--force`; the experiment's box stage always, as its directory is its own.
    pub force: bool,
    /// Nobody is at the rig: take every reading without asking anyone.
    pub unattended: bool,
    /// When to stop early (a reading count, a Ctrl-C flag).
    pub run: RunOptions,
    /// Who answers a real rig's requests to place, aim and calibrate the instruments (a
    /// simulated box answers for itself). None: as [`attendance`] decides from
    /// [`unattended`](Self::unattended), the specs and whether stdin is a terminal, a
    /// physical instrument with nobody to ask refused (`measure-box`). Some: as the caller
    /// decided and checked (the experiment's box stage: the terminal unless unattended,
    /// its request having refused a physical instrument with nobody at the rig).
    pub attendance: Option<Attendance>,
    /// Also write [`SPOTS_FILE`] in `out` once the box is measured: each spot's mean, one
    /// reading's covariance over the repeats kept (a spot read once: the meter's stated
    /// repeatability) and their count, the readings file the experiment's later stages
    /// and `validate` read. The experiment's box stage sets it; `measure-box` leaves the
    /// spots in `summary.json`.
    pub spot_readings: bool,
}

/// Why [`measure`] did not finish. Each refusal of the request has its own variant, so a
/// caller can say it in the words of its own options.
#[derive(Debug, thiserror::Error)]
pub enum MeasureBoxJobError {
    /// The plan file cannot be read or is not a valid plan.
    #[error(transparent)]
    Plan(#[from] BoxPlanError),
    /// The repeat count asked for ([`MeasureBoxRequest::repeats`]) is out of range.
    #[error("repeats {0}")]
    Repeats(String),
    /// No stage has this name.
    #[error("{0}")]
    UnknownStage(String),
    /// The instruments and the light make no rig ([`setup::box_light`]).
    #[error(transparent)]
    BoxLight(#[from] BoxLightError),
    #[error(transparent)]
    Nobody(#[from] NobodyAtTheRig),
    #[error(transparent)]
    Rig(#[from] RigError),
    #[error(transparent)]
    Measure(#[from] MeasureBoxError),
    /// The spots' readings file ([`MeasureBoxRequest::spot_readings`]) was not written.
    #[error(transparent)]
    SpotReadings(#[from] ReadingsError),
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
/// use metamer::session::{NoProgress, RunOptions};
///
/// let out = std::env::temp_dir().join(format!("metamer-doc-box-{}", std::process::id()));
/// let request = MeasureBoxRequest {
///     out: out.clone(),
///     spectral: "sim:i1pro?time_scale=0".into(),
///     spot: "sim:cs100a?time_scale=0".into(),
///     plan: None,
///     repeats: Some(1),
///     adaptive: false,
///     spot_rule: None,
///     spot_white: None,
///     resume: false,
///     stage: Some("tiles".into()),
///     seed: 1,
///     scenario: None,
///     force: false,
///     unattended: false,
///     run: RunOptions::default(),
///     attendance: None,
///     spot_readings: false,
/// };
/// let outcome = measure(&request, &|_| {}, &mut |_| Box::new(NoProgress)).unwrap();
/// // The other stages are still to measure before the scene can be assembled.
/// assert!(matches!(outcome, Outcome::StagesMissing(ref s) if s.len() == 3));
/// assert!(out.join("tiles.jsonl").exists());
/// # std::fs::remove_dir_all(&out).unwrap();
/// ```
pub fn measure<'p>(
    request: &MeasureBoxRequest,
    note: &dyn Fn(String),
    progress: &mut dyn FnMut(bool) -> Box<dyn ProgressSink + 'p>,
) -> Result<Outcome, MeasureBoxJobError> {
    let plan = plan(request)?;
    let stage: Option<BoxStage> = request
        .stage
        .as_deref()
        .map(str::parse)
        .transpose()
        .map_err(MeasureBoxJobError::UnknownStage)?;
    let (spectral, spot) = (&request.spectral, &request.spot);
    // As written, before a simulated box is made and its seed appended to the specs: a
    // misnamed instrument is refused as such, not as half of a mixed rig.
    for spec in [spectral, spot] {
        spec.check().map_err(RigError::Open)?;
    }
    let light = setup::box_light(spectral, spot, request.scenario)?;
    // Before anything is opened: a real rig with nobody to ask is refused.
    let attended = match request.attendance {
        Some(a) => a,
        None => attendance(&[spectral, spot], request.unattended)?,
    };
    let rig_request = RigRequest {
        plan: &plan,
        spectral,
        spot,
        seed: request.seed,
        light,
    };
    if let Some(pace) = crate::session::pace_note(&[spectral, spot]) {
        note(pace);
    }
    let mut rig = setup::open(&rig_request, || attended.operator(), note)?;
    let mut output = OutputPolicy::new(request.force);
    if let Some(p) = &request.plan {
        output.input(p);
    }
    let options = BoxOptions {
        output,
        dir: request.out.clone(),
        plan,
        stage,
        resume: request.resume,
        rig_options: std::mem::take(&mut rig.rig_options),
        details: BoxDetails {
            spectral: request.spectral.to_string(),
            spot: request.spot.to_string(),
        },
        run: request.run.clone(),
    };
    // The model the meter reports, not a guess from its spec: `replay:box-spots.jsonl`
    // names none. Asked only where the readings file is written, as the stage always did.
    let meter = request.spot_readings.then(|| rig.spot.info().model);
    // A plan that states a spot rule, a fixed count among them, reads its spots for the
    // pooled figure: three readings with the figure pooled over 24 spots (t with ν = 144)
    // give a narrower interval than five with a spot's own scatter (t with ν = 4).
    let by_rule = options.plan.spot_rule.is_some();
    let mut sink = progress(!rig.simulated && attended == Attendance::Terminal);
    let outcome = run(
        &options,
        Instruments {
            spectral: rig.spectral.as_mut(),
            spot: rig.spot.as_mut(),
        },
        rig.operator.as_mut(),
        sink.as_mut(),
    )?;
    if let (Outcome::Finished(summary), Some(meter)) = (&outcome, meter) {
        write_readings(
            &request.out.join(SPOTS_FILE),
            &spot_readings(summary, &meter, by_rule),
        )?;
    }
    Ok(outcome)
}

/// Each spot's mean with its scatter in X, Y and Z together, over the repeats the
/// reduction kept, in the plan's order; a spot read once carries the stated repeatability
/// of the `meter` (its model). Spots read `by_rule` (a plan's stated spot rule: a width
/// rule, whose counts rest on the figure pooled across the spots, or a fixed count) carry
/// that figure and its degrees of freedom.
fn spot_readings(summary: &Summary, meter: &str, by_rule: bool) -> Vec<(usize, PatchReading)> {
    let stated = repeatability::emissive_of(meter);
    if let Some(stated) = stated.filter(|_| by_rule) {
        let spots: Vec<_> = summary
            .spot_xyz
            .iter()
            .zip(summary.spots.iter())
            .map(|((patch, xyz), r)| (*patch, *xyz, r.stats.clone()))
            .collect();
        if let Some(pooled) = spot_rule::pooled_readings(&spots, &stated) {
            return pooled;
        }
    }
    summary
        .spot_xyz
        .iter()
        .zip(summary.spots.iter())
        .map(|((patch, xyz), r)| {
            let n = r.stats.n - r.stats.outliers.len();
            let cov = match (n, stated.and_then(|s| repeatability::covariance(&s, *xyz))) {
                (1, Some(c)) => c,
                _ => r.stats.cov,
            };
            (*patch, PatchReading::stated(*xyz, cov, n, 0.0))
        })
        .collect()
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
    plan.choose_adaptive(request.adaptive);
    if plan.spot_rule.is_none() {
        plan.spot_rule = request.spot_rule.clone();
    }
    if plan.spot_white.is_none() {
        plan.spot_white = request.spot_white;
    }
    plan.validate().map_err(|e| match e {
        BoxPlanError::Invalid { field, message } if field == "repeats" => {
            MeasureBoxJobError::Repeats(message)
        }
        e => e.into(),
    })?;
    Ok(plan)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A replayed CS-100A whose file name says nothing of the model: the spec names no
    /// meter, the opened instrument does, and its stated repeatability is the CS-100A's.
    #[test]
    fn a_replayed_meter_is_known_by_the_model_it_reports() {
        let dir = std::env::temp_dir().join(format!("metamer-box-stage-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("spot.jsonl");
        let transcript = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/protocols/cs100a/transcripts/normal_session.jsonl"
        );
        std::fs::copy(transcript, &file).unwrap();
        let spec = Spec::replay(&file);
        assert!(repeatability::emissive_of(spec.as_str()).is_none());
        let meter = spec.open(None).unwrap();
        let stated = repeatability::emissive_of(&meter.info().model).unwrap();
        let cs100a = repeatability::stated("cs100a", metamer_drivers::MeasureMode::Emissive);
        assert_eq!(stated, cs100a);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
