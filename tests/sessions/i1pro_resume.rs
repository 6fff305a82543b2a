//! A measure-box session on the simulated i1Pro, interrupted and resumed with fresh
//! instruments (as a new process would have), reads exactly what an uninterrupted session
//! reads — noise on, so the calibration's noise counts too: a resumed i1Pro must calibrate
//! again, and that calibration must be the one the uninterrupted session made.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use metamer::measure_box::simulated_box::{BoxOperator, SimulatedBox};
use metamer::measure_box::{self, BoxDetails, BoxOptions, BoxPlan, BoxStage, Instruments, Outcome};
use metamer::output::OutputPolicy;
use metamer::rig::scenario::Scenario;
use metamer::session::{NoProgress, RunEnd, RunOptions};
use metamer_drivers::{SharedWorld, Spec, View};

use crate::support::unused_dir;

const SEED: u64 = 3;
const SPECTRAL: &str = "sim:i1pro?time_scale=0";
const SPOT: &str = "sim:cs100a?time_scale=0";

fn plan() -> BoxPlan {
    BoxPlan {
        repeats: 1,
        ..BoxPlan::default()
    }
}

/// Runs the tiles stage in `dir` with instruments opened afresh, as a new process would.
fn run(dir: &Path, resume: bool, stop_after: Option<usize>) -> Outcome {
    let plan = plan();
    let truth = SimulatedBox::new(&plan, SEED, Scenario::default()).unwrap();
    let world = Arc::new(SharedWorld::new(View::Capped));
    let mut spectral = Spec::new(SPECTRAL)
        .with_seed_unless_set(SEED)
        .open(Some(world.clone()))
        .unwrap();
    let mut spot = Spec::new(SPOT)
        .with_seed_unless_set(SEED + 1)
        .open(Some(world.clone()))
        .unwrap();
    let mut operator = BoxOperator::new(truth, world);
    let options = BoxOptions {
        dir: dir.to_path_buf(),
        plan,
        stage: Some(BoxStage::Tiles),
        resume,
        rig_options: BTreeMap::from([("seed".to_string(), SEED.to_string())]),
        details: BoxDetails {
            spectral: SPECTRAL.into(),
            spot: SPOT.into(),
        },
        run: RunOptions {
            stop_after,
            interrupt: None,
            placement_s: None,
        },
        output: OutputPolicy::new(false),
    };
    measure_box::run(
        &options,
        Instruments {
            spectral: spectral.as_mut(),
            spot: spot.as_mut(),
        },
        &mut operator,
        &mut NoProgress,
    )
    .unwrap()
}

/// The journal's entries without their wall-clock times, and its calibration records.
fn journal(dir: &Path) -> (Vec<serde_json::Value>, Vec<serde_json::Value>) {
    let text = std::fs::read_to_string(BoxStage::Tiles.journal(dir)).unwrap();
    let (mut entries, mut calibrations) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let mut v: serde_json::Value = serde_json::from_str(line).unwrap();
        match v["type"].as_str() {
            Some("entry") => {
                v["reading"].as_object_mut().unwrap().remove("timestamp_s");
                entries.push(v);
            }
            Some("calibration") => calibrations.push(v),
            _ => {}
        }
    }
    (entries, calibrations)
}

fn stopped(outcome: Outcome) -> bool {
    matches!(
        outcome,
        Outcome::Incomplete {
            end: RunEnd::Stopped { .. },
            ..
        }
    )
}

#[test]
fn a_resumed_i1pro_session_reads_what_an_uninterrupted_one_reads() {
    let whole = unused_dir("whole");
    assert!(!stopped(run(&whole, false, None)));
    let (expected, calibrations) = journal(&whole);
    assert_eq!(expected.len(), 25);
    assert_eq!(calibrations.len(), 1, "{calibrations:?}");
    assert_eq!(calibrations[0]["before_step"], 0);

    // Stopped twice, each part with new instruments: the second resume stands for the
    // first run's calibration too, through the resumed run's record of it.
    let parts = unused_dir("parts");
    assert!(stopped(run(&parts, false, Some(4))));
    assert!(stopped(run(&parts, true, Some(7))));
    assert!(!stopped(run(&parts, true, None)));
    let (entries, calibrations) = journal(&parts);
    assert_eq!(entries.len(), 25);
    let before: Vec<_> = calibrations.iter().map(|c| &c["before_step"]).collect();
    assert_eq!(before, [0, 4, 11]);
    let noise: Vec<_> = calibrations.iter().map(|c| &c["noise_step"]).collect();
    assert_eq!(noise, [0, 0, 0]);
    for (k, (a, b)) in expected.iter().zip(&entries).enumerate() {
        assert_eq!(a, b, "tile reading {k}");
    }
    std::fs::remove_dir_all(&whole).ok();
    std::fs::remove_dir_all(&parts).ok();
}
