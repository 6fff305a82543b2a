//! Konica Minolta CS-100A chroma meter driver, generic over its serial link, so the real
//! port, a replayed transcript and the emulator run the same code. Facts, their sources and
//! tags: `protocols/cs100a/README.md`; codec: `metamer_protocols::cs100a`.
//!
//! Session: `MDS,04` (absolute Yxy) on connect, `MDS,06`/`MDS,07` (FAST/SLOW) whenever the
//! requested speed differs from the one last set, then `MES` per reading. Every exchange
//! discards stale input first (PP and VCC do the same, [C2]).

pub mod budget;
pub mod emulator;
pub mod error;
pub mod open;
#[cfg(unix)]
pub mod pty;

use std::time::Duration;

use metamer_protocols::cs100a::{self, Command, Mode, Reply, Status, Yxy};
use metamer_protocols::transcript::show_bytes;

use serde::{Deserialize, Serialize};

use crate::instrument::{
    CalibrationCondition, CalibrationOutcome, Capabilities, Flag, Instrument, InstrumentInfo,
    MeasureMode, ModeInfo, OptionInfo, OptionValues, Reading, Request,
};
use crate::link::{LinkError, SerialLink};
use crate::DriverError;
pub use error::Cs100aError;

/// Model name used in readings, transcripts and specs.
pub const MODEL: &str = "cs100a";

/// How long to wait for a reply. PP, VCC and PGL wait 5 s ([C2]); the LS-100 itself gives
/// up on a half-sent command after 5 s (KM-LS p.13, [C]); SLOW takes ≈0.4 s plus ≈64 ms of
/// wire time, so 5 s never cuts off a meter that is answering.
pub const REPLY_TIMEOUT: Duration = Duration::from_secs(5);

/// The meter's response speed (its `MDS,06`/`MDS,07` modes), the CS-100A's one
/// model-specific option (`speed=fast|slow`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Speed {
    /// FAST, ≈100 ms.
    #[default]
    Fast,
    /// SLOW, ≈400 ms, for dark or flickering targets.
    Slow,
}

impl Speed {
    pub fn name(self) -> &'static str {
        match self {
            Speed::Fast => "fast",
            Speed::Slow => "slow",
        }
    }
}

/// The name of the speed option.
pub const SPEED_OPTION: &str = "speed";

/// The response time of a speed setting, seconds (MC2, VB, VCC comments; [C2]).
pub fn response_time_s(speed: Speed) -> f64 {
    match speed {
        Speed::Fast => 0.1,
        Speed::Slow => 0.4,
    }
}

/// A CS-100A on a serial link.
pub struct Cs100a<L: SerialLink> {
    link: L,
    /// Speed last acknowledged by the meter; None until set (the meter keeps whatever its
    /// front panel or an earlier session chose).
    speed: Option<Speed>,
    /// Speed the next measurement uses (the `speed` option).
    wanted_speed: Speed,
    absolute: bool,
    timeout: Duration,
    /// The meter has answered at least once on this link, so silence now means it went
    /// away rather than that it was never in remote mode.
    answered: bool,
    /// Replies that were rejected and retried (see [`Cs100a::exchange`]).
    rejected: Vec<String>,
}

impl<L: SerialLink> Cs100a<L> {
    /// Wraps a link; nothing is sent until [`Cs100a::connect`] or the first measurement.
    pub fn new(link: L) -> Cs100a<L> {
        Cs100a {
            link,
            speed: None,
            wanted_speed: Speed::Fast,
            absolute: false,
            timeout: REPLY_TIMEOUT,
            answered: false,
            rejected: Vec::new(),
        }
    }

    /// Changes how long to wait for each reply.
    pub fn with_timeout(mut self, timeout: Duration) -> Cs100a<L> {
        self.timeout = timeout;
        self
    }

    /// Puts the meter in absolute Yxy mode; a meter that is not in remote mode fails here,
    /// with the instructions to fix it.
    pub fn connect(&mut self) -> Result<(), DriverError> {
        self.ack(Command::SetMode(Mode::Absolute))?;
        self.absolute = true;
        Ok(())
    }

    /// Sets FAST or SLOW response.
    pub fn set_speed(&mut self, speed: Speed) -> Result<(), DriverError> {
        let mode = match speed {
            Speed::Fast => Mode::Fast,
            Speed::Slow => Mode::Slow,
        };
        self.ack(Command::SetMode(mode))?;
        self.speed = Some(speed);
        Ok(())
    }

    /// One `MES`: the status and the values as sent.
    pub fn measure_yxy(&mut self) -> Result<(Status, Yxy), DriverError> {
        match self.exchange(Command::Measure)? {
            Reply::Measurement { status, value } => Ok((status, value)),
            Reply::Code(status) if !status.is_ok() => {
                Err(self.instrument_error(Command::Measure, status))
            }
            Reply::Code(status) => Err(Cs100aError::UnexpectedReply {
                port: self.link.describe(),
                command: Command::Measure.text(),
                received: status.code().to_string(),
                reason: "a measurement must carry Y, x and y".into(),
            }
            .into()),
        }
    }

    /// The link, e.g. to check that a replay was played to its end.
    pub fn link(&self) -> &L {
        &self.link
    }

    /// Gives the link back.
    pub fn into_link(self) -> L {
        self.link
    }

    fn ack(&mut self, command: Command) -> Result<(), DriverError> {
        match self.exchange(command)? {
            Reply::Code(Status::Ok00) => Ok(()),
            Reply::Code(status) if !status.is_ok() => Err(self.instrument_error(command, status)),
            other => Err(Cs100aError::UnexpectedReply {
                port: self.link.describe(),
                command: command.text(),
                received: format!("{other:?}"),
                reason: "expected the acknowledgement OK00".into(),
            }
            .into()),
        }
    }

    fn instrument_error(&self, command: Command, status: Status) -> DriverError {
        Cs100aError::Instrument {
            port: self.link.describe(),
            command: command.text(),
            status,
        }
        .into()
    }

    /// Sends a command and parses its reply.
    ///
    /// Retry policy: a reply that arrives complete but garbled (parity substitutes, bytes
    /// that are not the protocol, an unknown status code) or that carries a reading no meter
    /// can have measured (negative luminance, x + y > 1) is measured again once, because
    /// every command this driver sends is idempotent: `MES` measures the same target again,
    /// `MDS` sets the same mode again and `CLE` clears an already clear memory. The rejected
    /// reply is never silent: its bytes and the reason go to standard error as a warning and
    /// are kept in [`Cs100a::rejected_replies`]; a second bad reply is an error. Silence, a
    /// half reply, a disconnect and ER codes are not retried: silence means the meter is not
    /// in remote mode (waiting again only doubles the wait), a half reply or a disconnect
    /// means the cable or the meter needs attention, and an ER code is the meter's
    /// considered answer.
    fn exchange(&mut self, command: Command) -> Result<Reply, DriverError> {
        const ATTEMPTS: usize = 2;
        let mut attempt = 0;
        loop {
            attempt += 1;
            let line = self.transact(command)?;
            let error = match cs100a::parse_reply(&line) {
                Ok(reply) => match implausible(&reply) {
                    None => return Ok(reply),
                    Some(reason) => Cs100aError::ImpossibleReading {
                        port: self.link.describe(),
                        command: command.text(),
                        received: show_bytes(&line),
                        reason,
                    },
                },
                Err(reason) => Cs100aError::BadReply {
                    port: self.link.describe(),
                    command: command.text(),
                    received: show_bytes(&line),
                    reason,
                },
            };
            if attempt >= ATTEMPTS {
                return Err(error.into());
            }
            let warning = format!(
                "{error}; asking again (attempt {} of {ATTEMPTS})",
                attempt + 1
            );
            // eprintln! would panic on a full stderr; the warning is kept in `rejected` for
            // the session's record either way.
            let _ = std::io::Write::write_fmt(
                &mut std::io::stderr(),
                format_args!("warning: {warning}\n"),
            );
            self.rejected.push(warning);
        }
    }

    /// Replies rejected and asked again during this session, each with its bytes and why.
    pub fn rejected_replies(&self) -> &[String] {
        &self.rejected
    }

    /// Writes a command and reads one line, turning link failures into driver errors.
    fn transact(&mut self, command: Command) -> Result<Vec<u8>, DriverError> {
        let port = self.link.describe();
        let text = command.text();
        let answered = self.answered;
        let r = self
            .link
            .discard_input()
            .and_then(|()| self.link.write_all(&command.encode()))
            .and_then(|()| self.link.read_until(cs100a::TERMINATOR, self.timeout));
        r.map_err(|e| match e {
            LinkError::Timeout {
                timeout_ms,
                received,
            } if received.is_empty() && answered => Cs100aError::StoppedAnswering {
                port,
                command: text,
                timeout_ms,
            }
            .into(),
            LinkError::Timeout {
                timeout_ms,
                received,
            } if received.is_empty() => Cs100aError::NotInRemoteMode {
                port,
                command: text,
                timeout_ms,
            }
            .into(),
            LinkError::Timeout {
                timeout_ms,
                received,
            } => Cs100aError::PartialReply {
                port,
                command: text,
                received: show_bytes(&received),
                timeout_ms,
            }
            .into(),
            LinkError::Disconnected { received } => DriverError::Disconnected {
                port,
                command: text,
                received: if received.is_empty() {
                    "nothing".into()
                } else {
                    show_bytes(&received)
                },
            },
            other => DriverError::Link(other),
        })
        .inspect(|_| self.answered = true)
    }
}

/// Why a well-formed measurement reply cannot be a reading, if it cannot: values the
/// meter flagged as not measured (OK11, OK12) are not checked.
fn implausible(reply: &Reply) -> Option<metamer_color::Implausible> {
    let Reply::Measurement { value, .. } = reply else {
        return None;
    };
    let luminance = value.luminance.unwrap_or(0.0);
    let (x, y) = match (value.x, value.y) {
        (Some(x), Some(y)) => (x, y),
        _ => (0.3, 0.3),
    };
    metamer_color::check_yxy(luminance, x, y).err()
}

/// A reading from what the meter sent: Yxy → XYZ by the colour core. Values the
/// meter did not measure (OK11 chromaticity, OK12 placeholder luminance) are NaN, and the
/// flags say why; JSON writes them as null.
pub fn reading_from(status: Status, value: &Yxy, speed: Option<Speed>) -> Reading {
    let lum = value.luminance.unwrap_or(f64::NAN);
    let (x, y) = match (value.x, value.y) {
        (Some(x), Some(y)) => (x, y),
        _ => (f64::NAN, f64::NAN),
    };
    let mut reading = Reading::from_yxy(lum, x, y, MODEL);
    reading.flags = match status {
        Status::Ok11 => vec![Flag::ChromaticityOverRange],
        Status::Ok12 => vec![Flag::OverRange],
        Status::Ok13 => vec![Flag::LowLight],
        _ => Vec::new(),
    };
    reading.integration_s = speed.map(response_time_s);
    reading
}

impl<L: SerialLink + 'static> Instrument for Cs100a<L> {
    fn info(&self) -> InstrumentInfo {
        InstrumentInfo {
            model: MODEL.into(),
            // The CS-100A has no identify command (protocols/cs100a/README.md, "Line and framing").
            serial: None,
            firmware: None,
            connection: self.link.describe(),
        }
    }

    fn capabilities(&self) -> Capabilities {
        Capabilities {
            // A spot meter for light sources only: no lamp, no diffuser.
            modes: vec![ModeInfo {
                mode: MeasureMode::Emissive,
                spot: true,
                // The meter measures with Minolta's factory calibration (MDS,00 PRESET, the
                // power-on default [I]); it has no dark or white step the host must drive.
                calibrations: Vec::new(),
            }],
            spectral: false,
            // 1° and 0.01–299,000 cd/m² are general knowledge, unconfirmed by a KM source
            // (protocols/cs100a/README.md, "Measurement facts").
            acceptance_angle_deg: Some(1.0),
            luminance_range_cd_m2: Some((0.01, 299_000.0)),
            options: vec![OptionInfo {
                name: SPEED_OPTION.into(),
                description: "response speed: fast ≈100 ms, slow ≈400 ms for dark or \
                              flickering targets"
                    .into(),
                values: OptionValues::Choice(vec!["fast".into(), "slow".into()]),
                default: Speed::Fast.name().into(),
            }],
        }
    }

    fn calibration_needed(
        &mut self,
        _mode: MeasureMode,
    ) -> Result<Option<CalibrationCondition>, DriverError> {
        Ok(None)
    }

    fn calibrate(
        &mut self,
        _mode: MeasureMode,
        _condition: &CalibrationCondition,
    ) -> Result<CalibrationOutcome, DriverError> {
        Ok(CalibrationOutcome::Done)
    }

    fn set_option(&mut self, name: &str, value: &str) -> Result<(), DriverError> {
        if name != SPEED_OPTION {
            return Err(DriverError::UnknownOption {
                instrument: MODEL.into(),
                option: name.into(),
                known: SPEED_OPTION.into(),
            });
        }
        self.wanted_speed = match value {
            "fast" => Speed::Fast,
            "slow" => Speed::Slow,
            _ => {
                return Err(DriverError::BadOption {
                    instrument: MODEL.into(),
                    option: name.into(),
                    value: value.into(),
                    message: "expected fast or slow".into(),
                })
            }
        };
        Ok(())
    }

    fn option_values(&self) -> Vec<(String, String)> {
        vec![(SPEED_OPTION.into(), self.wanted_speed.name().into())]
    }

    fn measure(&mut self, request: &Request) -> Result<Reading, DriverError> {
        if request.mode != MeasureMode::Emissive {
            return Err(DriverError::Unsupported {
                instrument: MODEL.into(),
                what: format!(
                    "{} measurements (it has no lamp and no diffuser; measure a lit surface \
                     emissively)",
                    request.mode
                ),
            });
        }
        if !self.absolute {
            self.connect()?;
        }
        if self.speed != Some(self.wanted_speed) {
            self.set_speed(self.wanted_speed)?;
        }
        let (status, value) = self.measure_yxy()?;
        Ok(reading_from(status, &value, self.speed))
    }
}
