//! Spot readings with the calibration negotiated through an [`Operator`]: before each
//! reading the instrument is asked what calibration is due, the operator is asked to set
//! it up (the instrument's own words), and a reading refused because a calibration expired
//! meanwhile is negotiated again and repeated. For a simulated instrument the simulated
//! world plays the operator's hands: confirming "place the instrument on its white tile"
//! puts it on the tile, and after the calibration it goes back to the target.

use std::sync::Arc;

use metamer_drivers::{
    CalibrationCondition, CalibrationOutcome, DriverError, Instrument, MeasureMode, Reading,
    Request, SharedWorld, View,
};

use crate::session::{Answer, Operator, OperatorError};

/// A spot reading that could not be made.
#[derive(Debug, thiserror::Error)]
pub enum SpotError {
    #[error(transparent)]
    Driver(#[from] DriverError),
    #[error(transparent)]
    Operator(#[from] OperatorError),
    /// The operator declined to set up a calibration.
    #[error("stopped: the operator declined to {0}")]
    Declined(String),
    /// The instrument kept asking for calibrations (a driver that never answers Done).
    #[error("the {instrument} still asks for a calibration after {rounds} rounds; giving up")]
    Endless { instrument: String, rounds: usize },
}

/// Where a simulated instrument is: the world it sees and the target it is aimed at or
/// placed on between calibrations.
#[derive(Clone)]
pub struct SimulatedHands {
    pub world: Arc<SharedWorld>,
    pub target: View,
}

impl SimulatedHands {
    fn place(&self, condition: &CalibrationCondition) {
        self.world.set(match condition {
            CalibrationCondition::OnWhiteTile => View::WhiteTile,
            CalibrationCondition::SensorCapped => View::Capped,
            _ => self.target.clone(),
        });
    }

    fn back(&self) {
        self.world.set(self.target.clone());
    }
}

/// At most this many calibration rounds before one reading.
const MAX_ROUNDS: usize = 8;

/// Negotiates every calibration `mode` needs now: each condition is shown to `operator`,
/// then the instrument calibrates.
pub fn calibrate(
    instrument: &mut dyn Instrument,
    mode: MeasureMode,
    operator: &mut dyn Operator,
    hands: Option<&SimulatedHands>,
) -> Result<(), SpotError> {
    let mut next = instrument.calibration_needed(mode)?;
    let mut rounds = 0;
    while let Some(condition) = next {
        rounds += 1;
        if rounds > MAX_ROUNDS {
            return Err(SpotError::Endless {
                instrument: instrument.info().model,
                rounds: MAX_ROUNDS,
            });
        }
        let prompt = format!("{}: {}", instrument.info().model, condition.prompt());
        if operator.ask(&prompt)? == Answer::Abort {
            return Err(SpotError::Declined(condition.prompt()));
        }
        if let Some(h) = hands {
            h.place(&condition);
        }
        let outcome = instrument.calibrate(mode, &condition);
        if let Some(h) = hands {
            h.back();
        }
        next = match outcome? {
            CalibrationOutcome::Done => instrument.calibration_needed(mode)?,
            CalibrationOutcome::Needs(c) => Some(c),
        };
    }
    Ok(())
}

/// One reading in `mode`, calibrating first where needed and again when a calibration
/// expires before the reading.
pub fn read(
    instrument: &mut dyn Instrument,
    mode: MeasureMode,
    operator: &mut dyn Operator,
    hands: Option<&SimulatedHands>,
) -> Result<Reading, SpotError> {
    let request = Request { mode };
    for _ in 0..MAX_ROUNDS {
        calibrate(instrument, mode, operator, hands)?;
        match instrument.measure(&request) {
            Err(DriverError::NeedsCalibration { .. }) => continue,
            r => return Ok(r?),
        }
    }
    Err(SpotError::Endless {
        instrument: instrument.info().model,
        rounds: MAX_ROUNDS,
    })
}

/// The spectra of several readings as the colour core's spectral CSV: a `#` line saying what
/// they are, `nm` and one column per reading (`reading1`, …), one row per wavelength.
/// Values are written in Rust's shortest round-trip form, so reading the file back gives
/// the very numbers the instrument reported. None when no reading has a spectrum or their
/// wavelengths differ.
pub fn spectra_csv(readings: &[Reading]) -> Option<String> {
    let spectra: Vec<_> = readings
        .iter()
        .map(|r| r.spectrum.as_ref())
        .collect::<Option<_>>()?;
    let first = spectra.first()?;
    if spectra
        .iter()
        .any(|s| s.wavelengths_nm() != first.wavelengths_nm())
    {
        return None;
    }
    let unit = first.quantity().map(|q| q.unit()).unwrap_or("unknown unit");
    let mut out = format!(
        "# {} readings of the {}, {unit}\nnm",
        readings.len(),
        readings[0].instrument
    );
    for i in 1..=readings.len() {
        out.push_str(&format!(",reading{i}"));
    }
    out.push('\n');
    for (k, nm) in first.wavelengths_nm().iter().enumerate() {
        out.push_str(&nm.to_string());
        for s in &spectra {
            out.push_str(&format!(",{}", s.values()[k]));
        }
        out.push('\n');
    }
    Some(out)
}
