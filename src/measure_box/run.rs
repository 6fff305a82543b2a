//! A box measurement on the session engine: each stage its own journal in the output
//! directory (`tiles.jsonl`, `falloff.jsonl`, `materials.jsonl`, `spots.jsonl`), taken in
//! order; when all four are complete the readings become the measured scene
//! ([`super::assemble`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metamer_drivers::{Instrument, MeasureMode};

use super::assemble::{assemble, AssembleError, BoxDetails, StageEntries, Summary};
use super::plan::{BoxPlan, BoxStage, BoxStep, SPECTRAL, SPOT};
use super::spot_rule::SpotStopping;
use crate::color::Xyz;
use crate::output::OutputPolicy;
use crate::session::budget::meters_of;
use crate::session::{
    placements, CostReport, Entry, InstrumentRecord, JournalError, Operator, ProgressSink, Rig,
    RunEnd, RunOptions, Session, SessionError, StageOf,
};
use crate::validation::repeatability;

/// What to measure and how.
#[derive(Clone, Debug)]
pub struct BoxOptions {
    pub dir: PathBuf,
    pub plan: BoxPlan,
    /// Only this stage (measured again from the start unless resuming); None: every stage.
    pub stage: Option<BoxStage>,
    /// Continue the journals in `dir` instead of refusing them.
    pub resume: bool,
    /// Options of the rig that change what is measured (a simulated box's seed); recorded
    /// in each journal's header and checked on resuming.
    pub rig_options: BTreeMap<String, String>,
    pub details: BoxDetails,
    pub run: RunOptions,
    /// How the scene, light and summary files are written (the plan file among its
    /// inputs). They are replaced only when forced: by the caller, or because the session
    /// resumes or measures a stage again and so owns them.
    pub output: OutputPolicy,
}

/// The rig's two instruments.
pub struct Instruments<'a> {
    pub spectral: &'a mut dyn Instrument,
    pub spot: &'a mut dyn Instrument,
}

/// Where a measurement ended.
#[derive(Debug)]
pub enum Outcome {
    /// Every stage is complete: the scene and its files are written.
    Finished(Box<Summary>),
    /// A stage stopped before its end; its journal holds what was measured.
    Incomplete {
        stage: BoxStage,
        end: RunEnd,
        done: usize,
        total: usize,
        log: PathBuf,
    },
    /// The stages run are complete, these others have no complete journal yet.
    StagesMissing(Vec<BoxStage>),
}

/// A box measurement failed.
#[derive(Debug, thiserror::Error)]
pub enum MeasureBoxError {
    #[error("stage {stage}: {source}")]
    Session {
        stage: BoxStage,
        #[source]
        source: SessionError,
    },
    #[error("setting aside the earlier {stage} journal {}: {source}", path.display())]
    SetAside {
        stage: BoxStage,
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Assemble(#[from] AssembleError),
}

impl MeasureBoxError {
    /// What to do next, said with `measure-box`'s flags, where the session engine's own
    /// message cannot say it: a journal of an earlier session, one written with other
    /// options, or a reading that failed midway (the others are safe in the journal).
    pub fn advice(&self) -> Option<String> {
        let MeasureBoxError::Session { stage, source } = self else {
            return None;
        };
        match source {
            SessionError::Journal(JournalError::Exists { path, entries }) => Some(format!(
                "stage {stage}: {} exists with {entries} reading(s) of an earlier session: continue it with --resume, measure the stage again with --stage {stage}, or choose another output directory",
                path.display()
            )),
            SessionError::Journal(JournalError::OptionDiffers {
                path,
                option,
                logged,
                now,
            }) => Some(format!(
                "stage {stage}: {} was written by another session: its {option} is {logged}, this one's is {now}; run with the same --plan/--repeats/--seed and --resume, or choose another output directory",
                path.display()
            )),
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

    /// What is still to measure and how to continue, said with `measure-box`'s flags;
    /// None when finished.
    pub fn left_to_do(&self) -> Option<String> {
        let (stage, end, done, total, log) = match self {
            Outcome::Finished(_) => return None,
            Outcome::StagesMissing(stages) => {
                let names: Vec<&str> = stages.iter().map(|s| s.name()).collect();
                return Some(format!(
                    "stage(s) {} still to measure before the scene can be assembled (--stage NAME, or the whole session with --resume)",
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
            format!("stage {stage}: none of its {total} readings taken yet: continue with --resume")
        } else {
            format!(
                "stage {stage}: {} of {total} readings still to take; the others are safe in {}: continue with --resume",
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

/// Moves an earlier journal of a stage to be measured again out of the way, to
/// `NAME.replaced-K.jsonl` (nothing measured is deleted).
fn set_aside(stage: BoxStage, path: &Path) -> Result<(), MeasureBoxError> {
    if !path.exists() {
        return Ok(());
    }
    let mut k = 1;
    let target = loop {
        let t = path.with_file_name(format!("{}.replaced-{k}.jsonl", stage.name()));
        if !t.exists() {
            break t;
        }
        k += 1;
    };
    std::fs::rename(path, &target).map_err(|source| MeasureBoxError::SetAside {
        stage,
        path: path.to_path_buf(),
        source,
    })
}

/// Runs one stage's session, its budget said before its first reading and its cost after.
fn run_costed(
    session: &mut Session<BoxDetails, BoxStep>,
    rig: &mut Rig<'_>,
    options: &BoxOptions,
    stage: BoxStage,
    progress: &mut dyn ProgressSink,
) -> Result<(RunEnd, CostReport), MeasureBoxError> {
    let estimate = session.estimate(
        &meters_of(&rig.instruments),
        &|_| BOX_TARGET_CD_M2,
        BOX_LIGHT_ASSUMPTION,
        options.run.placement_s(),
    );
    let named = format!("the box's {stage} stage");
    progress.note(&estimate.before(&named));
    let end = session
        .run(rig, &options.run, progress)
        .map_err(|source| MeasureBoxError::Session { stage, source })?;
    let spent = session.spent().clone();
    progress.note(&spent.after(&named, &estimate));
    let cost = CostReport {
        estimate,
        actual: Some(spent),
    };
    Ok((end, cost))
}

/// The light every box target is budgeted at, cd/m²: a light tile's before its gain in the
/// simulated box; a real box's light is not known before it is measured.
pub const BOX_TARGET_CD_M2: f64 = super::simulated_box::TILE_CD_M2;

/// What [`BOX_TARGET_CD_M2`] assumes, as the budget says it.
pub const BOX_LIGHT_ASSUMPTION: &str =
    "every box target read at a light tile's 100 cd/m² (the simulated box's tiles before their gain)";

fn open_stage(
    options: &BoxOptions,
    stage: BoxStage,
    instruments: &BTreeMap<String, InstrumentRecord>,
    resume: bool,
) -> Result<Session<BoxDetails, BoxStep>, MeasureBoxError> {
    let session = Session::open(
        &stage.journal(&options.dir),
        options.plan.session_plan(stage, &options.rig_options),
        options.details.clone(),
        instruments.clone(),
        resume,
    )
    .map_err(|source| MeasureBoxError::Session { stage, source })?;
    let plan = &options.plan;
    Ok(match (&plan.spot_rule, plan.spot_white, stage) {
        (Some(rule), Some(white), BoxStage::Spots) => {
            let model = instruments
                .get(SPOT)
                .map(|r| r.info.model.clone())
                .unwrap_or_default();
            session.with_stopping(Box::new(SpotStopping {
                rule: rule.clone(),
                stated: repeatability::stated(&model, MeasureMode::Emissive),
                white: Xyz::new(white[0], white[1], white[2]),
            }))
        }
        _ => session,
    })
}

/// Measures what the journals in `options.dir` lack (every stage, or `options.stage`),
/// then, when all four stages are complete, writes the measured scene and its files.
pub fn run(
    options: &BoxOptions,
    instruments: Instruments<'_>,
    operator: &mut dyn Operator,
    progress: &mut dyn ProgressSink,
) -> Result<Outcome, MeasureBoxError> {
    let records: BTreeMap<String, InstrumentRecord> = [
        (
            SPECTRAL.to_string(),
            InstrumentRecord::of(&*instruments.spectral),
        ),
        (SPOT.to_string(), InstrumentRecord::of(&*instruments.spot)),
    ]
    .into();
    let stages: Vec<BoxStage> = match options.stage {
        Some(s) => vec![s],
        None => BoxStage::ALL.to_vec(),
    };
    let mut rig = Rig {
        screen: None,
        instruments: vec![
            (SPECTRAL.to_string(), instruments.spectral),
            (SPOT.to_string(), instruments.spot),
        ],
        operator,
    };
    let mut cost = BTreeMap::new();
    for &stage in &stages {
        let path = stage.journal(&options.dir);
        if options.stage.is_some() && !options.resume {
            set_aside(stage, &path)?;
        }
        let mut session = open_stage(options, stage, &records, options.resume)?;
        let total = session.plan().steps.len();
        if session.done() == total {
            // Nothing to run, so the session does not report what resuming repaired.
            for note in &session.notes {
                progress.note(note);
            }
            continue;
        }
        let number = BoxStage::ALL.iter().position(|&s| s == stage).unwrap_or(0) + 1;
        let of = BoxStage::ALL.len();
        progress.stage(&StageOf {
            number,
            of,
            name: stage.name().into(),
        });
        let placed = placements(&session.plan().steps)
            .iter()
            .enumerate()
            .filter(|(i, r)| r.as_ref().is_some_and(|r| r.start == *i))
            .count();
        let what = format!("stage {number}/{of} {stage}: {total} readings at {placed} placements");
        if session.recovered > 0 || session.torn_bytes > 0 {
            progress.note(&format!(
                "resuming {what}; {} of them are in {}",
                session.recovered,
                path.display()
            ));
        } else {
            progress.note(&what);
        }
        let (end, costs) = run_costed(&mut session, &mut rig, options, stage, progress)?;
        cost.insert(stage.name().to_string(), costs);
        if end != RunEnd::Complete {
            return Ok(Outcome::Incomplete {
                stage,
                end,
                done: session.done(),
                total,
                log: path,
            });
        }
    }
    let entries = match completed_stages(options, &records)? {
        Ok(entries) => entries,
        Err(missing) => return Ok(Outcome::StagesMissing(missing)),
    };
    let owned = options.output.force() || options.resume || options.stage.is_some();
    let policy = options.output.with_force(owned);
    let summary = assemble(
        &policy,
        &options.dir,
        &options.plan,
        &entries,
        &records,
        &options.details,
        &cost,
    )?;
    Ok(Outcome::Finished(Box::new(summary)))
}

/// Every stage's readings, from the journals (earlier runs' included), or the stages that
/// have no complete journal yet.
fn completed_stages(
    options: &BoxOptions,
    records: &BTreeMap<String, InstrumentRecord>,
) -> Result<Result<StageEntries, Vec<BoxStage>>, MeasureBoxError> {
    let mut missing = Vec::new();
    let mut loaded: BTreeMap<BoxStage, (PathBuf, Vec<Entry<BoxStep>>)> = BTreeMap::new();
    for stage in BoxStage::ALL {
        let path = stage.journal(&options.dir);
        if !path.exists() {
            missing.push(stage);
            continue;
        }
        let session = open_stage(options, stage, records, true)?;
        match session.complete_entries() {
            Some(entries) => {
                loaded.insert(stage, (path, entries.into_iter().cloned().collect()));
            }
            None => missing.push(stage),
        }
    }
    if !missing.is_empty() {
        return Ok(Err(missing));
    }
    Ok(Ok(StageEntries { stages: loaded }))
}
