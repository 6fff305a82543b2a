//! Taking one step: negotiate the calibration its instrument asks for, prepare the rig,
//! settle, measure, and on an expired calibration negotiate and measure again (bounded).
//!
//! Calibration comes before preparation: a calibration has the operator move the
//! instrument (onto its white tile, under a cap), so the step's own setup must follow it.

use metamer_drivers::{
    CalibrationCondition, CalibrationOutcome, DriverError, Instrument, MeasureMode, Reading,
    Request,
};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::time::Instant;

use super::budget::Cost;
use super::journal::{CalibrationRecord, JournalError};
use super::operator::{Answer, Operator, OperatorError, PlacementReadings};
use super::plan::{Prepare, Step};
use super::progress::{Heartbeat, ProgressSink};
use super::record::SessionJournal;
use super::screen::Screen;

/// What the session runs on: a screen where steps show drive values, the instruments by
/// role, and the operator.
pub struct Rig<'a> {
    pub screen: Option<&'a mut dyn Screen>,
    pub instruments: Vec<(String, &'a mut dyn Instrument)>,
    pub operator: &'a mut dyn Operator,
}

impl<'a> Rig<'a> {
    pub(super) fn instrument(&mut self, role: &str) -> Option<&mut (dyn Instrument + 'a)> {
        self.instruments
            .iter_mut()
            .find(|(r, _)| r == role)
            .map(|(_, i)| &mut **i)
    }
}

/// Calibration conditions asked for in one negotiation before giving up: instruments ask
/// for a few in a row (dark, then white tile); more means the operator's action did not
/// satisfy the instrument.
pub const CALIBRATION_ATTEMPTS: usize = 5;
/// Times a step is measured again after its calibration expired during the measurement.
pub const REMEASURE_ATTEMPTS: usize = 2;

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

/// What the operator is asked after a calibration moved the instrument (onto its tile, under
/// a cap) before a step that shows a colour: the screen step has no placement prompt of its
/// own, so without it the instrument would read its tile or its cap.
pub const AIM_AT_SCREEN_AGAIN: &str = "aim the instrument at the screen again";

/// Noise streams with this bit set are calibrations' (see [`StepTaker::calibrate`]); plan
/// indices never reach it.
const CALIBRATION_NOISE: u64 = 1 << 63;

/// One step being taken, with what it needs borrowed from the session.
pub(super) struct StepTaker<'s, 'r, 'a, H, D> {
    pub(super) index: usize,
    pub(super) step: &'s Step<D>,
    pub(super) rig: &'r mut Rig<'a>,
    pub(super) journal: &'s mut SessionJournal<H, D>,
    pub(super) calibrations: &'s mut Vec<CalibrationRecord>,
    /// How many of `calibrations` were journalled by earlier runs of the session.
    pub(super) earlier_calibrations: usize,
    pub(super) progress: &'s mut dyn ProgressSink,
    /// The steps of this step's placement (see [`super::plan::placements`]).
    pub(super) placement: Option<std::ops::Range<usize>>,
    /// The first step of the placement the operator set up in this run, while it stands:
    /// its later readings are taken without asking again. A calibration (the instrument
    /// moved to its tile or capped) clears it.
    pub(super) placed: &'s mut Option<usize>,
    /// What the run has taken so far, added to as the step is taken.
    pub(super) spent: &'s mut Cost,
    /// Wall seconds in each of the rig's instruments' calls (by their order in the rig),
    /// the instrument time of those that do not count their own.
    pub(super) wall_in_calls: &'s mut [f64],
}

impl<'a, H, D> StepTaker<'_, '_, 'a, H, D>
where
    H: Serialize + DeserializeOwned,
    D: Serialize + DeserializeOwned,
{
    /// The step's reading, or None when the operator aborted.
    pub(super) fn take(&mut self) -> Result<Option<Reading>, StepFailure> {
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
            self.spent.settle_s += self.step.settle.as_secs_f64();
            let model = self.instrument()?.info().model;
            let beat = Heartbeat::start(format!(
                "the {} instrument ({model}) measures {}",
                self.step.role, self.step.label
            ));
            let called = Instant::now();
            let measured = self.instrument()?.measure(&request);
            self.in_call(called);
            drop(beat);
            match measured {
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

    /// Adds the wall time since `called` to the step's instrument's calls.
    fn in_call(&mut self, called: Instant) {
        let role = &self.step.role;
        if let Some(k) = self.rig.instruments.iter().position(|(r, _)| r == role) {
            self.wall_in_calls[k] += called.elapsed().as_secs_f64();
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
    ///
    /// A simulated instrument's calibration draws its noise from a stream of its own, keyed
    /// by the step of the calibration it stands for, and the step's reading then draws from
    /// the step's stream as if no calibration had come before it. A resumed session must
    /// calibrate again (a new process has a new device) and stands for the calibration in
    /// force when the earlier run stopped: so it calibrates, and then reads, exactly as the
    /// uninterrupted session did.
    fn calibrate(&mut self, asked: Option<CalibrationCondition>) -> Result<bool, StepFailure> {
        let mode = self.step.mode;
        let Some(condition) = self.instrument()?.calibration_needed(mode)?.or(asked) else {
            return Ok(true);
        };
        let noise_step = self.calibration_noise_step();
        self.instrument()?
            .seek_noise(CALIBRATION_NOISE | noise_step as u64);
        let done = self.negotiate(condition, noise_step);
        let index = self.index as u64;
        self.instrument()?.seek_noise(index);
        done
    }

    /// The step whose calibration noise a calibration now draws: this step's, unless this
    /// run has not yet calibrated the role's instrument for the mode and an earlier run
    /// did — then the one that earlier run's last such calibration drew.
    fn calibration_noise_step(&self) -> usize {
        let (role, mode) = (&self.step.role, self.step.mode);
        let same = |c: &&CalibrationRecord| &c.role == role && c.mode == mode;
        let (earlier, this_run) = self.calibrations.split_at(self.earlier_calibrations);
        if this_run.iter().any(|c| same(&c)) {
            return self.index;
        }
        earlier
            .iter()
            .rev()
            .find(same)
            .map_or(self.index, |c| c.noise_step.unwrap_or(c.before_step))
    }

    /// Has the operator set up each condition the calibration asks for and journals it.
    fn negotiate(
        &mut self,
        mut condition: CalibrationCondition,
        noise_step: usize,
    ) -> Result<bool, StepFailure> {
        let (role, mode) = (self.step.role.clone(), self.step.mode);
        let mut moved = false;
        for _ in 0..CALIBRATION_ATTEMPTS {
            moved |= condition != CalibrationCondition::OnTarget;
            let model = self.instrument()?.info().model;
            let prompt = format!(
                "{role} instrument ({model}), {mode} calibration: {}",
                condition.prompt()
            );
            if self.ask(&prompt)? == Answer::Abort {
                return Ok(false);
            }
            let beat = Heartbeat::start(format!(
                "the {role} instrument ({model}) calibrates for {mode} readings"
            ));
            let called = Instant::now();
            let outcome = self.instrument()?.calibrate(mode, &condition);
            self.in_call(called);
            drop(beat);
            let outcome = outcome?;
            let record = CalibrationRecord {
                role: role.clone(),
                instrument: model.clone(),
                mode,
                condition: condition.clone(),
                before_step: self.index,
                noise_step: Some(noise_step),
                time_s: metamer_drivers::instrument::now_s(),
            };
            self.journal.append_calibration(&record)?;
            self.calibrations.push(record);
            self.spent.calibrations += 1;
            // Whatever the operator had set up, the instrument was moved for this.
            *self.placed = None;
            let how = calibrated(&condition);
            match outcome {
                CalibrationOutcome::Done => {
                    self.progress.note(&format!(
                        "calibrated the {role} instrument ({model}) for {mode} readings {how}"
                    ));
                    let on_screen = matches!(
                        self.step.prepare,
                        Prepare::Show { .. } | Prepare::ShiftImage { .. }
                    );
                    if moved && on_screen {
                        let prompt = format!("{role} instrument ({model}): {AIM_AT_SCREEN_AGAIN}");
                        return Ok(self.ask(&prompt)? == Answer::Confirmed);
                    }
                    return Ok(true);
                }
                CalibrationOutcome::Needs(next) => {
                    self.progress.note(&format!(
                        "the {role} instrument ({model}) took its {mode} calibration reading {how}; it needs one more"
                    ));
                    condition = next;
                }
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
        let asked = Instant::now();
        self.progress.suspend(&mut || answer = operator.ask(prompt));
        self.spent.operator_s += asked.elapsed().as_secs_f64();
        answer
    }

    /// Sets the rig up for the step; false when the operator aborted.
    fn prepare(&mut self) -> Result<bool, StepFailure> {
        match &self.step.prepare {
            Prepare::Show { rgb } => {
                let screen = self.rig.screen.as_mut().ok_or(StepFailure::NoScreen)?;
                screen
                    .show(*rgb)
                    .map_err(|e| StepFailure::Screen(Box::new(e)))?;
                Ok(true)
            }
            Prepare::ShiftImage { by } => {
                let screen = self.rig.screen.as_mut().ok_or(StepFailure::NoScreen)?;
                screen
                    .shift_image(*by)
                    .map_err(|e| StepFailure::Screen(Box::new(e)))?;
                Ok(true)
            }
            Prepare::Operator { prompt } => {
                let Some(range) = self.placement.clone() else {
                    let confirmed = self.ask(prompt)? == Answer::Confirmed;
                    self.spent.placements += usize::from(confirmed);
                    return Ok(confirmed);
                };
                if *self.placed == Some(range.start) {
                    return Ok(true);
                }
                let readings = PlacementReadings {
                    first: self.index - range.start + 1,
                    of: range.len(),
                };
                let operator = &mut *self.rig.operator;
                let mut answer = Ok(Answer::Abort);
                let asked = Instant::now();
                self.progress
                    .suspend(&mut || answer = operator.ask_placement(prompt, readings));
                self.spent.operator_s += asked.elapsed().as_secs_f64();
                let confirmed = answer? == Answer::Confirmed;
                if confirmed {
                    *self.placed = Some(range.start);
                    self.spent.placements += 1;
                }
                Ok(confirmed)
            }
            Prepare::None => Ok(true),
        }
    }
}

/// How a calibration was taken, said after it: `on its white calibration tile`.
fn calibrated(condition: &CalibrationCondition) -> String {
    match condition {
        CalibrationCondition::OnWhiteTile => "on its white calibration tile".into(),
        CalibrationCondition::SensorCapped => "with its sensor capped".into(),
        CalibrationCondition::OnTarget => "aimed at the target".into(),
        CalibrationCondition::Other(s) => format!("({s})"),
    }
}
