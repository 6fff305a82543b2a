//! Taking a plan's steps: for each step the journal lacks, in plan order, take it (calibrate
//! if due, prepare — the operator asked once per placement —, settle, measure:
//! [`super::step`]), report it, put a reading its instrument cannot have repeated to the
//! operator ([`super::repeats`]: read again, keep, stop), append the entry; stop before the
//! next step on an interrupt.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use metamer_drivers::registry::Repeatability;
use metamer_drivers::{MeasureMode, Reading};
use serde::de::DeserializeOwned;
use serde::Serialize;

use super::budget::{estimate, Cost, Meter, PLACEMENT_S};
use super::journal::{
    CalibrationRecord, Header, Journal, JournalError, JOURNAL_FORMAT, JOURNAL_VERSION,
};
use super::operator::Recheck;
use super::plan::{placements, Prepare, SessionPlan, Step};
use super::progress::{reading_summary, ProgressSink, StepProgress};
use super::record::{Entry, InstrumentRecord, SessionHeader, SessionJournal};
use super::repeats::deviation;
use super::step::{Rig, StepFailure, StepTaker};

mod error;
mod resume;
mod stopping;
pub use error::{SessionError, SettingDiffers};
use resume::{duplicates_note, place_entries, same_instrument};
pub use stopping::patch_so_far;

/// How to run.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Stop after this many new entries (an interruption on purpose, for tests and for
    /// splitting a long session).
    pub stop_after: Option<usize>,
    /// Set from elsewhere (a Ctrl-C handler) to stop before the next step.
    pub interrupt: Option<Arc<AtomicBool>>,
    /// The operator's time per placement the budget assumes; None: [`PLACEMENT_S`].
    pub placement_s: Option<f64>,
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

impl RunOptions {
    /// The operator's time per placement the budget assumes.
    pub fn placement_s(&self) -> f64 {
        self.placement_s.unwrap_or(PLACEMENT_S)
    }

    /// How a run ends before its next step, with `missing` steps missing, when it has taken
    /// `new` steps: interrupted, or stopped after as many as asked; None to go on.
    fn end_before_step(&self, new: usize, missing: usize) -> Option<RunEnd> {
        if self
            .interrupt
            .as_ref()
            .is_some_and(|i| i.load(Ordering::SeqCst))
        {
            return Some(RunEnd::Interrupted { missing });
        }
        if self.stop_after.is_some_and(|n| new >= n) {
            return Some(RunEnd::Stopped { missing });
        }
        None
    }
}

impl RunEnd {
    /// Whether the run was interrupted (Ctrl-C, a signal): a failure to the caller, though
    /// every reading taken is safe.
    pub fn is_interrupted(&self) -> bool {
        matches!(self, RunEnd::Interrupted { .. })
    }
}

/// Which steps of a plan need not be taken, from the entries journalled so far: a rule
/// that ends a target's repeats once they decide it. It must depend on nothing but the
/// plan and the entries before the step, so a resumed session and a re-run skip what the
/// first run skipped.
pub trait Stopping<D>: Send {
    /// Whether step `index` is skipped, given every step's entry so far (`None`: not
    /// taken, or skipped).
    fn skip(
        &self,
        index: usize,
        steps: &[super::plan::Step<D>],
        entries: &[Option<Entry<D>>],
    ) -> bool;
}

/// A session bound to its journal.
pub struct Session<H, D> {
    plan: SessionPlan<D>,
    stopping: Option<Box<dyn Stopping<D>>>,
    journal: SessionJournal<H, D>,
    entries: Vec<Option<Entry<D>>>,
    calibrations: Vec<CalibrationRecord>,
    /// Calibrations found in the journal when the session was resumed.
    earlier_calibrations: usize,
    /// Entries found in the journal when the session was resumed.
    pub recovered: usize,
    /// Bytes of a torn last line set aside on resuming (0 if none).
    pub torn_bytes: usize,
    /// Where a journal that held no session (empty, torn header) was moved on resuming.
    pub set_aside: Option<PathBuf>,
    /// What resuming repaired that the operator should know (readings of a second session
    /// set aside); [`Session::run`] reports them first.
    pub notes: Vec<String>,
    /// What this process's runs took.
    spent: Cost,
}

/// The repeatability stated for the instrument in `role` in `mode` (its model's, or a
/// default when the rig has none in that role).
fn stated_repeatability(rig: &mut Rig<'_>, role: &str, mode: MeasureMode) -> Repeatability {
    let model = rig
        .instrument(role)
        .map(|i| i.info().model)
        .unwrap_or_default();
    metamer_drivers::registry::stated_repeatability(&model, mode)
}

/// What the operator is asked about when step `index` (`label`) differs from the readings
/// before it in its placement.
fn what_differs(placement: &Option<std::ops::Range<usize>>, index: usize, label: &str) -> String {
    match placement {
        Some(r) => format!(
            "reading {}/{} ({}) differs",
            index - r.start + 1,
            r.len(),
            label
        ),
        None => format!("{label} differs"),
    }
}

/// How far `reading` of step `index` lies from the readings before it in its placement
/// (earlier runs' included), beyond the instrument's `repeatability`; None within it or
/// for the first reading.
fn deviation_from_earlier<D>(
    entries: &[Option<Entry<D>>],
    placement: &Option<std::ops::Range<usize>>,
    index: usize,
    reading: &Reading,
    repeatability: Repeatability,
) -> Option<super::repeats::Deviation> {
    let earlier: Vec<&Reading> = placement
        .clone()
        .map(|r| r.start..index)
        .into_iter()
        .flatten()
        .filter_map(|i| entries[i].as_ref().map(|e| &e.reading))
        .collect();
    deviation(&earlier, reading, repeatability)
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
            crate::output::OutputPolicy::new(false).dir(dir)?;
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
        let mut set_aside = None;
        let resumed = if resume && path.exists() {
            match Journal::resume(path, &header) {
                Ok(r) => Some(r),
                // Nothing was measured into it: keep it for inspection, start afresh.
                Err(JournalError::Broken { .. }) => {
                    set_aside = Some(super::journal::set_aside(path)?);
                    None
                }
                Err(e) => return Err(e.into()),
            }
        } else {
            None
        };
        let Some((journal, recovered)) = resumed else {
            let journal = Journal::create(path, &header)?;
            return Ok(Session {
                plan,
                stopping: None,
                journal,
                entries,
                calibrations: Vec::new(),
                earlier_calibrations: 0,
                recovered: 0,
                torn_bytes: 0,
                set_aside,
                notes: Vec::new(),
                spent: Cost::default(),
            });
        };
        let journal: SessionJournal<H, D> = journal;
        for (role, now) in &header.data.instruments {
            if let Some(logged) = recovered.header.data.instruments.get(role) {
                same_instrument(path, role, logged, now)?;
            }
        }
        let n = recovered.entries.len();
        place_entries(path, &plan, recovered.entries, &mut entries)?;
        let notes = duplicates_note(path, &recovered.duplicates)
            .into_iter()
            .collect();
        Ok(Session {
            plan,
            stopping: None,
            journal,
            entries,
            earlier_calibrations: recovered.calibrations.len(),
            calibrations: recovered.calibrations,
            recovered: n,
            torn_bytes: recovered.torn_bytes,
            set_aside: None,
            notes,
            spent: Cost::default(),
        })
    }

    pub fn plan(&self) -> &SessionPlan<D> {
        &self.plan
    }

    pub fn journal_path(&self) -> &Path {
        self.journal.path()
    }

    /// Ends targets' repeats by `stopping`'s rule.
    pub fn with_stopping(mut self, stopping: Box<dyn Stopping<D>>) -> Self {
        self.stopping = Some(stopping);
        self
    }

    /// Whether step `index` is skipped by the stopping rule.
    fn skipped(&self, index: usize) -> bool {
        self.entries[index].is_none()
            && self
                .stopping
                .as_ref()
                .is_some_and(|s| s.skip(index, &self.plan.steps, &self.entries))
    }

    /// Whether step `index` needs no taking now: journalled, or skipped by the stopping
    /// rule (then counted into `done`).
    fn passed_over(&self, index: usize, done: &mut usize) -> bool {
        if self.entries[index].is_some() {
            return true;
        }
        let skipped = self.skipped(index);
        *done += usize::from(skipped);
        skipped
    }

    /// Steps settled: in the journal, or skipped by the stopping rule.
    pub fn done(&self) -> usize {
        (0..self.entries.len())
            .filter(|&i| self.entries[i].is_some() || self.skipped(i))
            .count()
    }

    /// Steps in the journal (readings taken).
    pub fn taken(&self) -> usize {
        self.entries.iter().filter(|e| e.is_some()).count()
    }

    /// Every calibration journalled, earlier runs' included, in the order done.
    pub fn calibrations(&self) -> &[CalibrationRecord] {
        &self.calibrations
    }

    /// The cost of the steps the journal lacks ([`estimate`]), with the rig's instruments
    /// as `meters`, each step's expected light from `light` (where it comes from said by
    /// `light_assumption`) and `placement_s` seconds per placement.
    pub fn estimate(
        &self,
        meters: &BTreeMap<String, Meter>,
        light: &dyn Fn(&Step<D>) -> f64,
        light_assumption: &str,
        placement_s: f64,
    ) -> Cost {
        estimate(
            &self.plan,
            &|i| self.entries[i].is_some(),
            meters,
            light,
            light_assumption,
            placement_s,
        )
    }

    /// What this process's runs of the session took: the readings journalled, the
    /// placements the operator confirmed, the calibrations, the instruments' own time (a
    /// simulation's at the real pace, whatever its time scale; a real instrument's by the
    /// clock around its calls), the time requests waited for the operator, the settle
    /// waits, and the wall time of the runs.
    pub fn spent(&self) -> &Cost {
        &self.spent
    }

    /// Every entry in plan order; None until every step is measured or skipped by the
    /// stopping rule.
    pub fn complete_entries(&self) -> Option<Vec<&Entry<D>>> {
        let mut all = Vec::with_capacity(self.entries.len());
        for (i, e) in self.entries.iter().enumerate() {
            match e {
                Some(e) => all.push(e),
                None if self.skipped(i) => {}
                None => return None,
            }
        }
        Some(all)
    }

    /// Takes every step the journal lacks, in plan order.
    pub fn run(
        &mut self,
        rig: &mut Rig<'_>,
        options: &RunOptions,
        progress: &mut dyn ProgressSink,
    ) -> Result<RunEnd, SessionError> {
        self.check_rig(rig)?;
        for note in std::mem::take(&mut self.notes) {
            progress.note(&note);
        }
        let total = self.plan.steps.len();
        progress.start(self.done(), total);
        let started = Instant::now();
        let clocks: Vec<Option<f64>> = rig
            .instruments
            .iter()
            .map(|(_, i)| i.instrument_time_s())
            .collect();
        let mut wall_in_calls = vec![0.0; clocks.len()];
        let result = self.run_steps(rig, options, progress, &mut wall_in_calls);
        // An instrument that counts its own time says it; another's is the clock's around
        // its calls.
        for (k, (_, instrument)) in rig.instruments.iter().enumerate() {
            self.spent.instrument_s += match (clocks[k], instrument.instrument_time_s()) {
                (Some(before), Some(after)) => after - before,
                _ => wall_in_calls[k],
            };
        }
        self.spent.wall_s += started.elapsed().as_secs_f64();
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
            if matches!(step.prepare, Prepare::ShiftImage { .. }) && !has_screen {
                return Err(lacks("slides an image and the rig has no screen".into()));
            }
        }
        Ok(())
    }

    fn run_steps(
        &mut self,
        rig: &mut Rig<'_>,
        options: &RunOptions,
        progress: &mut dyn ProgressSink,
        wall_in_calls: &mut [f64],
    ) -> Result<RunEnd, SessionError> {
        let total = self.plan.steps.len();
        let mut placed = None;
        let mut done = self.taken();
        let mut new = 0usize;
        let start = Instant::now();
        let journal_path = self.journal.path().to_path_buf();
        for (index, placement) in placements(&self.plan.steps).into_iter().enumerate() {
            if self.passed_over(index, &mut done) {
                continue;
            }
            let missing = total - done;
            if let Some(end) = options.end_before_step(new, missing) {
                return Ok(end);
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
            // Step k's noise is the same whichever run takes it (see Instrument::seek_noise).
            if let Some(instrument) = rig.instrument(&step.role) {
                instrument.seek_noise(index as u64);
            }
            let reading = loop {
                let mut taker = StepTaker {
                    index,
                    step,
                    rig,
                    journal: &mut self.journal,
                    calibrations: &mut self.calibrations,
                    earlier_calibrations: self.earlier_calibrations,
                    progress,
                    placement: placement.clone(),
                    placed: &mut placed,
                    spent: &mut self.spent,
                    wall_in_calls: &mut *wall_in_calls,
                };
                let Some(reading) = taker.take().map_err(fail)? else {
                    return Ok(RunEnd::Aborted { missing });
                };
                let repeatability = stated_repeatability(rig, &step.role, step.mode);
                let deviation = deviation_from_earlier(
                    &self.entries,
                    &placement,
                    index,
                    &reading,
                    repeatability,
                );
                let elapsed = start.elapsed();
                progress.step(&StepProgress {
                    done: done + 1,
                    total,
                    index,
                    label: &step.label,
                    mode: step.mode,
                    reading: &reading,
                    elapsed,
                    remaining: elapsed.mul_f64((total - done - 1) as f64 / (new + 1) as f64),
                    placement: placement.as_ref().map(|r| (index - r.start + 1, r.len())),
                    deviation: deviation.as_ref(),
                });
                if deviation.is_none() {
                    break reading;
                }
                let why = what_differs(&placement, index, &step.label);
                let answer = recheck(&mut *rig.operator, progress, &mut self.spent, &why);
                match answer.map_err(|e| fail(StepFailure::Operator(e)))? {
                    Recheck::Keep => break reading,
                    Recheck::Stop => return Ok(RunEnd::Aborted { missing }),
                    Recheck::Again => {
                        let again = reading_summary(step.mode, &reading);
                        progress.note(&format!("  set aside: {again}; reading it again"));
                        // The operator re-aimed and confirmed: the placement stands.
                        placed = placement.as_ref().map(|r| r.start);
                    }
                }
            };
            let entry = Entry::of_step(index, step, reading);
            self.journal
                .append(&entry)
                .map_err(|e| fail(StepFailure::Journal(e)))?;
            done += 1;
            new += 1;
            self.spent.readings += 1;
            self.entries[index] = Some(entry);
        }
        Ok(RunEnd::Complete)
    }
}

/// Puts a reading that differs (`why`) to the operator with the progress display out of
/// the way; the time it waits is the operator's, and reading again is a placement.
fn recheck(
    operator: &mut dyn super::operator::Operator,
    progress: &mut dyn ProgressSink,
    spent: &mut Cost,
    why: &str,
) -> Result<Recheck, super::operator::OperatorError> {
    let mut answer = Ok(Recheck::Keep);
    let asked = Instant::now();
    progress.suspend(&mut || answer = operator.recheck(why));
    spent.operator_s += asked.elapsed().as_secs_f64();
    if matches!(answer, Ok(Recheck::Again)) {
        spent.placements += 1;
    }
    answer
}
