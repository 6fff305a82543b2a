//! The study of "measure only what the verdict needs": `metamer lab` with the fixed plans
//! and with other plan options on the same seed, for each simulated display, each box
//! light and a few seeds, compared by `metamer::experiment::lab::compare` (readings from
//! the journals, placements, real-pace minutes with a CS-100A and with an i1Pro on the
//! display, each patch's verdict against the fixed run's, the display-vs-box interval
//! width) and printed as tables with each bar's pass or fail. An ignored study
//! (`--ignored`); its tables are in docs/benchmarks.md.
//!
//! Each run goes to `METAMER_STUDY_DIR` (default `target/lab-study`) as
//! `PRESET-SCENARIO-seedN/ARM/`; a finished run there is re-used whole by `lab` itself, so
//! a second call only reads the folders. The environment chooses what runs:
//!
//! - `METAMER_STUDY_PRESETS`, `METAMER_STUDY_SCENARIOS`, `METAMER_STUDY_SEEDS`: lists
//!   separated by spaces (default every preset, both lights, seeds 1 and 2);
//! - `METAMER_STUDY_ARMS`: `NAME=ARGS;NAME=ARGS…`, each arm the `lab` options it adds to
//!   the fixed run's (default: [`DEFAULT_ARM`]). In ARGS, `--plan width:H` stands for a
//!   box plan whose spots are read by the width rule at H × the JND (at most 10),
//!   `--plan fixed:N` for one whose spots are read N times each under a stated rule (so
//!   with the figure pooled across the spots), and `width:H:rR` or `fixed:N:rR` the same
//!   with R readings of each tile; any other option (such as `--box-plan adaptive`) is
//!   passed as it is;
//! - `METAMER_STUDY_JOBS`: runs at a time (default 1).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use metamer::experiment::lab::compare::{verdict_word, LabComparison, LabFigures};

use crate::support::metamer_unscaled;

/// The options that exist today: the adaptive display plan, the display's spots
/// until their verdict is decided (0.1 beyond the JND, at most 6), the box's spots by the
/// width rule at 0.2 JND.
const DEFAULT_ARM: &str =
    "adaptive=--display-plan adaptive --until-decided 0.1 --repeats 6 --plan width:0.2";

/// The white the width rule's CIELAB is taken against: the ips-lcd's, which lights the
/// box in the default scenario (docs/benchmarks.md uses the same).
const SPOT_WHITE: &str = "[15.573, 16.34, 18.356]";

fn list(var: &str, default: &str) -> Vec<String> {
    std::env::var(var)
        .unwrap_or_else(|_| default.to_string())
        .split_whitespace()
        .map(String::from)
        .collect()
}

/// The plan file for `width:H[:rR]` or `fixed:N[:rR]`, written into `plans` once.
fn rule_plan(plans: &Path, spec: &str) -> PathBuf {
    let mut parts = spec.split(':');
    let kind = parts.next().expect("width or fixed");
    let value = parts.next().expect("width:H or fixed:N");
    let repeats = parts.next().map(|r| r.trim_start_matches('r'));
    let (name, lead) = match repeats {
        Some(r) => (
            format!("{kind}-{value}-r{r}.json"),
            format!("\"repeats\": {r}, "),
        ),
        None => (format!("{kind}-{value}.json"), String::new()),
    };
    let rule = match kind {
        "width" => format!(
            "{{\"rule\": \"width\", \"half_width_jnd\": {value}, \"most\": 10}}, \"spot_white\": {SPOT_WHITE}"
        ),
        _ => format!("{{\"rule\": \"fixed\", \"repeats\": {value}}}"),
    };
    let path = plans.join(name);
    let text = format!("{{{lead}\"spot_rule\": {rule}}}\n");
    std::fs::create_dir_all(plans).unwrap();
    if std::fs::read_to_string(&path).ok().as_deref() != Some(text.as_str()) {
        std::fs::write(&path, text).unwrap();
    }
    path
}

/// The arms: name and `lab` options, `--plan width:…` and `--plan fixed:…` made a file.
fn arms(plans: &Path) -> Vec<(String, Vec<String>)> {
    std::env::var("METAMER_STUDY_ARMS")
        .unwrap_or_else(|_| DEFAULT_ARM.to_string())
        .split(';')
        .filter(|a| !a.trim().is_empty())
        .map(|arm| {
            let (name, args) = arm.split_once('=').expect("NAME=ARGS");
            let args = args
                .split_whitespace()
                .map(|a| {
                    if a.starts_with("width:") || a.starts_with("fixed:") {
                        rule_plan(plans, a).display().to_string()
                    } else {
                        a.to_string()
                    }
                })
                .collect();
            (name.trim().to_string(), args)
        })
        .collect()
}

/// Runs (or re-uses) one lab into `dir`.
fn lab(dir: &Path, args: &[String]) {
    std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
    let mut all = vec!["lab".to_string(), "-o".into(), dir.display().to_string()];
    all.extend(args.iter().cloned());
    let o = metamer_unscaled(&all);
    assert!(
        o.status.success(),
        "metamer {}\n{}\n{}",
        all.join(" "),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

fn mark(holds: bool) -> &'static str {
    if holds {
        "✓"
    } else {
        "✗"
    }
}

#[test]
#[ignore = "a study: cargo test --release --test experiment -- --ignored --nocapture lab_study::print_lab_study_table"]
fn print_lab_study_table() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::var("METAMER_STUDY_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|_| root.join("target/lab-study"));
    let plans = dir.join("plans");
    let arms = arms(&plans);
    let mut cases = Vec::new();
    for seed in list("METAMER_STUDY_SEEDS", "1 2") {
        for scenario in list("METAMER_STUDY_SCENARIOS", "display-white led-rgb1") {
            for preset in list("METAMER_STUDY_PRESETS", "ips-lcd wide-gamut-ccfl ideal-crt") {
                cases.push((preset, scenario.clone(), seed.clone()));
            }
        }
    }
    // Every run, fixed and arms, as one queue.
    let mut runs: Vec<(PathBuf, Vec<String>)> = Vec::new();
    for (preset, scenario, seed) in &cases {
        let case = dir.join(format!("{preset}-{scenario}-seed{seed}"));
        let base: Vec<String> = ["--display", preset, "--scenario", scenario, "--seed", seed]
            .iter()
            .map(|s| s.to_string())
            .collect();
        runs.push((case.join("fixed"), base.clone()));
        for (name, args) in &arms {
            let mut a = base.clone();
            a.extend(args.iter().cloned());
            runs.push((case.join(name), a));
        }
    }
    let jobs: usize = std::env::var("METAMER_STUDY_JOBS")
        .ok()
        .and_then(|j| j.parse().ok())
        .unwrap_or(1);
    let queue = Mutex::new(runs.into_iter());
    std::thread::scope(|s| {
        for _ in 0..jobs.max(1) {
            s.spawn(|| loop {
                let next = queue.lock().unwrap().next();
                let Some((d, args)) = next else { break };
                lab(&d, &args);
                eprintln!("ran {}", d.display());
            });
        }
    });

    println!("arms: {}", {
        let a: Vec<String> = arms
            .iter()
            .map(|(n, a)| format!("{n} = `{}`", a.join(" ")))
            .collect();
        a.join("; ")
    });
    println!();
    println!("| display | light | seed | arm | readings: box tiles / fall-off / materials / spots · display · display spots = all | box placements | minutes, CS-100A / i1Pro on the display | display vs box median 95 % width |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    let mut compared = Vec::new();
    for (preset, scenario, seed) in &cases {
        let case = dir.join(format!("{preset}-{scenario}-seed{seed}"));
        let fixed = LabFigures::read(&case.join("fixed")).unwrap();
        let row = |arm: &str, f: &LabFigures| {
            let width = metamer::experiment::lab::compare::median_width(
                f.comparison("display_vs_box").unwrap_or(&[]),
            );
            println!(
                "| {preset} | {scenario} | {seed} | {arm} | {} / {} / {} / {} · {} · {} = {} | {} | {:.1} / {:.1} | {width:.3} |",
                f.stage_readings("box", "tiles"),
                f.stage_readings("box", "falloff"),
                f.stage_readings("box", "materials"),
                f.stage_readings("box", "spots"),
                f.stage_readings("display", ""),
                f.stage_readings("display-spots", ""),
                f.readings(),
                f.box_placements(),
                f.minutes_with("cs100a").unwrap_or(f64::NAN),
                f.minutes_with("i1pro").unwrap_or(f64::NAN),
            );
        };
        row("fixed", &fixed);
        for (name, _) in &arms {
            let other = LabFigures::read(&case.join(name)).unwrap();
            row(name, &other);
            compared.push((
                format!("{preset} | {scenario} | {seed} | {name}"),
                LabComparison::new(fixed.clone(), other),
            ));
        }
    }
    println!();
    let Some((_, first)) = compared.first() else {
        return;
    };
    let bars: Vec<String> = first.bars().into_iter().map(|b| b.bar).collect();
    println!("| display | light | seed | arm | {} |", bars.join(" | "));
    println!("| --- | --- | --- | --- |{}", " --- |".repeat(bars.len()));
    let mut held = vec![0; bars.len()];
    for (name, c) in &compared {
        let cells: Vec<String> = c
            .bars()
            .into_iter()
            .enumerate()
            .map(|(i, b)| {
                held[i] += usize::from(b.holds);
                format!("{} {}", mark(b.holds), b.figure)
            })
            .collect();
        println!("| {name} | {} |", cells.join(" | "));
    }
    println!();
    for (bar, n) in bars.iter().zip(&held) {
        println!("- {bar}: holds in {n} of {}", compared.len());
    }
    // The changed verdicts in full, for the notes.
    for (name, c) in &compared {
        for v in &c.verdicts {
            for (patch, a, b) in &v.changed {
                println!(
                    "changed: {name}: {} patch {patch}: {} → {}",
                    v.name,
                    verdict_word(*a),
                    verdict_word(*b)
                );
            }
        }
    }
}
