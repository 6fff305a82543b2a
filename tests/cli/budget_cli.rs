//! The measuring budget on the command line: said before the first reading, counting only
//! what a resumed session still lacks, kept with what the session took in its summary;
//! and `--placement-seconds` checked as a usage error on every measuring command.

use std::process::{Command, Output};

use serde_json::Value;

use crate::support::{text, unused_dir};

fn metamer(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(args)
        .env_remove("METAMER_SIM_TIME_SCALE")
        .output()
        .expect("the metamer binary runs")
}

/// The line number of the first line of `text` that starts with `start`.
fn line_of(text: &str, start: &str) -> usize {
    text.lines()
        .position(|l| l.starts_with(start))
        .unwrap_or_else(|| panic!("no line starts with {start:?} in:\n{text}"))
}

/// A characterization stopped after 10 of its 86 readings and resumed: each run says its
/// budget before its readings and their cost after, the resumed one for the 76 readings left, and
/// the summary keeps the resumed run's budget and cost. The simulated CS-100A counts its
/// time as the real meter's protocol states it, so budget and cost agree to the
/// nanosecond rounding of its wire time: 76 × (0.1 s + 33 characters × 11 bits / 4800 baud).
#[test]
fn the_budget_comes_before_the_first_reading_and_a_resumed_one_counts_what_is_left() {
    let dir = unused_dir("budget");
    let d = dir.to_str().unwrap();
    let args = [
        "characterize",
        "--display",
        "virtual:ips-lcd",
        "--instrument",
        "sim:cs100a?time_scale=0",
        "-o",
        d,
    ];
    let o = metamer(&[args.as_slice(), &["--stop-after", "10"]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    let budget = line_of(
        &err,
        "budget of the display's patches: 86 readings in 0 placements",
    );
    assert!(line_of(&err, "cost of the display's patches: 10 readings") > budget);

    let o = metamer(&[args.as_slice(), &["--resume"]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    let budget = line_of(
        &err,
        "budget of the display's patches: 76 readings in 0 placements",
    );
    // Without a terminal the last reading has a line of its own.
    let last = line_of(&err, "patch 86/86");
    assert!(budget < last, "{err}");
    assert!(line_of(&err, "cost of the display's patches: 76 readings") > last);

    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let cost = &summary["cost"];
    let by_hand = 76.0 * (0.1 + 33.0 * 11.0 / 4800.0);
    for side in ["estimate", "actual"] {
        assert_eq!(cost[side]["readings"], 76, "{cost}");
        let s = cost[side]["instrument_s"].as_f64().unwrap();
        assert!(
            (s - by_hand).abs() < 1e-5,
            "{side}: {s} s, by hand {by_hand} s"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_bad_placement_time_is_a_usage_error_on_every_measuring_command() {
    let dir = unused_dir("placement");
    let d = dir.to_str().unwrap();
    let commands: [&[&str]; 4] = [
        &[
            "characterize",
            "--display",
            "virtual",
            "--instrument",
            "sim:cs100a",
            "-o",
            d,
        ],
        &[
            "measure-box",
            "--spectral",
            "sim:i1pro",
            "--spot",
            "sim:cs100a",
            "-o",
            d,
        ],
        &["experiment", "--spectral", "sim:i1pro", "-o", d],
        &["lab", "-o", d],
    ];
    for command in commands {
        for bad in ["-1", "nan", "86401", "soon"] {
            let o = metamer(&[command, &[&format!("--placement-seconds={bad}")]].concat());
            let err = text(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{command:?} {bad}: {err}");
            assert!(err.contains("placement time"), "{command:?} {bad}: {err}");
        }
    }
    assert!(!dir.exists(), "a refused command wrote {d}");
}
