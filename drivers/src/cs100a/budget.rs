//! The CS-100A's time budget from its protocol facts (`protocols/cs100a/README.md`): the
//! measuring time of its response speed (FAST ≈ 100 ms, SLOW ≈ 400 ms) plus the command and
//! the 28-byte reply on the wire at 4800 baud, 7E2 (11 bit times a character). It needs no
//! calibration.

use metamer_protocols::cs100a::{self, Command, Status, Yxy};

use super::{response_time_s, Speed, MODEL, SPEED_OPTION};
use crate::budget::{TimeBudget, TimeQuery};
use crate::instrument::MeasureMode;
use crate::link::LineSettings;
use crate::DriverError;

/// Seconds one `MES` exchange spends on the wire: the command and the reply.
pub fn wire_s() -> f64 {
    let reply = cs100a::encode_measurement(
        Status::Ok00,
        &Yxy {
            luminance: Some(0.0),
            x: Some(0.0),
            y: Some(0.0),
        },
    );
    let chars = Command::Measure.encode().len() + reply.len();
    LineSettings::CS100A.char_time().as_secs_f64() * chars as f64
}

/// The CS-100A's budget for `query` (option `speed=fast|slow`; emissive only).
pub fn time_budget(query: &TimeQuery) -> Result<TimeBudget, DriverError> {
    if query.mode != MeasureMode::Emissive {
        return Err(DriverError::Unsupported {
            instrument: MODEL.into(),
            what: format!("{} measurements", query.mode),
        });
    }
    let speed = match query.option(SPEED_OPTION) {
        None | Some("fast") => Speed::Fast,
        Some("slow") => Speed::Slow,
        Some(v) => {
            return Err(DriverError::BadOption {
                instrument: MODEL.into(),
                option: SPEED_OPTION.into(),
                value: v.into(),
                message: "expected fast or slow".into(),
            })
        }
    };
    Ok(TimeBudget {
        reading_s: response_time_s(speed) + wire_s(),
        calibration_s: 0.0,
        calibration_valid_s: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cs100a::emulator::{Cs100aEmulator, EmulatorConfig};
    use crate::world::SharedWorld;
    use std::sync::Arc;

    /// The budget against the emulator at real pace: the delay it answers `MES` after (its
    /// measuring time and the reply's wire time), plus the command's own 5 characters on the
    /// wire, which the emulator does not wait out (the host sends them). By hand: 28 + 5
    /// characters × 11 bits / 4800 baud = 75.6 ms; FAST 0.1756 s, SLOW 0.4756 s.
    #[test]
    fn a_reading_takes_the_measuring_time_and_the_wire_time() {
        for (speed, by_hand) in [("fast", 0.175_625), ("slow", 0.475_625)] {
            let mut q = TimeQuery::new(MeasureMode::Emissive, 100.0);
            q.options.push((SPEED_OPTION.into(), speed.into()));
            let b = time_budget(&q).unwrap();
            assert!(
                (b.reading_s - by_hand).abs() < 1e-6,
                "{speed}: {}",
                b.reading_s
            );
            assert_eq!((b.calibration_s, b.calibration_valid_s), (0.0, None));
            let world = Arc::new(SharedWorld::new([100.0, 100.0, 100.0]));
            let mut e = Cs100aEmulator::new(
                world,
                EmulatorConfig {
                    time_scale: 1.0,
                    ..EmulatorConfig::default()
                },
            );
            let mode = if speed == "fast" {
                "MDS,06\r\n"
            } else {
                "MDS,07\r\n"
            };
            e.respond(mode.as_bytes());
            let (_, delay) = e.respond(b"MES\r\n");
            let command = 5.0 * 11.0 / 4800.0;
            let emulated = delay.as_secs_f64() + command;
            assert!(
                (b.reading_s / emulated - 1.0).abs() < 1e-6,
                "{speed}: budget {} s, emulator {emulated} s",
                b.reading_s
            );
        }
        let mut q = TimeQuery::new(MeasureMode::Reflective, 1.0);
        assert!(time_budget(&q).is_err());
        q.mode = MeasureMode::Emissive;
        q.options.push((SPEED_OPTION.into(), "medium".into()));
        assert!(time_budget(&q).is_err());
    }
}
