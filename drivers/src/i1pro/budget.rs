//! The i1Pro's time budget from its protocol facts (`protocols/i1pro/README.md`): the
//! integration time a light of a given luminance forces, the readings the driver averages
//! at it, the trial reading before it, the dark patches' longer reading, the lamp, and the
//! calibrations with their validity. It follows the driver's own rules (`engine.rs`) on the
//! unit's sensitivity as ArgyllCMS describes a real one.

use metamer_protocols::i1pro::Revision;

use super::emulator::DARK_NOISE_CD_M2;
use super::engine::{
    readings_for, DARK_LONG_READINGS, DARK_LONG_S, DARK_PATCH_READINGS, DARK_SHORT_TOTAL_S,
    REFLECTIVE_READINGS, REFLECTIVE_S, TOO_DARK_SIGMAS, TRIAL_S,
};
use super::wire::LAMP_WARMUP_S;
use super::{I1ProError, DARK_VALID_A_TO_D_S, DARK_VALID_E_S, MODEL, WHITE_VALID_S};
use crate::budget::{TimeBudget, TimeQuery};
use crate::instrument::MeasureMode;
use crate::DriverError;

/// A 2 s reading saturates on about 110 cd/m² of a display's white [C2: ArgyllCMS
/// `i1pro_imp.c`, `DISP_INTT`]: the largest cell collects the saturation count
/// ([`SATURATION`]) in 2 s at 110 cd/m².
pub const SATURATES_IN_2_S_CD_M2: f64 = 110.0;
/// The EEPROM's saturation count in normal gain (key 0x04B7, ≈ 45 000) [C2].
pub const SATURATION: f64 = 45_000.0;
/// The EEPROM's sensor target (key 0x04B4, ≈ 37 000) [C2].
pub const SENSOR_TARGET: f64 = 37_000.0;
/// The diffuser passes 1/40 of the light in the simulated unit (its ambient factors); a
/// real unit's EEPROM states its own [I].
const AMBIENT_FACTOR: f64 = 40.0;

/// The largest cell's counts per second for `cd_m2`.
fn peak_rate(cd_m2: f64) -> f64 {
    SATURATION / (DARK_LONG_S * SATURATES_IN_2_S_CD_M2) * cd_m2
}

/// The shortest integration time: one sub-clock of the finest clock mode (4.716 ms on a
/// Rev A–D with firmware ≥ 301, 4.896 ms on Rev E) [C2].
fn shortest_s(revision: Revision) -> f64 {
    match revision {
        Revision::AToD => 36e-6 * 131.0,
        Revision::E => 36e-6 * 136.0,
    }
}

fn revision(query: &TimeQuery) -> Result<Revision, DriverError> {
    match query.option("rev") {
        None | Some("d") => Ok(Revision::AToD),
        Some("e") => Ok(Revision::E),
        Some(v) => Err(DriverError::BadOption {
            instrument: MODEL.into(),
            option: "rev".into(),
            value: v.into(),
            message: "expected d or e".into(),
        }),
    }
}

/// One emissive reading of `cd_m2` as the driver takes it: the trial at 0.1 s (and one at
/// the shortest time when that saturates), then the readings at the time that puts the
/// largest cell at the sensor target, or [`DARK_PATCH_READINGS`] at 2 s for a light whose
/// one reading would not stand [`TOO_DARK_SIGMAS`] standard deviations above the sensor's
/// own noise ([`DARK_NOISE_CD_M2`], 1σ of Y at 2 s). A fixed time needs no trial.
fn emissive_s(cd_m2: f64, fixed: Option<f64>, shortest: f64) -> Result<f64, DriverError> {
    let at = |t: f64| t * readings_for(t) as f64;
    if let Some(t) = fixed {
        return Ok(at(t.clamp(shortest, DARK_LONG_S)));
    }
    let rate = peak_rate(cd_m2);
    let mut trial = TRIAL_S;
    if rate * TRIAL_S > SATURATION {
        if rate * shortest > SATURATION {
            return Err(I1ProError::TooBright {
                min_s: shortest,
                one_mode: false,
            }
            .into());
        }
        trial += shortest;
    }
    let t = if rate > 0.0 {
        (SENSOR_TARGET / rate).clamp(shortest, DARK_LONG_S)
    } else {
        DARK_LONG_S
    };
    if t >= DARK_LONG_S && cd_m2 < TOO_DARK_SIGMAS * DARK_NOISE_CD_M2 {
        return Ok(trial + DARK_LONG_S * DARK_PATCH_READINGS as f64);
    }
    Ok(trial + at(t))
}

/// The i1Pro's budget for `query` (options: `rev=d|e`, `integration_s=auto|S`).
pub fn time_budget(query: &TimeQuery) -> Result<TimeBudget, DriverError> {
    let revision = revision(query)?;
    let shortest = shortest_s(revision);
    let dark_valid = match revision {
        Revision::AToD => DARK_VALID_A_TO_D_S,
        Revision::E => DARK_VALID_E_S,
    };
    let fixed = match query.option("integration_s") {
        None | Some("auto") => None,
        Some(v) => Some(
            v.trim()
                .parse::<f64>()
                .ok()
                .filter(|t| t.is_finite() && *t > 0.0)
                .ok_or_else(|| DriverError::BadOption {
                    instrument: MODEL.into(),
                    option: "integration_s".into(),
                    value: v.into(),
                    message: "expected auto or a time in seconds".into(),
                })?,
        ),
    };
    // The emissive dark: a second of readings at the shortest time, nine at the longest.
    let short_dark = (DARK_SHORT_TOTAL_S / shortest).round() * shortest;
    let emissive_dark = short_dark + DARK_LONG_READINGS as f64 * DARK_LONG_S;
    // A lamp-lit shot: the lamp warms up, then the readings integrate.
    let lit = LAMP_WARMUP_S + REFLECTIVE_READINGS as f64 * REFLECTIVE_S;
    Ok(match query.mode {
        MeasureMode::Emissive => TimeBudget {
            reading_s: emissive_s(query.luminance_cd_m2, fixed, shortest)?,
            calibration_s: emissive_dark,
            calibration_valid_s: Some(dark_valid),
        },
        MeasureMode::Ambient => TimeBudget {
            reading_s: emissive_s(query.luminance_cd_m2 / AMBIENT_FACTOR, fixed, shortest)?,
            calibration_s: emissive_dark,
            calibration_valid_s: Some(dark_valid),
        },
        MeasureMode::Reflective => TimeBudget {
            reading_s: lit,
            // A lamp-off dark, then the white tile under the lamp.
            calibration_s: REFLECTIVE_READINGS as f64 * REFLECTIVE_S + lit,
            calibration_valid_s: Some(dark_valid.min(WHITE_VALID_S)),
        },
    })
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::i1pro::emulator::{default_light, EmulatorConfig, I1ProEmulator};
    use crate::i1pro::{Clock, I1Pro, ManualClock};
    use crate::instrument::{CalibrationCondition, Instrument};
    use crate::link::usb_pair::usb_pair;
    use crate::registry::time_budget as budget_of;
    use crate::world::{SharedWorld, View, World};
    use crate::Request;

    fn query(mode: MeasureMode, cd_m2: f64, rev: &str) -> TimeQuery {
        let mut q = TimeQuery::new(mode, cd_m2);
        q.options.push(("rev".into(), rev.into()));
        q
    }

    /// The figures by hand from the facts: the emissive dark is 212 readings of 4.716 ms
    /// (0.99979 s) and nine of 2 s; 100 cd/m² integrates 37 000 / (45 000 / 220 · 100) =
    /// 1.8089 s after the 0.1 s trial; a display's black (0.05 cd/m²) six readings of 2 s.
    #[test]
    fn the_budget_by_hand() {
        let b = budget_of("i1pro", &query(MeasureMode::Emissive, 100.0, "d")).unwrap();
        assert!((b.calibration_s - (212.0 * 4.716e-3 + 18.0)).abs() < 1e-9);
        assert_eq!(b.calibration_valid_s, Some(1800.0));
        assert!((b.reading_s - (0.1 + 37_000.0 * 220.0 / 4_500_000.0)).abs() < 1e-9);
        let black = budget_of("i1pro", &query(MeasureMode::Emissive, 0.05, "e")).unwrap();
        assert!((black.reading_s - 12.1).abs() < 1e-9);
        assert_eq!(black.calibration_valid_s, Some(3600.0));
        let r = budget_of("i1pro", &query(MeasureMode::Reflective, 0.0, "d")).unwrap();
        assert!((r.reading_s - 0.36).abs() < 1e-12 && (r.calibration_s - 0.52).abs() < 1e-12);
        let mut fixed = query(MeasureMode::Emissive, 1.0, "d");
        fixed.options.push(("integration_s".into(), "0.25".into()));
        // Three readings of 0.25 s, no trial.
        assert!((budget_of("i1pro", &fixed).unwrap().reading_s - 0.75).abs() < 1e-12);
        assert!(budget_of("i1pro", &query(MeasureMode::Emissive, 1e6, "d")).is_err());
        assert!(budget_of("i1pro", &query(MeasureMode::Emissive, 1.0, "x")).is_err());
    }

    /// The budget against the simulated unit's own clock at the real pace (its integrations
    /// and lamp times, counted whatever the time scale), with its noise: a dark calibration,
    /// then a display's levels from a CRT's black to a bright white and a light tile. Each
    /// reading and the session within 20 %.
    #[test]
    fn the_budget_comes_within_a_fifth_of_the_simulated_units_time_at_real_pace() {
        for (revision, rev) in [(Revision::AToD, "d"), (Revision::E, "e")] {
            let world = Arc::new(SharedWorld::new(View::WhiteTile));
            let device = I1ProEmulator::new(
                world.clone() as Arc<dyn World>,
                EmulatorConfig {
                    revision,
                    time_scale: 0.0,
                    ..EmulatorConfig::default()
                },
            )
            .unwrap();
            let pace = device.real_pace_clock();
            let (host, _thread) = usb_pair(device, "sim:i1pro");
            let mut m = I1Pro::open(host, Arc::new(ManualClock::new())).unwrap();
            let mut budget = 0.0;
            let mut spent = 0.0;
            let mut step = |what: &str, predicted: f64, run: &mut dyn FnMut()| {
                let before = pace.now_s();
                run();
                let took = pace.now_s() - before;
                eprintln!("{rev} {what}: budget {predicted:.3} s, simulated unit {took:.3} s");
                assert!(
                    (predicted / took - 1.0).abs() < 0.2,
                    "{rev} {what}: budget {predicted} s, simulated unit {took} s"
                );
                budget += predicted;
                spent += took;
            };
            let cal = budget_of("i1pro", &query(MeasureMode::Emissive, 0.0, rev)).unwrap();
            step("dark calibration", cal.calibration_s, &mut || {
                m.calibrate(MeasureMode::Emissive, &CalibrationCondition::OnWhiteTile)
                    .unwrap();
            });
            for cd in [
                0.05, 0.22, 1.0, 5.0, 20.0, 50.0, 100.0, 200.0, 1000.0, 5000.0,
            ] {
                let b = budget_of("i1pro", &query(MeasureMode::Emissive, cd, rev)).unwrap();
                world.set(View::radiance(default_light().scaled(cd / 100.0)).unwrap());
                step(&format!("{cd} cd/m²"), b.reading_s, &mut || {
                    m.measure(&Request::default()).unwrap();
                });
            }
            eprintln!("{rev} session: budget {budget:.2} s, simulated unit {spent:.2} s");
            assert!((budget / spent - 1.0).abs() < 0.2, "{budget} {spent}");
        }
    }
}
