//! Taking a plan's steps: for each step the journal lacks, in plan order, calibrate the
//! step's instrument if it says it must, prepare the rig, let it settle, measure (and on an
//! expired calibration negotiate and measure again), append the entry, report progress.
//!
//! Calibration comes before preparation: a calibration has the operator move the
//! instrument (onto its white tile, under a cap), so the step's own setup must follow it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use metamer_drivers::{
    CalibrationCondition, CalibrationOutcome, DriverError, Instrument, InstrumentInfo, MeasureMode,
    Reading, Request,
};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::journal::{
    CalibrationRecord, Header, Journal, JournalError, JOURNAL_FORMAT, JOURNAL_VERSION,
};
use super::operator::{Answer, Operator, OperatorError};
use super::plan::{Prepare, SessionPlan, Step};
use super::progress::{ProgressSink, StepProgress};
use super::screen::Screen;

/// Calibration conditions asked for in one negotiation before giving up: instruments ask
/// for a few in a row (dark, then white tile); more means the operator's action did not
/// satisfy the instrument.
pub const CALIBRATION_ATTEMPTS: usize = 5;
/// Times a step is measured again after its calibration expired during the measurement.
pub const REMEASURE_ATTEMPTS: usize = 2;

/// One measured step as journalled.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Entry<D> {
    /// The step's plan index.
    pub index: usize,
    pub label: String,
    pub role: String,
    pub mode: MeasureMode,
    pub data: D,
    pub reading: Reading,
}

/// The header's caller part the engine adds to: the instruments by role.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionHeader<H> {
    /// Every instrument of the rig by role, with its model-specific settings in force.
    pub instruments: BTreeMap<String, InstrumentRecord>,
    /// The caller's part.
    pub details: H,
}

/// An instrument as the journal records it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InstrumentRecord {
    pub info: InstrumentInfo,
    /// Model-specific settings in force, name → value.
    pub options: BTreeMap<String, String>,
}

impl InstrumentRecord {
    pub fn of(instrument: &dyn Instrument) -> InstrumentRecord {
        InstrumentRecord {
            info: instrument.info(),
            options: instrument.option_values().into_iter().collect(),
        }
    }
}

/// The journal type of a session with header data `H` and step data `D`.
pub type SessionJournal<H, D> = Journal<SessionHeader<H>, Entry<D>>;

/// A step could not be taken.
#[derive(Debug, thiserror::Error)]
pub enum StepFailure {
    #[error("showing it: {0}")]
    Screen(#[source] Box<dyn std::error::Error + Send + Sync>),
    #[error("the plan shows drive values but the rig has no screen")]
    NoScreen,
    #[error("the plan names instrument role '{0}' but the rig has no instrument in it")]
    NoInstrument(String),
    #[error(transparent)]
    Operator(#[from] OperatorError),
    #[error(transparent)]
    Instrument(#[from] DriverError),
    #[error("the {role} instrument still asks for {mode} calibration after {attempts} attempts: the last request was to {prompt}")]
    Calibration {
        role: String,
        mode: MeasureMode,
        attempts: usize,
        prompt: String,
    },
    #[error("the {role} instrument's {mode} calibration expired again right after calibrating, {attempts} times")]
    Expiring {
        role: String,
        mode: MeasureMode,
        attempts: usize,
    },
    #[error(transparent)]
    Journal(#[from] JournalError),
}

/// The session could not start or go on.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    #[error("creating the directory {}: {source}", dir.display())]
    Dir {
        dir: PathBuf,
        source: std::io::Error,
    },
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

/// How to run.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Stop after this many new entries (an interruption on purpose, for tests and for
    /// splitting a long session).
    pub stop_after: Option<usize>,
    /// Set from elsewhere (a Ctrl-C handler) to stop before the next step.
    pub interrupt: Option<Arc<AtomicBool>>,
}

/// Where a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunEnd {
    /// Every step is in the journal.
    Complete,
    /// Stopped by [`RunOptions::stop_after`] with this many steps still missing.
    Stopped { missing: usize },
    /// Stopped by [`RunOptions::interrupt`] with this many steps still missing.
    Interrupted { missing: usize },
    /// The operator declined a request, with this many steps still missing.
    Aborted { missing: usize },
}

/// What the session runs on: a screen where steps show drive values, the instruments by
/// role, and the operator.
pub struct Rig<'a> {
    pub screen: Option<&'a mut dyn Screen>,
    pub instruments: Vec<(String, &'a mut dyn Instrument)>,
    pub operator: &'a mut dyn Operator,
}

impl<'a> Rig<'a> {
    fn instrument(&mut self, role: &str) -> Option<&mut (dyn Instrument + 'a)> {
        self.instruments
            .iter_mut()
            .find(|(r, _)| r == role)
            .map(|(_, i)| &mut **i)
    }
}

/// A session bound to its journal.
pub struct Session<H, D> {
    plan: SessionPlan<D>,
    journal: SessionJournal<H, D>,
    entries: Vec<Option<Entry<D>>>,
    calibrations: Vec<CalibrationRecord>,
    /// Entries found in the journal when the session was resumed.
    pub recovered: usize,
    /// Bytes of a torn last line set aside on resuming (0 if none).
    pub torn_bytes: usize,
}

impl<H, D> Session<H, D>
where
    H: Serialize + DeserializeOwned + Clone,
    D: Serialize + DeserializeOwned + Clone + PartialEq,
{
    /// Starts a session of `plan` with its journal at `path` (its directory created if
    /// missing). With `resume`, an existing journal there is continued; without it an
    /// existing journal is an error and is left alone. `instruments` are the rig's, by role.
    pub fn open(
        path: &Path,
        plan: SessionPlan<D>,
        details: H,
        instruments: BTreeMap<String, InstrumentRecord>,
        resume: bool,
    ) -> Result<Self, SessionError> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| SessionError::Dir {
                dir: dir.to_path_buf(),
                source,
            })?;
        }
        let header = Header {
            format: JOURNAL_FORMAT.into(),
            version: JOURNAL_VERSION,
            kind: plan.kind.clone(),
            fingerprint: plan.fingerprint().map_err(SessionError::Plan)?,
            options: plan.options.clone(),
            steps: plan.steps.len(),
            started_s: metamer_drivers::instrument::now_s(),
            data: SessionHeader {
                instruments,
                details,
            },
        };
        let mut entries = vec![None; plan.steps.len()];
        if !(resume && path.exists()) {
            let journal = Journal::create(path, &header)?;
            return Ok(Session {
                plan,
                journal,
                entries,
                calibrations: Vec::new(),
                recovered: 0,
                torn_bytes: 0,
            });
        }
        let (journal, recovered): (SessionJournal<H, D>, _) = Journal::resume(path, &header)?;
        for (role, now) in &header.data.instruments {
            if let Some(logged) = recovered.header.data.instruments.get(role) {
                if logged.info.model != now.info.model {
                    return Err(SessionError::InstrumentDiffers {
                        path: path.to_path_buf(),
                        role: role.clone(),
                        logged: logged.info.model.clone(),
                        now: now.info.model.clone(),
                    });
                }
            }
        }
        let bad = |line: usize, message: String| SessionError::Entry {
            path: path.to_path_buf(),
            line,
            message,
        };
        let n = recovered.entries.len();
        for (line, entry) in recovered.entries {
            let step = plan.steps.get(entry.index).ok_or_else(|| {
                bad(
                    line,
                    format!(
                        "step index {} is beyond the plan's {}",
                        entry.index,
                        plan.steps.len()
                    ),
                )
            })?;
            if step.label != entry.label || step.data != entry.data {
                return Err(bad(
                    line,
                    format!(
                        "step {} was planned as '{}' ({}) but journalled as '{}' ({})",
                        entry.index,
                        step.label,
                        serde_json::to_string(&step.data).unwrap_or_default(),
                        entry.label,
                        serde_json::to_string(&entry.data).unwrap_or_default(),
                    ),
                ));
            }
            let i = entry.index;
            if entries[i].replace(entry).is_some() {
                return Err(bad(line, format!("step {i} is journalled twice")));
            }
        }
        Ok(Session {
            plan,
            journal,
            entries,
            calibrations: recovered.calibrations,
            recovered: n,
            torn_bytes: recovered.torn_bytes,
        })
    }

    pub fn plan(&self) -> &SessionPlan<D> {
        &self.plan
    }

    pub fn journal_path(&self) -> &Path {
        self.journal.path()
    }

    /// Steps in the journal.
    pub fn done(&self) -> usize {
        self.entries.iter().filter(|e| e.is_some()).count()
    }

    /// Every calibration journalled, earlier runs' included, in the order done.
    pub fn calibrations(&self) -> &[CalibrationRecord] {
        &self.calibrations
    }

    /// Every entry in plan order; None until every step is measured.
    pub fn complete_entries(&self) -> Option<Vec<&Entry<D>>> {
        self.entries.iter().map(Option::as_ref).collect()
    }

    /// Takes every step the journal lacks, in plan order.
    pub fn run(
        &mut self,
        rig: &mut Rig<'_>,
        options: &RunOptions,
        progress: &mut dyn ProgressSink,
    ) -> Result<RunEnd, SessionError> {
        self.check_rig(rig)?;
        let total = self.plan.steps.len();
        progress.start(self.done(), total);
        let result = self.run_steps(rig, options, progress);
        progress.finish();
        result
    }

    /// Whether the rig has what every step still to take needs: its instrument in a mode it
    /// offers, and a screen for the steps that show colours.
    fn check_rig(&self, rig: &mut Rig<'_>) -> Result<(), SessionError> {
        let has_screen = rig.screen.is_some();
        for (index, step) in self.plan.steps.iter().enumerate() {
            if self.entries[index].is_some() {
                continue;
            }
            let lacks = |need: String| SessionError::RigLacks {
                index,
                label: step.label.clone(),
                need,
            };
            let Some(instrument) = rig.instrument(&step.role) else {
                return Err(lacks(format!(
                    "needs a '{}' instrument and the rig has none",
                    step.role
                )));
            };
            let capabilities = instrument.capabilities();
            if !capabilities.supports(step.mode) {
                let offered: Vec<&str> = capabilities.modes.iter().map(|m| m.mode.name()).collect();
                return Err(lacks(format!(
                    "measures {} with the '{}' instrument, a {} that offers only {}",
                    step.mode,
                    step.role,
                    instrument.info().model,
                    offered.join(", ")
                )));
            }
            if matches!(step.prepare, Prepare::Show { .. }) && !has_screen {
                return Err(lacks("shows a colour and the rig has no screen".into()));
            }
        }
        Ok(())
    }

    fn run_steps(
        &mut self,
        rig: &mut Rig<'_>,
        options: &RunOptions,
        progress: &mut dyn ProgressSink,
    ) -> Result<RunEnd, SessionError> {
        let total = self.plan.steps.len();
        let mut done = self.done();
        let mut new = 0usize;
        let start = Instant::now();
        let journal_path = self.journal.path().to_path_buf();
        for index in 0..total {
            if self.entries[index].is_some() {
                continue;
            }
            let missing = total - done;
            if options
                .interrupt
                .as_ref()
                .is_some_and(|i| i.load(Ordering::SeqCst))
            {
                return Ok(RunEnd::Interrupted { missing });
            }
            if options.stop_after.is_some_and(|n| new >= n) {
                return Ok(RunEnd::Stopped { missing });
            }
            let step = &self.plan.steps[index];
            let fail = |source: StepFailure| SessionError::Step {
                index,
                total,
                label: step.label.clone(),
                prepare: step.prepare.clone(),
                done,
                journal: journal_path.clone(),
                source: Box::new(source),
            };
            let mut taker = StepTaker {
                index,
                step,
                rig,
                journal: &mut self.journal,
                calibrations: &mut self.calibrations,
                progress,
            };
            let reading = match taker.take().map_err(fail)? {
                Some(r) => r,
                None => return Ok(RunEnd::Aborted { missing }),
            };
            let entry = Entry {
                index,
                label: step.label.clone(),
                role: step.role.clone(),
                mode: step.mode,
                data: step.data.clone(),
                reading,
            };
            self.journal
                .append(&entry)
                .map_err(|e| fail(StepFailure::Journal(e)))?;
            done += 1;
            new += 1;
            let elapsed = start.elapsed();
            progress.step(&StepProgress {
                done,
                total,
                index,
                label: &step.label,
                reading: &entry.reading,
                elapsed,
                remaining: elapsed.mul_f64((total - done) as f64 / new as f64),
            });
            self.entries[index] = Some(entry);
        }
        Ok(RunEnd::Complete)
    }
}

/// One step being taken, with what it needs borrowed from the session.
struct StepTaker<'s, 'r, 'a, H, D> {
    index: usize,
    step: &'s Step<D>,
    rig: &'r mut Rig<'a>,
    journal: &'s mut SessionJournal<H, D>,
    calibrations: &'s mut Vec<CalibrationRecord>,
    progress: &'s mut dyn ProgressSink,
}

impl<'a, H, D> StepTaker<'_, '_, 'a, H, D>
where
    H: Serialize + DeserializeOwned,
    D: Serialize + DeserializeOwned,
{
    /// The step's reading, or None when the operator aborted.
    fn take(&mut self) -> Result<Option<Reading>, StepFailure> {
        let request = Request {
            mode: self.step.mode,
        };
        let mut expired = 0;
        // The condition a measurement asked for when its calibration had expired.
        let mut asked = None;
        loop {
            if !self.calibrate(asked.take())? || !self.prepare()? {
                return Ok(None);
            }
            std::thread::sleep(self.step.settle);
            match self.instrument()?.measure(&request) {
                Ok(reading) => return Ok(Some(reading)),
                Err(DriverError::NeedsCalibration { condition, .. })
                    if expired < REMEASURE_ATTEMPTS =>
                {
                    expired += 1;
                    asked = Some(condition);
                }
                Err(DriverError::NeedsCalibration { .. }) => {
                    return Err(StepFailure::Expiring {
                        role: self.step.role.clone(),
                        mode: self.step.mode,
                        attempts: expired + 1,
                    })
                }
                Err(e) => return Err(e.into()),
            }
        }
    }

    fn instrument(&mut self) -> Result<&mut (dyn Instrument + 'a), StepFailure> {
        let role = &self.step.role;
        self.rig
            .instrument(role)
            .ok_or_else(|| StepFailure::NoInstrument(role.clone()))
    }

    /// Negotiates the calibration the step's instrument asks for, if any, or else the one
    /// a failed measurement `asked` for; false when the operator aborted.
    fn calibrate(&mut self, asked: Option<CalibrationCondition>) -> Result<bool, StepFailure> {
        let (role, mode) = (self.step.role.clone(), self.step.mode);
        let Some(mut condition) = self.instrument()?.calibration_needed(mode)?.or(asked) else {
            return Ok(true);
        };
        for _ in 0..CALIBRATION_ATTEMPTS {
            let model = self.instrument()?.info().model;
            let prompt = format!(
                "{role} instrument ({model}), {mode} calibration: {}",
                condition.prompt()
            );
            if self.ask(&prompt)? == Answer::Abort {
                return Ok(false);
            }
            let outcome = self.instrument()?.calibrate(mode, &condition)?;
            let record = CalibrationRecord {
                role: role.clone(),
                instrument: model,
                mode,
                condition: condition.clone(),
                before_step: self.index,
                time_s: metamer_drivers::instrument::now_s(),
            };
            self.journal.append_calibration(&record)?;
            self.progress.note(&format!(
                "calibrated the {role} instrument for {mode}: {}",
                condition.prompt()
            ));
            self.calibrations.push(record);
            match outcome {
                CalibrationOutcome::Done => return Ok(true),
                CalibrationOutcome::Needs(next) => condition = next,
            }
        }
        Err(StepFailure::Calibration {
            role,
            mode,
            attempts: CALIBRATION_ATTEMPTS,
            prompt: condition.prompt(),
        })
    }

    /// Asks the operator with the progress display out of the way.
    fn ask(&mut self, prompt: &str) -> Result<Answer, OperatorError> {
        let operator = &mut *self.rig.operator;
        let mut answer = Ok(Answer::Abort);
        self.progress.suspend(&mut || answer = operator.ask(prompt));
        answer
    }

    /// Sets the rig up for the step; false when the operator aborted.
    fn prepare(&mut self) -> Result<bool, StepFailure> {
        match &self.step.prepare {
            Prepare::Show { rgb } => {
                let screen = self.rig.screen.as_mut().ok_or(StepFailure::NoScreen)?;
                screen.show(*rgb).map_err(StepFailure::Screen)?;
                Ok(true)
            }
            Prepare::Operator { prompt } => Ok(self.ask(prompt)? == Answer::Confirmed),
            Prepare::None => Ok(true),
        }
    }
}
