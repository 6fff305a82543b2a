//! Two small hand-built lab folders: a few journal entries per stage, `lab.json`'s budget
//! and `comparisons.json`'s verdicts, with every figure counted by hand.

use std::path::{Path, PathBuf};

use super::*;

/// A CS-100A reading at FAST: 100 ms measuring plus 33 characters at 4800 baud, 11 bits
/// each (`protocols/cs100a/README.md`): 0.1 + 33 × 11 / 4800 = 0.175625 s.
const CS100A_READING_S: f64 = 0.175_625;

fn fresh(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("metamer-lab-compare-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A journal of `n` CS-100A emissive entries at luminance `y`, after a header.
fn journal(file: &Path, n: usize, y: f64) {
    std::fs::create_dir_all(file.parent().unwrap()).unwrap();
    let mut text = String::from(
        "{\"type\":\"header\",\"format\":\"metamer-session-journal\",\"version\":2}\n",
    );
    for i in 0..n {
        text.push_str(&format!(
            "{{\"type\":\"entry\",\"index\":{i},\"mode\":\"emissive\",\"reading\":{{\"xyz\":[{y},{y},{y}],\"instrument\":\"cs100a\"}}}}\n"
        ));
    }
    std::fs::write(file, text).unwrap();
}

fn cost(readings: usize, placements: usize) -> String {
    format!(
        "{{\"readings\":{readings},\"placements\":{placements},\"calibrations\":0,\"instrument_s\":1.0,\"operator_s\":0.0,\"settle_s\":0.0,\"wall_s\":2.0}}"
    )
}

/// `lab.json` with the stages' placements as taken.
fn lab_json(dir: &Path, placements: [usize; 3]) {
    let stage = |name: &str, p: usize| {
        format!(
            "{{\"stage\":\"{name}\",\"cost\":{{\"estimate\":{},\"actual\":{}}}}}",
            cost(1, p),
            cost(1, p)
        )
    };
    let text = format!(
        "{{\"budget\":[{},{},{}],\"budget_total\":{{\"estimate\":{},\"actual\":{}}}}}",
        stage("box", placements[0]),
        stage("display", placements[1]),
        stage("display-spots", placements[2]),
        cost(3, 1),
        cost(3, 1)
    );
    std::fs::write(dir.join(LAB_FILE), text).unwrap();
}

/// `comparisons.json` with each comparison's patches as (verdict, interval lo, hi).
fn comparisons(dir: &Path, sides: [&[(&str, f64, f64)]; 3]) {
    let v = dir.join("validation");
    std::fs::create_dir_all(&v).unwrap();
    let one = |patches: &[(&str, f64, f64)]| {
        let p: Vec<String> = patches
            .iter()
            .enumerate()
            .map(|(i, (jnd, lo, hi))| {
                format!(
                    "{{\"patch\":{},\"de76_interval\":{{\"lo\":{lo},\"hi\":{hi}}},\"jnd\":\"{jnd}\"}}",
                    i + 1
                )
            })
            .collect();
        format!("{{\"patches\":[{}]}}", p.join(","))
    };
    let text = format!(
        "{{\"version\":1,\"display_vs_box\":{},\"simulation_vs_box\":{},\"display_vs_simulation\":{}}}",
        one(sides[0]),
        one(sides[1]),
        one(sides[2])
    );
    std::fs::write(v.join(COMPARISONS_FILE), text).unwrap();
}

/// The fixed run: box 4 + 2 + 6 readings in 5 placements, the display's 7 in one journal,
/// 6 display spots in 2 placements: 25 readings, 7 placements.
fn fixed_run() -> PathBuf {
    let d = fresh("fixed");
    journal(&d.join("box/tiles.jsonl"), 4, 100.0);
    journal(&d.join("box/falloff.jsonl"), 2, 50.0);
    journal(&d.join("box/spots.jsonl"), 6, 5.0);
    journal(&d.join("display/log.jsonl"), 7, 10.0);
    journal(&d.join("display-spots/journal.jsonl"), 6, 10.0);
    lab_json(&d, [5, 0, 2]);
    comparisons(
        &d,
        [
            &[
                ("below", 0.1, 0.5),
                ("undecided", 2.0, 3.0),
                ("above", 2.5, 3.1),
                ("undecided", 1.9, 2.6),
            ],
            &[("below", 0.0, 0.2), ("below", 0.0, 0.4)],
            &[("above", 3.0, 4.0)],
        ],
    );
    d
}

/// The other run: box 4 + 2 + 3, the display's 3 + 2 in two journals, 4 display spots in
/// 2 placements: 18 readings, 7 placements.
fn other_run() -> PathBuf {
    let d = fresh("other");
    journal(&d.join("box/tiles.jsonl"), 4, 100.0);
    journal(&d.join("box/falloff.jsonl"), 2, 50.0);
    journal(&d.join("box/spots.jsonl"), 3, 5.0);
    journal(&d.join("display/log.jsonl"), 3, 10.0);
    journal(&d.join("display/log.verify.jsonl"), 2, 10.0);
    journal(&d.join("display-spots/journal.jsonl"), 4, 10.0);
    lab_json(&d, [5, 0, 2]);
    comparisons(
        &d,
        [
            &[
                ("below", 0.2, 0.8),
                ("below", 1.5, 2.2),
                ("below", 1.8, 2.2),
                ("undecided", 1.8, 2.8),
            ],
            &[("below", 0.0, 0.2), ("undecided", 1.0, 2.5)],
            &[("above", 3.0, 4.0)],
        ],
    );
    d
}

#[test]
fn two_hand_built_runs_give_the_hand_counted_figures() {
    let (fixed_dir, other_dir) = (fixed_run(), other_run());
    let fixed = LabFigures::read(&fixed_dir).unwrap();
    let other = LabFigures::read(&other_dir).unwrap();
    assert_eq!(fixed.readings(), 25);
    assert_eq!(other.readings(), 18);
    assert_eq!(fixed.stage_readings("box", "spots"), 6);
    assert_eq!(other.stage_readings("display", ""), 5);
    assert_eq!(other.box_placements(), 5);
    // Every reading a CS-100A's, 7 placements at 30 s (the driver states its reading
    // time to within a microsecond of the hand figure).
    let by_hand = |n: usize| (n as f64 * CS100A_READING_S + 7.0 * 30.0) / 60.0;
    assert!((fixed.minutes_with("cs100a").unwrap() - by_hand(25)).abs() < 1e-5);
    assert!((other.minutes_with("cs100a").unwrap() - by_hand(18)).abs() < 1e-5);
    // With an i1Pro on the display: the box's 9 CS-100A readings as before; the display's
    // 5 and the display spots' 4, all at 10 cd/m², each stage its own session with the
    // calibrations it needs.
    let i1pro = metamer_drivers::time_budget("i1pro", &TimeQuery::new(MeasureMode::Emissive, 10.0))
        .unwrap();
    let want =
        (9.0 * CS100A_READING_S + i1pro.session_s(5) + i1pro.session_s(4) + 7.0 * 30.0) / 60.0;
    assert!((other.minutes_with("i1pro").unwrap() - want).abs() < 1e-5);
    assert!(other.states_cost());

    let c = LabComparison::new(fixed, other);
    // display vs box: same, decided, changed (above → below), same.
    let d = &c.verdicts[0];
    assert_eq!((d.same, d.decided, d.unmatched), (2, 1, 0));
    assert_eq!(d.changed, vec![(3, JndVerdict::Above, JndVerdict::Below)]);
    // simulation vs box: the second patch below → undecided is a change.
    assert_eq!(c.verdicts[1].same, 1);
    assert_eq!(c.verdicts[1].changed.len(), 1);
    assert_eq!((c.verdicts[2].same, c.verdicts[2].changed.len()), (1, 0));
    // Widths: fixed 0.4, 1.0, 0.6, 0.7 → median 0.65; other 0.6, 0.7, 0.4, 1.0 → 0.65.
    assert!((c.width_ratio - 1.0).abs() < 1e-12, "{}", c.width_ratio);
    let bars = c.bars();
    let holds: Vec<bool> = bars.iter().map(|b| b.holds).collect();
    // 18 > 0.4 × 25; 5 placements ≤ 70; minutes not under 40 %; two comparisons changed.
    assert_eq!(
        holds,
        vec![false, true, false, false, false, false, true, true, true]
    );
    for d in [fixed_dir, other_dir] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn a_verdict_is_the_same_decided_or_changed() {
    use JndVerdict::*;
    assert_eq!(VerdictClass::of(Below, Below), VerdictClass::Same);
    assert_eq!(VerdictClass::of(Undecided, Above), VerdictClass::Decided);
    assert_eq!(VerdictClass::of(Below, Undecided), VerdictClass::Changed);
    assert_eq!(VerdictClass::of(Above, Below), VerdictClass::Changed);
}

#[test]
fn a_folder_without_its_files_is_refused_naming_the_file() {
    let d = fresh("empty");
    let e = LabFigures::read(&d).unwrap_err().to_string();
    assert!(e.contains("lab.json"), "{e}");
    let _ = std::fs::remove_dir_all(d);
}
