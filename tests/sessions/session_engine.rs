//! The session engine on a made-up rig: a spot meter that reads the screen (no calibration)
//! and a spectrometer whose reflective mode needs a dark then a white calibration that lasts
//! two measurements, read tile by tile as the operator places it. Checked: calibration
//! prompts exactly when due, every entry and calibration journalled, resume after a SIGKILL
//! to the same entries as an uninterrupted run, a changed option refused by name, a torn
//! last line set aside, and an operator's abort.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use metamer::session::{
    Answer, Entry, InstrumentRecord, Prepare, Rig, RunEnd, RunOptions, ScriptedOperator, Session,
    SessionError, SessionPlan, Step, StepProgress,
};
use metamer_drivers::{CalibrationCondition, Instrument, MeasureMode};
use serde::{Deserialize, Serialize};

mod resume_checks;
mod rig;

use rig::{FakeScreen, Shared, Spectrometer, SpotMeter, TileOperator, VALID_FOR};

use crate::support::fresh_dir;

/// Tiles the spectrometer reads.
const TILES: usize = 5;
/// Set in the child process that is killed mid-run: the journal's path.
const CHILD_ENV: &str = "METAMER_SESSION_ENGINE_CHILD";

/// The caller's data of a step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Target {
    what: String,
}

/// Spot on white; tiles 1 and 2; spot on grey; tiles 3 to 5; spot on red.
fn plan(tiles: usize, settle: Duration) -> SessionPlan<Target> {
    let spot = |label: &str, rgb: [u8; 3]| Step {
        label: label.into(),
        role: "spot".into(),
        mode: MeasureMode::Emissive,
        prepare: Prepare::Show { rgb },
        settle,
        data: Target {
            what: format!("screen {rgb:?}"),
        },
    };
    let tile = |n: usize| Step {
        label: format!("tile {n}"),
        role: "spectral".into(),
        mode: MeasureMode::Reflective,
        prepare: Prepare::Operator {
            prompt: format!("place the spectrometer on tile {n}"),
        },
        settle,
        data: Target {
            what: format!("tile {n}"),
        },
    };
    let mut steps = vec![spot("white", [255; 3]), tile(1), tile(2)];
    steps.push(spot("grey", [128; 3]));
    steps.extend((3..=tiles).map(tile));
    steps.push(spot("red", [255, 0, 0]));
    SessionPlan {
        kind: "test-box".into(),
        options: [
            ("tiles".to_string(), tiles.to_string()),
            ("valid_for".to_string(), VALID_FOR.to_string()),
        ]
        .into(),
        steps,
    }
}

fn instruments() -> BTreeMap<String, InstrumentRecord> {
    let world = Shared::default();
    [
        (
            "spot".to_string(),
            InstrumentRecord::of(&SpotMeter(world.clone())),
        ),
        (
            "spectral".to_string(),
            InstrumentRecord::of(&Spectrometer::new(world)),
        ),
    ]
    .into()
}

/// What one run did.
struct Ran {
    end: RunEnd,
    prompts: Vec<String>,
    /// (done, total, index) per step reported.
    progress: Vec<(usize, usize, usize)>,
    remaining_at_end: Option<Duration>,
    session: Session<String, Target>,
}

fn open(path: &Path, plan: SessionPlan<Target>, resume: bool) -> Session<String, Target> {
    Session::open(path, plan, "a test rig".to_string(), instruments(), resume).unwrap()
}

/// Runs the plan on a fresh rig (instruments not calibrated, as after a restart).
fn run(session: Session<String, Target>, answers: Vec<Answer>, options: &RunOptions) -> Ran {
    run_with(session, answers, options, true)
}

fn run_with(
    mut session: Session<String, Target>,
    answers: Vec<Answer>,
    options: &RunOptions,
    reports_expiry: bool,
) -> Ran {
    let world = Shared::default();
    let mut screen = FakeScreen(world.clone());
    let mut spot = SpotMeter(world.clone());
    let mut spectro = Spectrometer {
        reports_expiry,
        ..Spectrometer::new(world.clone())
    };
    let mut operator = TileOperator {
        script: ScriptedOperator::with_answers(answers),
        world,
    };
    let mut progress = Vec::new();
    let mut remaining_at_end = None;
    let end = {
        let mut rig = Rig {
            screen: Some(&mut screen),
            instruments: vec![
                ("spot".to_string(), &mut spot as &mut dyn Instrument),
                ("spectral".to_string(), &mut spectro),
            ],
            operator: &mut operator,
        };
        let mut sink = |p: &StepProgress<'_>| {
            progress.push((p.done, p.total, p.index));
            remaining_at_end = Some(p.remaining);
        };
        session.run(&mut rig, options, &mut sink).unwrap()
    };
    Ran {
        end,
        prompts: operator.script.prompts,
        progress,
        remaining_at_end,
        session,
    }
}

fn temp(tag: &str) -> PathBuf {
    fresh_dir(tag).join("journal.jsonl")
}

fn entries(session: &Session<String, Target>) -> Vec<Entry<Target>> {
    session
        .complete_entries()
        .unwrap()
        .into_iter()
        .cloned()
        .collect()
}

const CAP: &str = "spectral instrument (fake-spectro), reflective calibration: cap the sensor so no light reaches it";
const WHITE: &str = "spectral instrument (fake-spectro), reflective calibration: place the instrument on its white calibration tile";

fn tile(n: usize) -> String {
    format!("place the spectrometer on tile {n}")
}

#[test]
fn calibrations_are_asked_for_when_due_and_everything_is_journalled() {
    let path = temp("straight");
    let ran = run(
        open(&path, plan(TILES, Duration::ZERO), false),
        vec![],
        &RunOptions::default(),
    );
    assert_eq!(ran.end, RunEnd::Complete);
    // First use: dark, white, then the tile. The calibration lasts two measurements, so the
    // third and fifth tiles find it expired while measuring: calibrate, place it again.
    let expected: Vec<String> = vec![
        CAP.into(),
        WHITE.into(),
        tile(1),
        tile(2),
        tile(3),
        CAP.into(),
        WHITE.into(),
        tile(3),
        tile(4),
        tile(5),
        CAP.into(),
        WHITE.into(),
        tile(5),
    ];
    assert_eq!(ran.prompts, expected);

    // An instrument whose calibration check does not know of the expiry: the condition
    // its measurement error names is negotiated, with the same prompts.
    let quiet = temp("quiet");
    let ran_quiet = run_with(
        open(&quiet, plan(TILES, Duration::ZERO), false),
        vec![],
        &RunOptions::default(),
        false,
    );
    assert_eq!(ran_quiet.prompts, expected);
    assert_eq!(entries(&ran_quiet.session), entries(&ran.session));
    std::fs::remove_dir_all(quiet.parent().unwrap()).unwrap();

    let all = entries(&ran.session);
    assert_eq!(all.len(), 8);
    let by_label: BTreeMap<&str, metamer::color::Xyz> = all
        .iter()
        .map(|e| (e.label.as_str(), e.reading.xyz))
        .collect();
    // Each reading is of what its step prepared.
    assert_eq!(by_label["grey"][1], 64.0);
    assert_eq!(by_label["red"][1], 0.0);
    for n in 1..=TILES {
        assert!((by_label[format!("tile {n}").as_str()][1] - 11.0 * n as f64).abs() < 1e-9);
    }
    assert!(all
        .iter()
        .all(|e| (e.role == "spot") == (e.mode == MeasureMode::Emissive)));

    // The calibrations, each condition before the step that needed it.
    let cal: Vec<(usize, CalibrationCondition)> = ran
        .session
        .calibrations()
        .iter()
        .map(|c| (c.before_step, c.condition.clone()))
        .collect();
    let (capped, white) = (
        CalibrationCondition::SensorCapped,
        CalibrationCondition::OnWhiteTile,
    );
    let expected_cal = vec![
        (1, capped.clone()),
        (1, white.clone()),
        (4, capped.clone()),
        (4, white.clone()),
        (6, capped),
        (6, white),
    ];
    assert_eq!(cal, expected_cal);
    assert!(ran
        .session
        .calibrations()
        .iter()
        .all(|c| c.role == "spectral"
            && c.instrument == "fake-spectro"
            && c.mode == MeasureMode::Reflective));

    // Progress: one report per step, counting up; nothing left at the end.
    assert_eq!(
        ran.progress,
        (0..8).map(|i| (i + 1, 8, i)).collect::<Vec<_>>()
    );
    assert_eq!(ran.remaining_at_end, Some(Duration::ZERO));

    // The journal on disk holds the same: resuming it finds every entry and calibration
    // and measures nothing.
    // A session holds its journal's lock until it is dropped.
    drop(ran);
    let again = run(
        open(&path, plan(TILES, Duration::ZERO), true),
        vec![],
        &RunOptions::default(),
    );
    assert_eq!((again.end, again.session.recovered), (RunEnd::Complete, 8));
    assert!(again.prompts.is_empty() && again.progress.is_empty());
    assert_eq!(entries(&again.session), all);
    assert_eq!(again.session.calibrations().len(), 6);
    let text = std::fs::read_to_string(&path).unwrap();
    assert_eq!(text.lines().count(), 1 + 8 + 6);
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
}

/// The child process of [`a_killed_session_resumes_to_the_uninterrupted_entries`]: runs the
/// plan slowly into the journal named by [`CHILD_ENV`] until it is killed.
#[test]
fn child_process_runs_until_killed() {
    let Some(path) = std::env::var_os(CHILD_ENV) else {
        return;
    };
    let slow = plan(TILES, Duration::from_millis(100));
    run(
        open(Path::new(&path), slow, false),
        vec![],
        &RunOptions::default(),
    );
}

#[test]
fn a_killed_session_resumes_to_the_uninterrupted_entries() {
    let straight = temp("uninterrupted");
    let whole = run(
        open(&straight, plan(TILES, Duration::ZERO), false),
        vec![],
        &RunOptions::default(),
    );

    let path = temp("killed");
    // The child test's name as the harness lists it: its module path without the binary's.
    let (_, child_test) = concat!(module_path!(), "::child_process_runs_until_killed")
        .split_once("::")
        .unwrap();
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args([child_test, "--exact", "--nocapture"])
        .env(CHILD_ENV, &path)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let entry_lines = || {
        std::fs::read_to_string(&path).map_or(0, |t| {
            t.lines()
                .filter(|l| l.starts_with("{\"type\":\"entry\""))
                .count()
        })
    };
    while entry_lines() < 3 {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the child measures nothing"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap(); // SIGKILL: no handler runs, no buffer is flushed.
    child.wait().unwrap();
    let before = entry_lines();
    assert!((3..8).contains(&before), "{before} entries before the kill");

    // The settle time is not part of the plan: the fast plan resumes the slow one's journal.
    let resumed = run(
        open(&path, plan(TILES, Duration::ZERO), true),
        vec![],
        &RunOptions::default(),
    );
    assert_eq!(resumed.end, RunEnd::Complete);
    assert_eq!(resumed.session.recovered, before);
    assert_eq!(resumed.progress.len(), 8 - before);
    assert_eq!(entries(&resumed.session), entries(&whole.session));
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
    std::fs::remove_dir_all(straight.parent().unwrap()).unwrap();
}

#[test]
fn a_changed_option_is_refused_by_name_and_the_journal_left_alone() {
    let path = temp("option");
    let first = run(
        open(&path, plan(TILES, Duration::ZERO), false),
        vec![],
        &RunOptions {
            stop_after: Some(4),
            ..RunOptions::default()
        },
    );
    assert_eq!(first.end, RunEnd::Stopped { missing: 4 });
    drop(first);
    let before = std::fs::read(&path).unwrap();
    let e = Session::<String, Target>::open(
        &path,
        plan(TILES + 1, Duration::ZERO),
        "a test rig".into(),
        instruments(),
        true,
    )
    .err()
    .unwrap();
    let text = e.to_string();
    assert!(
        text.contains("was written by another session: its option tiles is 5, this one's is 6"),
        "{text}"
    );
    assert!(!text.contains("--"), "library errors name no flags: {text}");
    // Another instrument model in a role: refused, naming the role and both models.
    let mut swapped = instruments();
    swapped.get_mut("spot").unwrap().info.model = "other-spot".into();
    let e = Session::<String, Target>::open(
        &path,
        plan(TILES, Duration::ZERO),
        "a test rig".into(),
        swapped,
        true,
    )
    .err()
    .unwrap();
    assert!(
        e.to_string()
            .contains("was written with spot instrument fake-spot, this session has other-spot"),
        "{e}"
    );
    // Starting anew where a journal is: refused, saying how many entries it holds.
    let e = Session::<String, Target>::open(
        &path,
        plan(TILES, Duration::ZERO),
        "a test rig".into(),
        instruments(),
        false,
    )
    .err()
    .unwrap();
    assert!(e.to_string().contains("exists with 4 entries"), "{e}");
    assert_eq!(std::fs::read(&path).unwrap(), before);
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
}

#[test]
fn a_torn_last_line_is_set_aside_and_the_step_measured_again() {
    let path = temp("torn");
    let first = run(
        open(&path, plan(TILES, Duration::ZERO), false),
        vec![],
        &RunOptions {
            stop_after: Some(3),
            ..RunOptions::default()
        },
    );
    assert_eq!(first.end, RunEnd::Stopped { missing: 5 });
    drop(first);
    // A crash in the middle of writing the fourth entry.
    let fragment = "{\"type\":\"entry\",\"index\":3,\"label\":\"gr";
    let mut bytes = std::fs::read(&path).unwrap();
    let whole = bytes.clone();
    bytes.extend_from_slice(fragment.as_bytes());
    std::fs::write(&path, &bytes).unwrap();

    let resumed = run(
        open(&path, plan(TILES, Duration::ZERO), true),
        vec![],
        &RunOptions::default(),
    );
    assert_eq!(resumed.session.torn_bytes, fragment.len());
    assert_eq!(resumed.session.recovered, 3);
    let side = metamer::session::torn_path(&path);
    assert_eq!(
        std::fs::read_to_string(&side).unwrap(),
        format!("{fragment}\n")
    );
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.starts_with(std::str::from_utf8(&whole).unwrap()));
    assert!(text
        .lines()
        .all(|l| serde_json::from_str::<serde_json::Value>(l).is_ok()));
    assert_eq!(resumed.progress.first(), Some(&(4, 8, 3)));
    assert_eq!(entries(&resumed.session).len(), 8);
    drop(resumed);

    // Damage before the last line is no crash: an error naming file and line.
    let mut damaged = whole.clone();
    damaged.extend_from_slice(b"{\"type\":\"entry\",\"oops\n");
    damaged.extend_from_slice(text.lines().last().unwrap().as_bytes());
    damaged.push(b'\n');
    std::fs::write(&path, &damaged).unwrap();
    let e = Session::<String, Target>::open(
        &path,
        plan(TILES, Duration::ZERO),
        "a test rig".into(),
        instruments(),
        true,
    )
    .err()
    .unwrap();
    let line = whole.iter().filter(|&&b| b == b'\n').count() + 1;
    assert!(
        e.to_string().contains(&format!(
            "journal.jsonl, line {line}: not an entry or calibration"
        )),
        "{e}"
    );
    assert_eq!(std::fs::read(&path).unwrap(), damaged);
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
}

#[test]
fn an_operator_abort_keeps_what_is_measured() {
    let path = temp("abort");
    // Confirm the dark and white calibrations and tile 1, decline tile 2.
    let answers = vec![
        Answer::Confirmed,
        Answer::Confirmed,
        Answer::Confirmed,
        Answer::Abort,
    ];
    let ran = run(
        open(&path, plan(TILES, Duration::ZERO), false),
        answers,
        &RunOptions::default(),
    );
    assert_eq!(ran.end, RunEnd::Aborted { missing: 6 });
    assert_eq!(ran.session.done(), 2);
    assert_eq!(
        ran.prompts.last().map(String::as_str),
        Some(tile(2).as_str())
    );
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
}

#[test]
fn a_rig_that_lacks_what_a_step_needs_is_refused_before_measuring() {
    let path = temp("missing");
    let mut session = open(&path, plan(TILES, Duration::ZERO), false);
    let world = Shared::default();
    let mut screen = FakeScreen(world.clone());
    let mut spot = SpotMeter(world);
    let mut operator = ScriptedOperator::confirming();
    let mut rig = Rig {
        screen: Some(&mut screen),
        instruments: vec![("spot".to_string(), &mut spot as &mut dyn Instrument)],
        operator: &mut operator,
    };
    let e = session
        .run(&mut rig, &RunOptions::default(), &mut |_: &StepProgress<
            '_,
        >| {})
        .unwrap_err();
    assert_eq!(
        e.to_string(),
        "step 2 (tile 1) needs a 'spectral' instrument and the rig has none; nothing was measured"
    );
    assert_eq!(session.done(), 0);
    // An instrument that lacks the step's mode: the spot meter in the spectral role.
    let world = Shared::default();
    let mut spot = SpotMeter(world.clone());
    let mut not_spectral = SpotMeter(world);
    let mut rig = Rig {
        screen: None,
        instruments: vec![
            ("spot".to_string(), &mut spot as &mut dyn Instrument),
            ("spectral".to_string(), &mut not_spectral),
        ],
        operator: &mut operator,
    };
    let e = session
        .run(&mut rig, &RunOptions::default(), &mut |_: &StepProgress<
            '_,
        >| {})
        .unwrap_err();
    assert_eq!(
        e.to_string(),
        "step 1 (white) shows a colour and the rig has no screen; nothing was measured"
    );
    assert!(matches!(e, SessionError::RigLacks { index: 0, .. }));
    let mut screen = FakeScreen(Shared::default());
    rig.screen = Some(&mut screen);
    let e = session
        .run(&mut rig, &RunOptions::default(), &mut |_: &StepProgress<
            '_,
        >| {})
        .unwrap_err();
    assert_eq!(
        e.to_string(),
        "step 2 (tile 1) measures reflective with the 'spectral' instrument, a fake-spot that offers only emissive; nothing was measured"
    );
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
}
