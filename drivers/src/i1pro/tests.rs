//! The driver against its emulator over the in-process USB pair: every mode, the
//! calibration windows with a hand-moved clock, and the faults.

use std::sync::Arc;

use metamer_color::{colorchecker, radiance_to_xyz, ColorCheckerSet, ObserverKind, Spectrum};
use metamer_protocols::i1pro::calibration::key;
use metamer_protocols::i1pro::Revision;

use super::emulator::{
    default_light, EmulatorConfig, Fault, REPEATABILITY_REFLECTANCE, REPEATABILITY_Y,
};
use super::open::sim_with;
use super::ManualClock;
use crate::instrument::{CalibrationCondition, CalibrationOutcome, Instrument, MeasureMode};
use crate::world::{SharedWorld, View, World};
use crate::{DriverError, OpenOptions, Request};

fn open(
    world: &Arc<SharedWorld>,
    config: EmulatorConfig,
) -> Result<(Box<dyn Instrument>, ManualClock), DriverError> {
    let clock = ManualClock::new();
    let m = sim_with(
        world.clone() as Arc<dyn World>,
        EmulatorConfig {
            time_scale: 0.0,
            ..config
        },
        &OpenOptions::default(),
        Arc::new(clock.clone()),
    )?;
    Ok((m, clock))
}

fn quiet(revision: Revision) -> EmulatorConfig {
    EmulatorConfig {
        revision,
        noise: false,
        ..EmulatorConfig::default()
    }
}

fn calibrate(m: &mut dyn Instrument, mode: MeasureMode) {
    let c = m
        .calibration_needed(mode)
        .unwrap()
        .expect("a calibration is due");
    assert_eq!(c, CalibrationCondition::OnWhiteTile);
    assert_eq!(m.calibrate(mode, &c).unwrap(), CalibrationOutcome::Done);
    assert_eq!(m.calibration_needed(mode).unwrap(), None);
}

/// The light sampled on the instrument's 36 bands, as the CSV the CLI writes holds it.
fn on_grid(s: &Spectrum) -> Spectrum {
    Spectrum::measured(380.0, 10.0, s.on_grid(380.0, 10.0, 36)).unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

fn emissive_matches_the_light(revision: Revision, noise: bool, tol: f64) {
    let light = default_light();
    let world = Arc::new(SharedWorld::new(View::radiance(light.clone()).unwrap()));
    let (mut m, _) = open(
        &world,
        EmulatorConfig {
            noise,
            ..quiet(revision)
        },
    )
    .unwrap();
    world.set(View::WhiteTile);
    calibrate(m.as_mut(), MeasureMode::Emissive);
    world.set(View::radiance(light.clone()).unwrap());
    let r = m.measure(&Request::default()).unwrap();
    let want = radiance_to_xyz(&on_grid(&light), ObserverKind::Cie1931).to_array();
    for k in 0..3 {
        assert!(
            rel(r.xyz[k], want[k]) < tol,
            "{revision:?} {:?} vs {want:?}",
            r.xyz
        );
    }
    // The band-limited grid loses little of the full 1 nm light.
    let full = radiance_to_xyz(&light, ObserverKind::Cie1931).to_array();
    assert!(rel(r.xyz[1], full[1]) < 0.02, "{:?} vs {full:?}", r.xyz);
    let t = r.integration_s.unwrap();
    assert!(t > 0.0047 && t <= 2.0001, "{t}");
}

/// Without noise a reading differs from the light only by whole-count rounding: of the
/// reading and of the two darks, about one count in a blue band of some 4000 counts
/// (100 cd/m² of LED-RGB1 at 1.8 s), 2.5·10⁻⁴ of it, less once weighted into X, Y, Z.
const EXACT: f64 = 3e-4;

#[test]
fn emissive_without_noise_gives_the_lights_xyz_to_3e_4() {
    emissive_matches_the_light(Revision::AToD, false, EXACT);
    emissive_matches_the_light(Revision::E, false, EXACT);
}

#[test]
fn emissive_with_noise_stays_within_the_declared_repeatability() {
    emissive_matches_the_light(Revision::AToD, true, 4.0 * REPEATABILITY_Y);
    emissive_matches_the_light(Revision::E, true, 4.0 * REPEATABILITY_Y);
}

#[test]
fn open_reports_serial_firmware_and_revision() {
    let world = Arc::new(SharedWorld::new(View::Capped));
    let (m, _) = open(&world, quiet(Revision::AToD)).unwrap();
    let info = m.info();
    assert_eq!(info.model, "i1pro");
    assert_eq!(info.serial.as_deref(), Some("9000001"));
    assert_eq!(info.firmware.as_deref(), Some("505 (Rev A–D)"));
    let (m, _) = open(&world, quiet(Revision::E)).unwrap();
    assert_eq!(m.info().firmware.as_deref(), Some("629 (Rev E (i1Pro 2))"));
    let caps = m.capabilities();
    let dark = &caps.mode(MeasureMode::Emissive).unwrap().calibrations[0];
    assert_eq!(dark.valid_for_s, Some(3600.0));
    assert!(caps.supports(MeasureMode::Ambient));
}

#[test]
fn a_fixed_integration_time_is_used_and_checked() {
    let world = Arc::new(SharedWorld::new(View::WhiteTile));
    let (mut m, _) = open(&world, quiet(Revision::AToD)).unwrap();
    calibrate(m.as_mut(), MeasureMode::Emissive);
    world.set(View::radiance(default_light()).unwrap());
    m.set_option("integration_s", "0.1").unwrap();
    assert_eq!(m.option_values()[0].1, "0.1");
    let r = m.measure(&Request::default()).unwrap();
    // 0.1 s is 1471 clocks of 68 µs: 0.100028 s.
    assert!((r.integration_s.unwrap() - 1471.0 * 68e-6).abs() < 1e-12);
    assert!((r.xyz[1] - 100.0).abs() < 2.0, "{:?}", r.xyz);
    // From one sub-clock of the finer clock mode (131 × 36 µs) to the long dark's 2 s
    // (29412 clocks of 68 µs), shown rounded.
    for bad in ["9", "2.1", "0.0046"] {
        let e = m.set_option("integration_s", bad).unwrap_err();
        assert!(e.to_string().contains("from 0.004716 to 2"), "{e}");
    }
    m.set_option("integration_s", "0.004716").unwrap();
    m.set_option("integration_s", "2").unwrap();
    m.set_option("integration_s", "0.1").unwrap();
    // Too much light for the fixed time: an error, never a clipped spectrum.
    world.set(View::radiance(default_light().scaled(20.0)).unwrap());
    m.set_option("integration_s", "1").unwrap();
    let e = m.measure(&Request::default()).unwrap_err();
    assert!(
        e.to_string()
            .contains("saturated at the fixed integration time"),
        "{e}"
    );
}

#[test]
fn too_bright_and_too_dark_say_what_to_do() {
    let world = Arc::new(SharedWorld::new(View::WhiteTile));
    let (mut m, _) = open(&world, quiet(Revision::AToD)).unwrap();
    calibrate(m.as_mut(), MeasureMode::Emissive);
    // 100 000 cd/m² saturates even at 4.716 ms (about 46 000 cd/m² does).
    world.set(View::radiance(default_light().scaled(1000.0)).unwrap());
    let e = m.measure(&Request::default()).unwrap_err();
    assert!(e.to_string().contains("too bright"), "{e}");
    assert!(e.to_string().contains("time of 4.716 ms;"), "{e}");
    world.set(View::radiance(default_light().scaled(1e-6)).unwrap());
    let e = m.measure(&Request::default()).unwrap_err();
    assert!(e.to_string().contains("too dark"), "{e}");
    assert!(e.to_string().contains("time of 2.000 s"), "{e}");
    world.set(View::Capped);
    let e = m.measure(&Request::default()).unwrap_err();
    assert!(e.to_string().contains("too dark"), "{e}");
}

#[test]
fn reflective_reads_every_colorchecker_patch_and_recalibrates_when_expired() {
    for revision in [Revision::AToD, Revision::E] {
        let world = Arc::new(SharedWorld::new(View::WhiteTile));
        let (mut m, clock) = open(
            &world,
            EmulatorConfig {
                revision,
                ..EmulatorConfig::default()
            },
        )
        .unwrap();
        let reflective = Request {
            mode: MeasureMode::Reflective,
        };
        let mut prompts = 0;
        for (i, patch) in colorchecker(ColorCheckerSet::BabelColorAverage)
            .into_iter()
            .enumerate()
        {
            if i == 12 {
                // Past the white calibration's hour.
                clock.advance(3601.0);
                let e = m.measure(&reflective).unwrap_err();
                assert!(matches!(e, DriverError::NeedsCalibration { .. }), "{e}");
                assert!(e.to_string().contains("expired after"), "{e}");
            }
            if let Some(c) = m.calibration_needed(MeasureMode::Reflective).unwrap() {
                prompts += 1;
                world.set(View::WhiteTile);
                assert_eq!(
                    m.calibrate(MeasureMode::Reflective, &c).unwrap(),
                    CalibrationOutcome::Done
                );
            }
            world.set(View::surface(patch.clone()).unwrap());
            let r = m.measure(&reflective).unwrap();
            let s = r.spectrum.unwrap();
            for w in 0..36 {
                let nm = 380.0 + 10.0 * w as f64;
                let d = (s.values()[w] - patch.value_at(nm)).abs();
                assert!(
                    d < 4.0 * REPEATABILITY_REFLECTANCE,
                    "{revision:?} patch {i} {nm} nm: {} vs {}",
                    s.values()[w],
                    patch.value_at(nm)
                );
            }
        }
        assert_eq!(prompts, 2, "{revision:?}");
    }
}

#[test]
fn a_dark_calibration_expires_after_30_minutes_on_rev_d() {
    let world = Arc::new(SharedWorld::new(View::WhiteTile));
    let (mut m, clock) = open(&world, quiet(Revision::AToD)).unwrap();
    let e = m.measure(&Request::default()).unwrap_err();
    assert!(e.to_string().contains("no dark calibration yet"), "{e}");
    calibrate(m.as_mut(), MeasureMode::Emissive);
    world.set(View::radiance(default_light()).unwrap());
    clock.advance(1799.0);
    m.measure(&Request::default()).unwrap();
    clock.advance(2.0);
    let e = m.measure(&Request::default()).unwrap_err();
    assert!(
        e.to_string()
            .contains("dark calibration expired after 30 min"),
        "{e}"
    );
    // The wrong condition is answered with the right one.
    assert_eq!(
        m.calibrate(MeasureMode::Emissive, &CalibrationCondition::SensorCapped)
            .unwrap(),
        CalibrationOutcome::Needs(CalibrationCondition::OnWhiteTile)
    );
}

#[test]
fn a_dark_calibration_in_the_light_is_refused() {
    let world = Arc::new(SharedWorld::new(View::radiance(default_light()).unwrap()));
    let (mut m, _) = open(&world, quiet(Revision::AToD)).unwrap();
    let e = m
        .calibrate(MeasureMode::Emissive, &CalibrationCondition::OnWhiteTile)
        .unwrap_err();
    assert!(e.to_string().contains("dark calibration saw light"), "{e}");
}

#[test]
fn ambient_through_the_diffuser_gives_pi_times_the_radiance_in_lux() {
    let world = Arc::new(SharedWorld::new(View::WhiteTile));
    let (mut m, _) = open(
        &world,
        EmulatorConfig {
            diffuser: true,
            ..quiet(Revision::AToD)
        },
    )
    .unwrap();
    calibrate(m.as_mut(), MeasureMode::Ambient);
    world.set(View::radiance(default_light()).unwrap());
    let r = m
        .measure(&Request {
            mode: MeasureMode::Ambient,
        })
        .unwrap();
    let want =
        std::f64::consts::PI * radiance_to_xyz(&on_grid(&default_light()), ObserverKind::Cie1931).y;
    assert!(rel(r.xyz[1], want) < EXACT, "{} vs {want}", r.xyz[1]);
}

#[test]
fn faults_are_clear_errors_never_wrong_spectra() {
    let world = Arc::new(SharedWorld::new(View::WhiteTile));
    let e = open(
        &world,
        EmulatorConfig {
            missing_keys: vec![key::EMISSIVE],
            ..quiet(Revision::AToD)
        },
    )
    .err()
    .unwrap();
    assert!(e.to_string().contains("factory calibration"), "{e}");
    assert!(
        e.to_string().contains("0x044d") || e.to_string().contains("0x044D"),
        "{e}"
    );
    let (mut m, _) = open(
        &world,
        EmulatorConfig {
            fault: Some(Fault::ShortRead(1)),
            ..quiet(Revision::AToD)
        },
    )
    .unwrap();
    let e = m
        .calibrate(MeasureMode::Emissive, &CalibrationCondition::OnWhiteTile)
        .unwrap_err();
    // The first shot is the short dark: 212 readings of 4.716 ms, 256 bytes each.
    assert!(
        e.to_string().contains("sent 27136 of the 54272 bytes"),
        "{e}"
    );
    let (mut m, _) = open(
        &world,
        EmulatorConfig {
            fault: Some(Fault::DisconnectMidRead(2)),
            ..quiet(Revision::AToD)
        },
    )
    .unwrap();
    let e = m
        .calibrate(MeasureMode::Emissive, &CalibrationCondition::OnWhiteTile)
        .unwrap_err();
    assert!(matches!(e, DriverError::Disconnected { .. }), "{e}");
    assert!(e.to_string().contains("read measurement"), "{e}");
}

#[test]
fn a_unit_in_low_power_is_brought_up_or_reported() {
    let world = Arc::new(SharedWorld::new(View::WhiteTile));
    let (m, _) = open(
        &world,
        EmulatorConfig {
            low_power_polls: 3,
            ..quiet(Revision::AToD)
        },
    )
    .unwrap();
    assert_eq!(m.info().serial.as_deref(), Some("9000001"));
    let e = open(
        &world,
        EmulatorConfig {
            low_power_polls: 20,
            ..quiet(Revision::AToD)
        },
    )
    .err()
    .unwrap();
    assert!(e.to_string().contains("stays in low power"), "{e}");
}

#[test]
fn a_stall_and_a_timeout_are_errors_that_name_the_request() {
    let world = Arc::new(SharedWorld::new(View::WhiteTile));
    let (mut m, _) = open(
        &world,
        EmulatorConfig {
            fault: Some(Fault::StallTrigger(1)),
            ..quiet(Revision::AToD)
        },
    )
    .unwrap();
    let e = m
        .calibrate(MeasureMode::Emissive, &CalibrationCondition::OnWhiteTile)
        .unwrap_err();
    let text = e.to_string();
    assert!(text.contains("during 'trigger measurement'"), "{text}");
    assert!(text.contains("stalled endpoint 0x00"), "{text}");
    // The read of 212 readings of 4.716 ms waits 2 s + 999.8 ms, as the codec's timeout
    // rule says.
    let (mut m, _) = open(
        &world,
        EmulatorConfig {
            fault: Some(Fault::SilentRead(1)),
            ..quiet(Revision::AToD)
        },
    )
    .unwrap();
    let e = m
        .calibrate(MeasureMode::Emissive, &CalibrationCondition::OnWhiteTile)
        .unwrap_err();
    let text = e.to_string();
    assert!(
        text.contains("during 'read measurement': no reply within 2999 ms"),
        "{text}"
    );
    assert!(text.contains("unplug and replug"), "{text}");
}

#[test]
fn a_sample_that_saturates_under_the_lamp_is_an_error() {
    let world = Arc::new(SharedWorld::new(View::WhiteTile));
    let (mut m, _) = open(&world, quiet(Revision::AToD)).unwrap();
    calibrate(m.as_mut(), MeasureMode::Reflective);
    // A fluorescent sample giving back 2.5 times the lamp's light.
    world.set(View::surface(Spectrum::constant(380.0, 730.0, 2.5)).unwrap());
    let e = m
        .measure(&Request {
            mode: MeasureMode::Reflective,
        })
        .unwrap_err();
    assert!(e.to_string().contains("sample saturated"), "{e}");
}
