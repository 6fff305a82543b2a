//! The box's adaptive plan on the simulated box: fewer placements than the paper's plan
//! with the same verdict for every spot, and rounds stopped midway and resumed that read
//! exactly what an uninterrupted session reads.

use std::path::{Path, PathBuf};

use metamer::measure_box::job::{measure, MeasureBoxRequest};
use metamer::measure_box::{BoxStage, Outcome, Summary};
use metamer::session::{NoProgress, ProgressSink, RunOptions, StageOf, StepProgress};
use metamer::validation::JND_DE76;

use crate::support::fresh_dir;

fn request(out: &Path, plan: Option<PathBuf>, adaptive: bool) -> MeasureBoxRequest {
    MeasureBoxRequest {
        out: out.to_path_buf(),
        spectral: "sim:i1pro?time_scale=0".into(),
        spot: "sim:cs100a?time_scale=0".into(),
        plan,
        repeats: None,
        adaptive,
        spot_rule: None,
        spot_white: None,
        resume: false,
        stage: None,
        seed: 1,
        scenario: None,
        force: false,
        unattended: true,
        run: RunOptions::default(),
        attendance: None,
        spot_readings: false,
    }
}

fn finished(r: &MeasureBoxRequest) -> Summary {
    match measure(r, &|_| {}, &mut |_| Box::new(NoProgress)).unwrap() {
        Outcome::Finished(s) => *s,
        o => panic!("{:?}", o.left_to_do()),
    }
}

/// Placements: one per target read (the readings of a target follow each other).
fn placements(s: &Summary) -> usize {
    s.tiles.len() + s.falloff.len() + s.materials.len() + s.spots.len()
}

/// The default box (5 × 5 tiles, the paper's nine angles a plane): the fixed plan places
/// the instruments 25 + 18 + 25 + 24 = 92 times; the adaptive one reads fewer tiles and
/// angles and its measured scene gives every spot the fixed plan's verdict against the
/// JND (the render of the scene against the box's own spot readings).
#[test]
fn the_adaptive_box_reads_fewer_placements_with_the_same_spot_verdicts() {
    let dir = fresh_dir("box-adaptive");
    let fixed = finished(&request(&dir.join("fixed"), None, false));
    let adaptive = finished(&request(&dir.join("adaptive"), None, true));
    assert_eq!(placements(&fixed), 92);
    let a = adaptive
        .adaptive
        .as_ref()
        .expect("the adaptive plan's summary");
    assert!(placements(&adaptive) <= 70, "{}", placements(&adaptive));
    assert_eq!(a.tiles_read.len() + a.tiles_predicted.len(), 25);
    assert_eq!(a.tiles_read.len(), adaptive.tiles.len());
    assert_eq!(
        adaptive.provenance.predicted_tiles, a.tiles_predicted,
        "the scene says which tiles are predicted"
    );
    let verdicts = |s: &Summary| -> Vec<bool> {
        s.render
            .comparison
            .patches
            .iter()
            .map(|p| p.de76 < JND_DE76)
            .collect()
    };
    assert_eq!(verdicts(&fixed), verdicts(&adaptive));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Entry lines of every journal of a stage directory, by file name.
fn journals(dir: &Path) -> Vec<(String, Vec<String>)> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".jsonl"))
        .collect();
    names.sort();
    names
        .into_iter()
        .map(|n| {
            let lines = std::fs::read_to_string(dir.join(&n))
                .unwrap()
                .lines()
                .filter(|l| l.starts_with("{\"type\":\"entry\""))
                // The time of a reading differs between runs; what was read does not.
                .map(|l| {
                    let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
                    v["reading"]
                        .as_object_mut()
                        .map(|r| r.remove("timestamp_s"));
                    v.to_string()
                })
                .collect();
            (n, lines)
        })
        .collect()
}

/// A rule tight enough to need rounds (0.01 JND, up to 14 tiles): the tiles stage stopped
/// after 5 readings of a round and resumed each time reads the same rounds, the same tiles in the
/// same order with the same readings, as one uninterrupted session.
#[test]
fn stopped_rounds_resume_to_the_same_plan() {
    let dir = fresh_dir("box-rounds");
    let plan = dir.join("plan.json");
    std::fs::write(
        &plan,
        r#"{"adaptive": {"tile_effect_jnd": 0.01, "max_tiles": 14}}"#,
    )
    .unwrap();
    let tiles_only = |out: &Path| MeasureBoxRequest {
        stage: Some("tiles".into()),
        ..request(out, Some(plan.clone()), false)
    };
    let whole = dir.join("whole");
    let o = measure(&tiles_only(&whole), &|_| {}, &mut |_| Box::new(NoProgress)).unwrap();
    assert!(
        matches!(o, Outcome::StagesMissing(_)),
        "{:?}",
        o.left_to_do()
    );
    let stopped = dir.join("stopped");
    let mut calls = 0;
    loop {
        let r = MeasureBoxRequest {
            resume: calls > 0,
            run: RunOptions {
                stop_after: Some(5),
                ..RunOptions::default()
            },
            ..tiles_only(&stopped)
        };
        calls += 1;
        match measure(&r, &|_| {}, &mut |_| Box::new(NoProgress)).unwrap() {
            Outcome::Incomplete { .. } => assert!(calls < 50),
            _ => break,
        }
    }
    let w = journals(&whole);
    assert!(
        w.len() > 1,
        "the rule reads more than the first pass: {:?}",
        w.iter().map(|j| &j.0).collect::<Vec<_>>()
    );
    // Each session of a call stops after 5 readings: the first pass's 18 take four calls.
    assert!(calls >= 4, "stopped {calls} times");
    assert_eq!(journals(&stopped), w);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// What a run tells its progress sink: the stages announced and the notes.
#[derive(Clone, Default)]
struct Told(std::rc::Rc<std::cell::RefCell<(Vec<StageOf>, Vec<String>)>>);

impl ProgressSink for Told {
    fn step(&mut self, _: &StepProgress<'_>) {}
    fn stage(&mut self, stage: &StageOf) {
        self.0.borrow_mut().0.push(stage.clone());
    }
    fn note(&mut self, text: &str) {
        self.0.borrow_mut().1.push(text.to_string());
    }
}

/// The tiles' rounds (a rule tight enough to need them, each later round one tile read
/// twice) stopped after every reading and resumed, with the simulated operator: each call that reads announces the tiles stage
/// (stage 1 of 4) and the round it reads with its readings and placements, as a fresh
/// round does, a resume of a later round (`tiles.batch-N.jsonl`) among them.
#[test]
fn a_resumed_later_round_prints_its_stage_header() {
    let dir = fresh_dir("box-round-header");
    let plan = dir.join("plan.json");
    std::fs::write(
        &plan,
        r#"{"adaptive": {"tile_effect_jnd": 0.01, "max_tiles": 14}}"#,
    )
    .unwrap();
    let out = dir.join("out");
    let tiles = BoxStage::Tiles;
    let stage = StageOf {
        number: 1,
        of: 4,
        name: "tiles".into(),
    };
    let mut resumed_later = 0;
    for call in 0..100 {
        let r = MeasureBoxRequest {
            stage: Some("tiles".into()),
            resume: call > 0,
            run: RunOptions {
                stop_after: Some(1),
                ..RunOptions::default()
            },
            ..request(&out, Some(plan.clone()), false)
        };
        let told = Told::default();
        let sink = told.clone();
        let o = measure(&r, &|_| {}, &mut |_| Box::new(sink.clone())).unwrap();
        let (stages, notes) = told.0.borrow().clone();
        if !matches!(o, Outcome::Incomplete { .. }) {
            break;
        }
        assert_eq!(
            stages,
            std::slice::from_ref(&stage),
            "call {call}: {notes:?}"
        );
        // The round the call stopped in is the stage's last journal; its header is said.
        let last = metamer::measure_box::adaptive::later_rounds(&out, tiles).len();
        let header = if last == 0 {
            "stage 1/4 tiles: ".to_string()
        } else {
            format!("stage 1/4 tiles round {last}: ")
        };
        assert!(
            notes
                .iter()
                .any(|n| n.contains(&header) && n.contains(" readings at ")),
            "call {call}: no `{header}` in {notes:?}"
        );
        if notes
            .iter()
            .any(|n| n.starts_with("resuming stage 1/4 tiles round "))
        {
            resumed_later += 1;
        }
    }
    assert!(resumed_later > 0, "no later round was resumed");
    std::fs::remove_dir_all(&dir).unwrap();
}
