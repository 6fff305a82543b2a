//! What the operator is asked during a session, on a made-up meter whose readings are
//! given: each placement asked for once with its number of readings (again after a
//! calibration moved the instrument, and on resuming mid-placement), and a reading that
//! differs from the placement's earlier ones by more than the meter repeats shown and put
//! to the operator: read again (the doubtful reading is not journalled), kept, or stop.

use std::collections::{BTreeMap, VecDeque};
use std::path::{Path, PathBuf};

use metamer::session::operator::placement_prompt;
use metamer::session::{
    Answer, InstrumentRecord, Operator, OperatorError, PlacementReadings, Prepare, Recheck, Rig,
    RunEnd, RunOptions, Session, SessionPlan, Step, StepProgress,
};
use metamer_drivers::{
    CalibrationCondition, CalibrationOutcome, Capabilities, DriverError, Instrument,
    InstrumentInfo, MeasureMode, ModeInfo, Reading, Request,
};

use crate::support::unused_dir;

/// Gives the luminances queued, at the chromaticity of D65; with `valid_for`, needs a
/// white-tile calibration first and after every `valid_for` readings.
struct Meter {
    ys: VecDeque<f64>,
    valid_for: Option<usize>,
    used: Option<usize>,
}

impl Meter {
    fn new(ys: &[f64], valid_for: Option<usize>) -> Meter {
        Meter {
            ys: ys.iter().copied().collect(),
            valid_for,
            used: None,
        }
    }
}

impl Instrument for Meter {
    fn info(&self) -> InstrumentInfo {
        InstrumentInfo {
            model: "fake-meter".into(),
            serial: None,
            firmware: None,
            connection: "test".into(),
        }
    }
    fn capabilities(&self) -> Capabilities {
        Capabilities {
            modes: vec![ModeInfo {
                mode: MeasureMode::Emissive,
                spot: true,
                calibrations: vec![],
            }],
            spectral: false,
            acceptance_angle_deg: Some(1.0),
            luminance_range_cd_m2: None,
            options: vec![],
        }
    }
    fn calibration_needed(
        &mut self,
        _: MeasureMode,
    ) -> Result<Option<CalibrationCondition>, DriverError> {
        let due = match (self.valid_for, self.used) {
            (None, _) => false,
            (Some(_), None) => true,
            (Some(n), Some(used)) => used >= n,
        };
        Ok(due.then_some(CalibrationCondition::OnWhiteTile))
    }
    fn calibrate(
        &mut self,
        _: MeasureMode,
        _: &CalibrationCondition,
    ) -> Result<CalibrationOutcome, DriverError> {
        self.used = Some(0);
        Ok(CalibrationOutcome::Done)
    }
    fn measure(&mut self, _: &Request) -> Result<Reading, DriverError> {
        self.used = self.used.map(|u| u + 1);
        let y = self
            .ys
            .pop_front()
            .expect("the test queued enough readings");
        Ok(Reading {
            timestamp_s: 0.0,
            ..Reading::from_yxy(y, 0.3127, 0.3290, "fake-meter")
        })
    }
}

/// Does what it is asked; answers doubtful readings from a script (then keeps them).
#[derive(Default)]
struct Hands {
    prompts: Vec<String>,
    rechecks: VecDeque<Recheck>,
    doubted: Vec<String>,
}

impl Operator for Hands {
    fn ask(&mut self, prompt: &str) -> Result<Answer, OperatorError> {
        self.prompts.push(prompt.into());
        Ok(Answer::Confirmed)
    }
    fn ask_placement(
        &mut self,
        what: &str,
        readings: PlacementReadings,
    ) -> Result<Answer, OperatorError> {
        self.ask(&placement_prompt(what, readings))
    }
    fn recheck(&mut self, why: &str) -> Result<Recheck, OperatorError> {
        self.doubted.push(why.into());
        Ok(self.rechecks.pop_front().unwrap_or(Recheck::Keep))
    }
}

/// Targets A and B, three readings each.
fn plan() -> SessionPlan<String> {
    let mut steps = Vec::new();
    for target in ["A", "B"] {
        for k in 1..=3 {
            steps.push(Step {
                label: format!("{target} #{k}"),
                role: "spot".into(),
                mode: MeasureMode::Emissive,
                prepare: Prepare::Operator {
                    prompt: format!("aim at {target}"),
                },
                settle: std::time::Duration::ZERO,
                data: format!("{target}{k}"),
            });
        }
    }
    SessionPlan {
        kind: "operator-test".into(),
        options: BTreeMap::new(),
        steps,
    }
}

fn journal(tag: &str) -> PathBuf {
    unused_dir(tag).join("journal.jsonl")
}

/// What one run showed.
struct Ran {
    end: RunEnd,
    /// (reading k of n, flagged) per reading reported.
    shown: Vec<((usize, usize), bool)>,
    /// Luminances journalled, in plan order (None: not measured).
    journalled: Vec<Option<f64>>,
}

fn run(path: &Path, resume: bool, meter: &mut Meter, hands: &mut Hands) -> Ran {
    let records = [("spot".to_string(), InstrumentRecord::of(&*meter))].into();
    let mut session: Session<String, String> =
        Session::open(path, plan(), String::new(), records, resume).unwrap();
    let mut shown = Vec::new();
    let end = {
        let mut rig = Rig {
            screen: None,
            instruments: vec![("spot".to_string(), meter as &mut dyn Instrument)],
            operator: hands,
        };
        let mut sink = |p: &StepProgress<'_>| {
            shown.push((p.placement.unwrap(), p.deviation.is_some()));
        };
        session
            .run(&mut rig, &RunOptions::default(), &mut sink)
            .unwrap()
    };
    // Closed before it is read back (a journal may be held by one session at a time).
    drop(session);
    let reopened: Session<String, String> = Session::open(
        path,
        plan(),
        String::new(),
        [("spot".to_string(), InstrumentRecord::of(&*meter))].into(),
        true,
    )
    .unwrap();
    let journalled = match reopened.complete_entries() {
        Some(all) => all.iter().map(|e| Some(e.reading.xyz[1])).collect(),
        None => (0..6)
            .map(|i| (i < reopened.done()).then_some(f64::NAN))
            .collect(),
    };
    Ran {
        end,
        shown,
        journalled,
    }
}

#[test]
fn each_placement_is_asked_for_once_with_its_readings() {
    let path = journal("once");
    let mut meter = Meter::new(&[100.0, 100.1, 100.05, 50.0, 50.02, 50.01], None);
    let mut hands = Hands::default();
    let ran = run(&path, false, &mut meter, &mut hands);
    assert_eq!(ran.end, RunEnd::Complete);
    assert_eq!(
        hands.prompts,
        ["aim at A — 3 readings", "aim at B — 3 readings"]
    );
    let shown: Vec<_> = ran.shown.iter().map(|s| s.0).collect();
    assert_eq!(shown, [(1, 3), (2, 3), (3, 3), (1, 3), (2, 3), (3, 3)]);
    assert!(ran.shown.iter().all(|s| !s.1) && hands.doubted.is_empty());
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
}

#[test]
fn a_calibration_moves_the_instrument_so_the_placement_is_asked_again() {
    let path = journal("calibrated");
    // The calibration lasts two readings: before A's first and third, and B's second.
    let mut meter = Meter::new(&[100.0, 100.1, 100.05, 50.0, 50.02, 50.01], Some(2));
    let mut hands = Hands::default();
    let ran = run(&path, false, &mut meter, &mut hands);
    assert_eq!(ran.end, RunEnd::Complete);
    let white = "spot instrument (fake-meter), emissive calibration: place the instrument on its white calibration tile";
    assert_eq!(
        hands.prompts,
        [
            white,
            "aim at A — 3 readings",
            white,
            "aim at A — reading 3 of 3",
            "aim at B — 3 readings",
            white,
            "aim at B — readings 2–3 of 3",
        ]
    );
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
}

#[test]
fn a_reading_the_meter_does_not_repeat_is_read_again_when_the_operator_re_aims() {
    let path = journal("again");
    // A's third reading is 3 % off the first two (the meter repeats within ±0.2 %).
    let mut meter = Meter::new(&[100.0, 100.1, 103.0, 100.05, 50.0, 50.02, 50.01], None);
    let mut hands = Hands {
        rechecks: [Recheck::Again].into(),
        ..Hands::default()
    };
    let ran = run(&path, false, &mut meter, &mut hands);
    assert_eq!(ran.end, RunEnd::Complete);
    assert_eq!(hands.doubted, ["reading 3/3 (A #3) differs"]);
    // Shown flagged, then read again within the noise; asked for each target once.
    assert_eq!(
        ran.shown[..4],
        [
            ((1, 3), false),
            ((2, 3), false),
            ((3, 3), true),
            ((3, 3), false)
        ]
    );
    assert_eq!(hands.prompts.len(), 2);
    // The set-aside reading is not in the journal.
    assert_eq!(
        ran.journalled,
        [100.0, 100.1, 100.05, 50.0, 50.02, 50.01].map(Some)
    );
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
}

#[test]
fn a_doubtful_reading_is_kept_or_the_session_stops_as_the_operator_says() {
    let path = journal("keep");
    let mut meter = Meter::new(&[100.0, 100.1, 103.0, 50.0, 50.02, 50.01], None);
    let mut hands = Hands {
        rechecks: [Recheck::Keep].into(),
        ..Hands::default()
    };
    let ran = run(&path, false, &mut meter, &mut hands);
    assert_eq!(ran.end, RunEnd::Complete);
    assert_eq!(ran.journalled[2], Some(103.0));
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();

    let path = journal("stop");
    let mut meter = Meter::new(&[100.0, 100.1, 103.0], None);
    let mut hands = Hands {
        rechecks: [Recheck::Stop].into(),
        ..Hands::default()
    };
    let ran = run(&path, false, &mut meter, &mut hands);
    assert_eq!(ran.end, RunEnd::Aborted { missing: 4 });
    assert_eq!(ran.journalled.iter().flatten().count(), 2);
    // Resumed mid-placement: asked for the readings left, compared with the journalled ones.
    let mut meter = Meter::new(&[100.02, 50.0, 50.02, 50.01], None);
    let mut hands = Hands::default();
    let ran = run(&path, true, &mut meter, &mut hands);
    assert_eq!(ran.end, RunEnd::Complete);
    assert_eq!(
        hands.prompts,
        ["aim at A — reading 3 of 3", "aim at B — 3 readings"]
    );
    assert_eq!(ran.journalled[2], Some(100.02));
    assert!(hands.doubted.is_empty());
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
}
