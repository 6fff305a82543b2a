//! A box measurement on the session engine: each stage its own journal in the output
//! directory (`tiles.jsonl`, `falloff.jsonl`, `materials.jsonl`, `spots.jsonl`), taken in
//! order; when all four are complete the readings become the measured scene
//! ([`super::assemble`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metamer_drivers::{Instrument, MeasureMode};

use super::adaptive::shifted::{RoundShifted, ROUND_STRIDE};
use super::adaptive::{self, AdaptiveRule, AdaptiveSummary, RoundDecision};
use super::assemble::{assemble, AssembleError, BoxDetails, StageEntries, Summary};
use super::plan::{BoxPlan, BoxStage, BoxStep, Target, SPECTRAL, SPOT};
use super::spot_rule::SpotStopping;
use crate::color::Xyz;
use crate::output::OutputPolicy;
use crate::session::budget::meters_of;
use crate::session::{
    placements, CostReport, Entry, InstrumentRecord, Operator, ProgressSink, Rig, RunEnd,
    RunOptions, Session, SessionError, StageOf,
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

pub mod advice;

/// Moves an earlier journal of a stage to be measured again out of the way, to
/// `NAME.replaced-K.jsonl` (nothing measured is deleted).
fn set_aside(stage: BoxStage, path: &Path) -> Result<(), MeasureBoxError> {
    if !path.exists() {
        return Ok(());
    }
    let stem = path.file_stem().map_or_else(
        || stage.name().to_string(),
        |s| s.to_string_lossy().into_owned(),
    );
    let mut k = 1;
    let target = loop {
        let t = path.with_file_name(format!("{stem}.replaced-{k}.jsonl"));
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

/// Runs one stage's session (round `round` of an adaptive stage), its budget said before
/// its first reading and its cost after.
fn run_costed(
    session: &mut Session<BoxDetails, BoxStep>,
    instruments: &mut Instruments<'_>,
    operator: &mut dyn Operator,
    round: usize,
    options: &BoxOptions,
    progress: &mut dyn ProgressSink,
) -> Result<(RunEnd, CostReport), MeasureBoxError> {
    let offset = round as u64 * ROUND_STRIDE;
    let mut spectral = RoundShifted {
        inner: &mut *instruments.spectral,
        offset,
    };
    let mut spot = RoundShifted {
        inner: &mut *instruments.spot,
        offset,
    };
    let mut rig = Rig {
        screen: None,
        instruments: vec![
            (SPECTRAL.to_string(), &mut spectral),
            (SPOT.to_string(), &mut spot),
        ],
        operator,
    };
    let rig = &mut rig;
    let stage = session
        .plan()
        .steps
        .first()
        .map_or(BoxStage::Tiles, |s| s.data.stage);
    let estimate = session.estimate(
        &meters_of(&rig.instruments),
        &|_| BOX_TARGET_CD_M2,
        BOX_LIGHT_ASSUMPTION,
        options.run.placement_s(),
    );
    let named =
        match (round, &options.plan.adaptive) {
            (0, Some(rule)) if stage.in_rounds() => {
                format!(
            "the box's {stage} stage, its first pass (the adaptive plan reads at most {} {})",
            if stage == BoxStage::Tiles { rule.max_tiles } else { rule.max_falloff },
            if stage == BoxStage::Tiles { "tiles" } else { "fall-off angles" }
        )
            }
            (0, _) => format!("the box's {stage} stage"),
            _ => format!("the box's {stage} stage, round {round}"),
        };
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

/// Measures what the journals in `options.dir` lack (every stage, or `options.stage`),
/// then, when all four stages are complete, writes the measured scene and its files.
pub fn run(
    options: &BoxOptions,
    mut instruments: Instruments<'_>,
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
    let mut cost = BTreeMap::new();
    for &stage in &stages {
        let path = stage.journal(&options.dir);
        if options.stage.is_some() && !options.resume {
            for later in adaptive::later_rounds(&options.dir, stage)
                .into_iter()
                .rev()
            {
                set_aside(stage, &later)?;
            }
            set_aside(stage, &path)?;
        }
        let mut taken: Vec<Entry<BoxStep>> = Vec::new();
        let mut stage_cost: Option<CostReport> = None;
        for round in 0.. {
            let Some(steps) = round_steps(options, stage, round, &taken) else {
                break;
            };
            let plan = options
                .plan
                .round_plan(stage, round, steps, &options.rig_options);
            let mut session = open_round(options, stage, round, plan, &records, options.resume)?;
            let total = session.plan().steps.len();
            let log = session.journal_path().to_path_buf();
            if session.done() < total {
                announce(&session, stage, round, stage_cost.is_none(), progress);
                let (end, costs) = run_costed(
                    &mut session,
                    &mut instruments,
                    operator,
                    round,
                    options,
                    progress,
                )?;
                stage_cost = Some(summed(stage_cost, costs));
                if end != RunEnd::Complete {
                    if let Some(c) = stage_cost {
                        cost.insert(stage.name().to_string(), c);
                    }
                    return Ok(Outcome::Incomplete {
                        stage,
                        end,
                        done: taken.len() + session.done(),
                        total: taken.len() + total,
                        log,
                    });
                }
            } else {
                // Nothing to run, so the session does not report what resuming repaired.
                for note in &session.notes {
                    progress.note(note);
                }
            }
            taken.extend(
                session
                    .complete_entries()
                    .unwrap_or_default()
                    .into_iter()
                    .cloned(),
            );
        }
        if let Some(c) = stage_cost {
            cost.insert(stage.name().to_string(), c);
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

/// The steps of round `round` of `stage` after the entries `taken` of the rounds before
/// it: the whole stage as round 0 of a fixed stage, the adaptive plan's rounds of an
/// adaptive one; None when the stage has no such round.
fn round_steps(
    options: &BoxOptions,
    stage: BoxStage,
    round: usize,
    taken: &[Entry<BoxStep>],
) -> Option<Vec<crate::session::Step<BoxStep>>> {
    let plan = &options.plan;
    match (round, adaptive_rule(plan, stage)) {
        (0, _) => Some(plan.steps(stage)),
        (_, None) => None,
        (_, Some(rule)) => {
            let next = adaptive::next_round(plan, rule, stage, taken).next;
            (!next.is_empty()).then(|| plan.steps_of(stage, &next))
        }
    }
}

fn adaptive_rule(plan: &BoxPlan, stage: BoxStage) -> Option<&AdaptiveRule> {
    plan.adaptive.as_ref().filter(|_| stage.in_rounds())
}

/// The stage's (or the round's) readings and placements, said before it starts; the
/// stage itself told to `progress` before the `first` round this run takes of it (none
/// costed yet), which is a later round when a resume finds the earlier ones complete.
fn announce(
    session: &Session<BoxDetails, BoxStep>,
    stage: BoxStage,
    round: usize,
    first: bool,
    progress: &mut dyn ProgressSink,
) {
    let number = BoxStage::ALL.iter().position(|&s| s == stage).unwrap_or(0) + 1;
    let of = BoxStage::ALL.len();
    if first {
        progress.stage(&StageOf {
            number,
            of,
            name: stage.name().into(),
        });
    }
    let total = session.plan().steps.len();
    let placed = placements(&session.plan().steps)
        .iter()
        .enumerate()
        .filter(|(i, r)| r.as_ref().is_some_and(|r| r.start == *i))
        .count();
    let round_name = if round == 0 {
        String::new()
    } else {
        format!(" round {round}")
    };
    let what =
        format!("stage {number}/{of} {stage}{round_name}: {total} readings at {placed} placements");
    if session.recovered > 0 || session.torn_bytes > 0 {
        progress.note(&format!(
            "resuming {what}; {} of them are in {}",
            session.recovered,
            session.journal_path().display()
        ));
    } else {
        progress.note(&what);
    }
}

/// Two rounds' budgets and costs as one.
fn summed(a: Option<CostReport>, b: CostReport) -> CostReport {
    let Some(mut a) = a else {
        return b;
    };
    a.estimate.add(&b.estimate);
    a.actual = match (a.actual, b.actual) {
        (Some(mut x), Some(y)) => {
            x.add(&y);
            Some(x)
        }
        (x, y) => x.or(y),
    };
    a
}

/// Opens round `round` of `stage` (round 0: the stage's own journal). A later round's
/// journal exists only if this measurement wrote it, so it is always continued.
fn open_round(
    options: &BoxOptions,
    stage: BoxStage,
    round: usize,
    plan: crate::session::SessionPlan<BoxStep>,
    instruments: &BTreeMap<String, InstrumentRecord>,
    resume: bool,
) -> Result<Session<BoxDetails, BoxStep>, MeasureBoxError> {
    let session = Session::open(
        &adaptive::round_journal(&options.dir, stage, round),
        plan,
        options.details.clone(),
        instruments.clone(),
        resume || round > 0,
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

/// A stage's complete readings over its rounds, from the journals: its journals, its
/// entries, how many rounds and the last decision (None for a fixed stage); None when a
/// round is missing or incomplete.
type Loaded = (
    Vec<PathBuf>,
    Vec<Entry<BoxStep>>,
    Option<(usize, RoundDecision)>,
);

fn load_stage(
    options: &BoxOptions,
    stage: BoxStage,
    records: &BTreeMap<String, InstrumentRecord>,
) -> Result<Option<Loaded>, MeasureBoxError> {
    let mut paths = Vec::new();
    let mut taken: Vec<Entry<BoxStep>> = Vec::new();
    for round in 0.. {
        let Some(steps) = round_steps(options, stage, round, &taken) else {
            break;
        };
        let path = adaptive::round_journal(&options.dir, stage, round);
        if !path.exists() {
            return Ok(None);
        }
        let plan = options
            .plan
            .round_plan(stage, round, steps, &options.rig_options);
        let session = open_round(options, stage, round, plan, records, true)?;
        let Some(entries) = session.complete_entries() else {
            return Ok(None);
        };
        taken.extend(entries.into_iter().cloned());
        paths.push(path);
    }
    let decided = adaptive_rule(&options.plan, stage).map(|rule| {
        (
            paths.len(),
            adaptive::next_round(&options.plan, rule, stage, &taken),
        )
    });
    Ok(Some((paths, taken, decided)))
}

/// Every stage's readings, from the journals (earlier runs' included), or the stages that
/// have no complete journal yet.
fn completed_stages(
    options: &BoxOptions,
    records: &BTreeMap<String, InstrumentRecord>,
) -> Result<Result<StageEntries, Vec<BoxStage>>, MeasureBoxError> {
    let mut missing = Vec::new();
    let mut loaded = BTreeMap::new();
    let mut rounds = BTreeMap::new();
    let mut decided = BTreeMap::new();
    for stage in BoxStage::ALL {
        match load_stage(options, stage, records)? {
            Some((mut paths, entries, decision)) => {
                let first = paths.remove(0);
                loaded.insert(stage, (first, entries));
                rounds.insert(stage, paths);
                if let Some(d) = decision {
                    decided.insert(stage, d);
                }
            }
            None => missing.push(stage),
        }
    }
    if !missing.is_empty() {
        return Ok(Err(missing));
    }
    let adaptive = options
        .plan
        .adaptive
        .as_ref()
        .map(|rule| adaptive_summary(&options.plan, rule, &loaded, &mut decided));
    Ok(Ok(StageEntries {
        stages: loaded,
        later_rounds: rounds,
        adaptive,
    }))
}

/// What the adaptive rounds read and decided.
fn adaptive_summary(
    plan: &BoxPlan,
    rule: &AdaptiveRule,
    loaded: &BTreeMap<BoxStage, (PathBuf, Vec<Entry<BoxStep>>)>,
    decided: &mut BTreeMap<BoxStage, (usize, RoundDecision)>,
) -> AdaptiveSummary {
    let entries = |stage| loaded.get(&stage).map_or(&[][..], |(_, e)| e.as_slice());
    let tiles_read: Vec<[usize; 2]> = adaptive::spatial::tiles_read(entries(BoxStage::Tiles))
        .into_iter()
        .map(|t| t.0)
        .collect();
    let g = &plan.geometry;
    let tiles_predicted = (0..g.rows * g.cols)
        .map(|k| [k / g.cols, k % g.cols])
        .filter(|t| !tiles_read.contains(t))
        .collect();
    let falloff_read = entries(BoxStage::Falloff)
        .iter()
        .filter_map(|e| match e.data.target {
            Target::Falloff { plane, angle_deg } if e.data.repeat == 0 => Some((plane, angle_deg)),
            _ => None,
        })
        .collect();
    let none = || {
        (
            0,
            RoundDecision {
                next: Vec::new(),
                figure: 0.0,
                why: String::new(),
            },
        )
    };
    let (tile_rounds, tiles) = decided.remove(&BoxStage::Tiles).unwrap_or_else(none);
    let (falloff_rounds, falloff) = decided.remove(&BoxStage::Falloff).unwrap_or_else(none);
    AdaptiveSummary {
        tiles_read,
        tiles_predicted,
        tiles,
        tile_rounds,
        falloff_read,
        falloff,
        falloff_rounds,
        rule: rule.clone(),
    }
}
