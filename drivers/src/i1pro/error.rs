//! What can go wrong with an i1Pro, with what the user can do about it.

use metamer_protocols::i1pro::commands::ControlRequestError;
use metamer_protocols::i1pro::replies::ReplyError;
use metamer_protocols::i1pro::timing::TimingError;
use metamer_protocols::i1pro::{CalibrationError, EepromError, PipelineError, ReadingError};

/// An i1Pro failure. Link failures (timeout, stall, disconnect) are wrapped with the
/// request that was under way, so a message says what the instrument was doing.
#[derive(Debug, thiserror::Error)]
pub enum I1ProError {
    /// A reply of the wrong length or content.
    #[error("the i1Pro answered '{request}' with a reply that cannot be right: {source}")]
    Reply {
        request: &'static str,
        #[source]
        source: ReplyError,
    },
    /// The driver built a request the instrument's revision does not have (a driver bug).
    #[error("i1Pro request: {0}")]
    Request(#[from] ControlRequestError),
    /// The EEPROM could not be read as a directory of items.
    #[error("the i1Pro's EEPROM is not readable ({0}); unplug and replug it, and if it stays, the unit needs service")]
    Eeprom(#[from] EepromError),
    /// The EEPROM lacks or garbles a calibration item.
    #[error("the i1Pro's factory calibration in its EEPROM is unusable: {0}")]
    Calibration(#[from] CalibrationError),
    /// Fewer (or more) bytes than were asked for arrived on the data endpoint.
    #[error("the i1Pro sent {got} of the {expected} bytes of {what}; no reading was made from them (unplug and replug the instrument if this repeats)")]
    ShortRead {
        what: &'static str,
        got: usize,
        expected: usize,
    },
    /// Readings that parsed badly.
    #[error("the i1Pro's readings are malformed: {0}")]
    Readings(#[from] ReadingError),
    /// A pipeline step refused its input.
    #[error("processing the i1Pro's readings: {0}")]
    Pipeline(#[from] PipelineError),
    /// An integration time out of the instrument's range.
    #[error("i1Pro timing: {0}")]
    Timing(#[from] TimingError),
    /// The light saturates the sensor even at the shortest integration time.
    #[error("the light is too bright for the i1Pro: the sensor saturates even at its shortest integration time of {:.3} ms{}; measure a dimmer target or further away", ms(.min_s), one_mode_note(.one_mode))]
    TooBright {
        min_s: f64,
        /// The unit has one clock mode, so its shortest time is one sub-clock of it.
        one_mode: bool,
    },
    /// An integration time no clock mode of the unit can run (a driver bug: the driver
    /// keeps its times within the unit's range).
    #[error("an integration time of {seconds} s is outside what the i1Pro's clock modes can run (the shortest is {:.3} ms)", ms(.shortest_s))]
    IntegrationTime { seconds: f64, shortest_s: f64 },
    /// The clock modes the unit reports cannot be used.
    #[error("the i1Pro's clock modes cannot be used: {problem}; unplug and replug it, and if it stays, the unit needs service")]
    ClockModes { problem: String },
    /// A fixed integration time lets the sensor saturate.
    #[error("the i1Pro's sensor saturated at the fixed integration time of {integration_s} s; set a shorter integration time or let the instrument choose it (auto)")]
    SaturatedAtFixedTime { integration_s: f64 },
    /// No light distinguishable from the sensor's noise even at the longest integration time.
    #[error("too dark for the i1Pro: even at its longest integration time of {max_s:.3} s{} the light gives {:.0} counts over all cells, within the sensor's noise ({floor:.0} counts, 5σ); check that the instrument faces the light source and nothing covers it", over(*.readings), whole(.signal))]
    TooDark {
        max_s: f64,
        /// Readings averaged at it (more than one for a dim light worth reading longer).
        readings: usize,
        signal: f64,
        floor: f64,
    },
    /// A dark calibration saw light.
    #[error("the dark calibration saw light (mean {mean:.0} counts/s, limit {limit:.0}): place the instrument on its white tile, which covers the sensor, and calibrate again")]
    DarkNotDark { mean: f64, limit: f64 },
    /// Readings of one exposure disagreed (the light or the instrument moved).
    #[error("the i1Pro's readings of one exposure disagree by more than 10 %: keep the instrument and the target still while it measures")]
    Inconsistent,
    /// The unit did not leave low power.
    #[error("the i1Pro stays in low power after 1.5 s: plug it into a USB port that supplies full power (not an unpowered hub) and try again")]
    LowPower,
    /// A reflective sample saturated the sensor under the lamp.
    #[error("the sample saturated the i1Pro's sensor under its lamp (a fluorescent or glossy sample, or light leaking in): shade the sample and measure again")]
    SaturatedSample,
    /// A USB transfer failed.
    #[error(transparent)]
    Transfer(#[from] TransferError),
    /// The white-tile reading saturated or was too dim.
    #[error("the white-tile reading was {problem}: make sure the instrument sits flat on its own white tile and calibrate again")]
    BadWhite { problem: &'static str },
}

/// Rounded counts as they print, without a "-0" for a sum that is a hair below zero.
fn whole(c: &f64) -> f64 {
    c.round() + 0.0
}

/// How many readings a "too dark" verdict averaged, where more than one.
fn over(readings: usize) -> String {
    if readings > 1 {
        format!(", averaged over {readings} readings,")
    } else {
        String::new()
    }
}

fn ms(s: &f64) -> f64 {
    s * 1e3
}

fn one_mode_note(one: &bool) -> &'static str {
    if *one {
        " (this unit has no shorter clock mode)"
    } else {
        ""
    }
}

/// A USB transfer that failed, with the request it belonged to.
#[derive(Debug, thiserror::Error)]
#[error(
    "the i1Pro on {device} failed during '{request}': {source}{}",
    advice(source)
)]
pub struct TransferError {
    pub device: String,
    pub request: &'static str,
    #[source]
    pub source: crate::link::LinkError,
}

fn advice(e: &crate::link::LinkError) -> &'static str {
    use crate::link::LinkError;
    match e {
        LinkError::Timeout { .. } => "; unplug and replug the instrument and try again",
        LinkError::Stalled { .. } => "; the instrument refused it (reset it by replugging)",
        _ => "",
    }
}
