//! The measuring cost from the stages' own files: each measuring stage's budget and what it
//! took, and each side's accuracy against its readings and minutes
//! (`validation::cost_curve`) from the box's and the display's spot journals and the
//! display's summary. A run without these files (given readings, a run made before its
//! stage kept a cost) leaves out what it lacks, with a note; it never fails the report.

use std::path::Path;

use metamer_drivers::MeasureMode;
use serde_json::Value;

use super::files::read_json;
use crate::color::{delta_e76, Xyz};
use crate::experiment::display_spots;
use crate::experiment::Stage;
use crate::session::{Cost, CostReport};
use crate::validation::cost_curve::{
    repeated_targets, repeats_curve, CostCurve, CurvePoint, Pace, BOX_SPOTS, DISPLAY_MODEL,
    DISPLAY_SPOTS,
};
use crate::validation::repeatability;
use crate::validation::report::{CostFigures, StageCost};

/// The box's spot journal, beside its summary.
const BOX_SPOTS_JOURNAL: &str = "spots.jsonl";
/// The side the display model's held-out figure is drawn as.
pub const DISPLAY_MODEL_HELD_OUT: &str = "display model, held out";
/// The largest journal read for a curve: far above a session's (a reading's line is under
/// 500 bytes, so 24 patches read 30 times make about 350 kB), so a stray file cannot
/// exhaust memory.
const MAX_JOURNAL_BYTES: u64 = 64 << 20;

/// Each measuring stage's budget and cost as its files keep them, box first; a stage
/// whose files keep none (given readings, or a run before budgets were kept) is left out.
pub fn measuring_cost(layout: RunDirs) -> Vec<StageCost> {
    let figures = |c: &Cost| CostFigures {
        readings: c.readings,
        placements: c.placements,
        calibrations: c.calibrations,
        instrument_s: c.instrument_s,
        rig_s: c.instrument_s + c.operator_s + c.settle_s,
    };
    stage_dirs(layout)
        .into_iter()
        .filter_map(|(stage, dir)| {
            let kept = crate::experiment::budget::kept(stage.name(), dir)?;
            Some(StageCost {
                stage: stage.name().to_string(),
                budget: figures(&kept.estimate),
                taken: kept.actual.as_ref().map(figures),
            })
        })
        .collect()
}

fn stage_dirs(layout: RunDirs<'_>) -> [(Stage, &Path); 3] {
    [
        (Stage::Box, layout.box_dir),
        (Stage::Display, layout.display_dir),
        (Stage::DisplaySpots, layout.display_spots_dir),
    ]
}

/// Every side's curve of the run under `layout`, named `run`, with a note for each side
/// whose files do not give one.
pub fn curves(layout: RunDirs, run: &str) -> (Vec<CostCurve>, Vec<String>) {
    let mut out = Vec::new();
    let mut notes = Vec::new();
    let display = read_json(
        &layout
            .display_dir
            .join(crate::experiment::display::SUMMARY_FILE),
    );
    let white = display
        .as_ref()
        .ok()
        .and_then(|s| xyz(&s["white_xyz"]))
        .filter(|w| w[1] > 0.0);
    let mut note = |what: &str, why: String| {
        notes.push(format!(
            "no {what} curve of {run} in the accuracy chart: {why}"
        ))
    };
    match white {
        Some(white) => {
            let box_pace = read_json(&layout.box_dir.join("summary.json"))
                .ok()
                .and_then(|s| cost_report(&s["cost"]["spots"]));
            match spots_curve(
                &layout.box_dir.join(BOX_SPOTS_JOURNAL),
                BOX_SPOTS,
                box_pace,
                white,
                run,
            ) {
                Ok(c) => out.push(c),
                Err(why) => note(BOX_SPOTS, why),
            }
            let spots_pace = read_json(&layout.display_spots_dir.join(display_spots::RECORD_FILE))
                .ok()
                .and_then(|s| cost_report(&s["cost"]));
            match spots_curve(
                &layout.display_spots_dir.join(display_spots::JOURNAL_FILE),
                DISPLAY_SPOTS,
                spots_pace,
                white,
                run,
            ) {
                Ok(c) => out.push(c),
                Err(why) => note(DISPLAY_SPOTS, why),
            }
        }
        None => note(
            "spot",
            format!(
                "the display's summary gives no white ({})",
                layout.display_dir.display()
            ),
        ),
    }
    match display {
        Ok(summary) => out.extend(model_curves(&summary, run)),
        Err(why) => note(DISPLAY_MODEL, format!("its summary {why}")),
    }
    (out, notes)
}

/// The measuring stages' directories of one run.
#[derive(Clone, Copy, Debug)]
pub struct RunDirs<'a> {
    pub box_dir: &'a Path,
    pub display_dir: &'a Path,
    pub display_spots_dir: &'a Path,
}

/// The files of the run in `layout` that a comparison with it reads, by a name for each,
/// those that exist.
pub fn compared_files(layout: RunDirs) -> Vec<(String, std::path::PathBuf)> {
    [
        ("compared box", layout.box_dir.join("summary.json")),
        ("compared box spots", layout.box_dir.join(BOX_SPOTS_JOURNAL)),
        (
            "compared display",
            layout
                .display_dir
                .join(crate::experiment::display::SUMMARY_FILE),
        ),
        (
            "compared display spots",
            layout.display_spots_dir.join(display_spots::JOURNAL_FILE),
        ),
        (
            "compared display spots record",
            layout.display_spots_dir.join(display_spots::RECORD_FILE),
        ),
    ]
    .into_iter()
    .filter(|(_, p)| p.is_file())
    .map(|(n, p)| (n.to_string(), p))
    .collect()
}

/// XYZ from a JSON array of three finite numbers.
fn xyz(v: &Value) -> Option<Xyz> {
    let a = v.as_array().filter(|a| a.len() == 3)?;
    let n: Vec<f64> = a.iter().filter_map(Value::as_f64).collect();
    (n.len() == 3 && n.iter().all(|x| x.is_finite())).then(|| Xyz::new(n[0], n[1], n[2]))
}

fn cost_report(v: &Value) -> Option<CostReport> {
    serde_json::from_value(v.clone()).ok()
}

/// The stage's time per reading (instrument and settle) and per placement as its budget
/// states them, and its placements (what it took, else its budget); nothing without a
/// cost. The budget's figures, not the clock's, so a simulated rig's minutes are a real
/// one's.
fn pace(c: Option<&CostReport>) -> Pace {
    let Some(c) = c else {
        return Pace::default();
    };
    let b = &c.estimate;
    let per = |s: f64, n: usize| if n > 0 { s / n as f64 } else { 0.0 };
    Pace {
        reading_s: per(b.instrument_s + b.settle_s, b.readings),
        placement_s: per(b.operator_s, b.placements),
        placements: c.actual.as_ref().unwrap_or(b).placements,
    }
}

/// The curve of a spot journal: its entries' readings grouped by patch (in the order
/// first read), the meter's stated emissive repeatability pooled over them.
fn spots_curve(
    journal: &Path,
    side: &str,
    cost: Option<CostReport>,
    white: Xyz,
    run: &str,
) -> Result<CostCurve, String> {
    let size = std::fs::metadata(journal)
        .map_err(|e| format!("{} cannot be read: {e}", journal.display()))?
        .len();
    if size > MAX_JOURNAL_BYTES {
        return Err(format!(
            "{} is {size} bytes, more than a journal holds",
            journal.display()
        ));
    }
    let text = std::fs::read_to_string(journal)
        .map_err(|e| format!("{} cannot be read: {e}", journal.display()))?;
    let mut options = Value::Null;
    let mut model = None;
    let mut groups: Vec<(u64, Vec<Xyz>)> = Vec::new();
    // A torn last line (an interrupted session) is set aside, as the session does.
    for line in text
        .lines()
        .filter_map(|l| serde_json::from_str::<Value>(l).ok())
    {
        match line["type"].as_str() {
            Some("header") => options = line["options"].clone(),
            Some("entry") => {
                let (Some(patch), Some(x)) =
                    (line["data"]["patch"].as_u64(), xyz(&line["reading"]["xyz"]))
                else {
                    continue;
                };
                if line["data"]["target"].as_str().is_some_and(|t| t != "spot") {
                    continue;
                }
                model = model.or_else(|| line["reading"]["instrument"].as_str().map(String::from));
                match groups.iter_mut().find(|(p, _)| *p == patch) {
                    Some((_, g)) => g.push(x),
                    None => groups.push((patch, vec![x])),
                }
            }
            _ => {}
        }
    }
    if groups.is_empty() {
        return Err(format!("{} holds no spot reading", journal.display()));
    }
    let stated = repeatability::stated(model.as_deref().unwrap_or(""), MeasureMode::Emissive);
    let readings: Vec<Vec<Xyz>> = groups.into_iter().map(|(_, g)| g).collect();
    let most = readings.iter().map(Vec::len).max().unwrap_or(0);
    let targets = repeated_targets(&readings, &stated, white);
    Ok(CostCurve {
        side: side.into(),
        plan: spots_plan(&options, most),
        run: run.into(),
        measure: "median 95 % half-width of a patch's mean".into(),
        points: repeats_curve(&targets, pace(cost.as_ref())),
    })
}

/// How a spot journal's plan read its patches, from its header's options: a rule
/// (the display's `rule`, the box plan's `spot_rule`) or a fixed count, and whether the
/// intervals rest on the figure pooled over the patches (every rule's do).
fn spots_plan(options: &Value, most: usize) -> String {
    let box_rule = options["plan"]
        .as_str()
        .and_then(|p| serde_json::from_str::<Value>(p).ok())
        .map(|p| p["spot_rule"]["rule"].as_str().map(str::to_string))
        .unwrap_or_default();
    // A verdict rule allowed no more than its least readings takes one look: a fixed count.
    let one_look = most <= crate::validation::sequential::MIN_READINGS;
    match (options["rule"].is_string(), box_rule.as_deref()) {
        (true, _) if !one_look => "until decided".into(),
        (true, _) | (false, Some("fixed")) => format!("fixed, {most} readings, pooled"),
        (false, Some(_)) => "until narrow enough".into(),
        (false, None) => format!("fixed, {most} readings"),
    }
}

/// The display model's curves from its summary: an adaptive plan's predicted error before
/// each batch and when it stopped, and either plan's held-out error.
fn model_curves(summary: &Value, run: &str) -> Vec<CostCurve> {
    let adaptive = &summary["adaptive"];
    let plan = if adaptive.is_null() {
        "fixed"
    } else {
        "adaptive"
    };
    let pace = pace(cost_report(&summary["cost"]).as_ref());
    let point = |readings: usize, value: f64| CurvePoint {
        readings,
        minutes: pace.minutes(readings),
        value,
    };
    let mut out = Vec::new();
    let mut predicted: Vec<CurvePoint> = adaptive["batches"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|b| {
            Some(point(
                b["after_readings"].as_u64()? as usize,
                b["predicted_de"].as_f64()?,
            ))
        })
        .collect();
    if let (Some(n), Some(de)) = (
        adaptive["fit_readings"].as_u64(),
        adaptive["predicted_de"].as_f64(),
    ) {
        predicted.push(point(n as usize, de));
    }
    if !predicted.is_empty() {
        out.push(CostCurve {
            side: DISPLAY_MODEL.into(),
            plan: plan.into(),
            run: run.into(),
            measure: "largest predicted ΔE*ab at the colours to reproduce".into(),
            points: predicted,
        });
    }
    let v = &summary["verification"];
    let held_out = xyz(&v["white_xyz"]).and_then(|white| {
        v["patches"]
            .as_array()?
            .iter()
            .filter_map(|p| {
                let (m, f) = (xyz(&p["measured_xyz"])?, xyz(&p["predicted_xyz"])?);
                Some(delta_e76(m.to_lab(white), f.to_lab(white)))
            })
            .reduce(f64::max)
    });
    if let (Some(de), Some(n)) = (held_out, summary["readings"].as_u64()) {
        out.push(CostCurve {
            side: DISPLAY_MODEL_HELD_OUT.into(),
            plan: plan.into(),
            run: run.into(),
            measure: "largest ΔE*ab at the held-out patches".into(),
            points: vec![point(n as usize, de)],
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::files::testdir;
    use super::*;

    /// Each journal header's way of reading spots gets its own words: the paper's count, a
    /// box plan's fixed count or width rule, a display rule with room to stop or without.
    #[test]
    fn each_spot_plan_is_named_by_how_it_read() {
        let boxed = |rule: &str| serde_json::json!({ "plan": format!("{{\"spot_rule\":{rule}}}") });
        let cases = [
            (serde_json::json!({ "plan": "{}" }), 5, "fixed, 5 readings"),
            (
                boxed(r#"{"rule":"fixed","repeats":3}"#),
                3,
                "fixed, 3 readings, pooled",
            ),
            (
                boxed(r#"{"rule":"width","half_width_jnd":0.3,"most":10}"#),
                4,
                "until narrow enough",
            ),
            (
                serde_json::json!({ "rule": "verdict 0" }),
                3,
                "until decided",
            ),
            (
                serde_json::json!({ "rule": "verdict 0" }),
                2,
                "fixed, 2 readings, pooled",
            ),
        ];
        for (options, most, words) in cases {
            assert_eq!(spots_plan(&options, most), words, "{options}");
        }
    }

    /// A hand-built display-spot journal: patch 1 read twice, patch 2 once, with a budget
    /// of 4 readings of 0.8 s and 2 placements of 30 s each (3 readings taken). The curve's
    /// readings are 2 (one each) then 3; its minutes (2·0.2 + 60)/60 and (3·0.2 + 60)/60;
    /// at m = 1 the median of the two one-reading half-widths h₁, h₂ is (h₁ + h₂)/2, at
    /// m = 2 it is (h₁/√2 + h₂)/2, so their difference is h₁(1 − 1/√2)/2.
    #[test]
    fn a_spot_journal_gives_the_curve_of_its_patches() {
        let dir = testdir::fresh("cost-curve");
        let entry = |i: usize, patch: usize, y: f64| {
            format!(
                "{{\"type\":\"entry\",\"index\":{i},\"data\":{{\"patch\":{patch},\"repeat\":1}},\"reading\":{{\"xyz\":[{},{y},{}],\"instrument\":\"cs100a\"}}}}\n",
                0.95 * y,
                1.09 * y
            )
        };
        let journal = format!(
            "{{\"type\":\"header\",\"options\":{{\"repeats\":\"2\"}}}}\n{}{}{}{{\"type\":\"ent",
            entry(0, 1, 4.0),
            entry(1, 1, 4.1),
            entry(2, 2, 8.0)
        );
        testdir::write(&dir, "journal.jsonl", &journal);
        let cost = CostReport {
            estimate: Cost {
                readings: 4,
                placements: 2,
                instrument_s: 0.8,
                operator_s: 60.0,
                ..Cost::default()
            },
            actual: Some(Cost {
                readings: 3,
                placements: 2,
                instrument_s: 0.9,
                ..Cost::default()
            }),
        };
        let white = Xyz::new(95.047, 100.0, 108.883);
        let c = spots_curve(
            &dir.join("journal.jsonl"),
            DISPLAY_SPOTS,
            Some(cost),
            white,
            "this run",
        )
        .unwrap();
        assert_eq!(c.plan, "fixed, 2 readings");
        let readings: Vec<usize> = c.points.iter().map(|p| p.readings).collect();
        assert_eq!(readings, [2, 3]);
        assert!((c.points[0].minutes - 60.4 / 60.0).abs() < 1e-12, "{c:?}");
        assert!((c.points[1].minutes - 60.6 / 60.0).abs() < 1e-12, "{c:?}");
        let stated = repeatability::stated("cs100a", MeasureMode::Emissive);
        let t = repeated_targets(
            &[
                vec![Xyz::new(3.895, 4.1, 4.469), Xyz::new(3.8, 4.0, 4.36)],
                vec![Xyz::new(7.6, 8.0, 8.72)],
            ],
            &stated,
            white,
        );
        let h1 = t[0].one_reading;
        let drop = c.points[0].value - c.points[1].value;
        assert!(
            (drop - h1 * (1.0 - 0.5f64.sqrt()) / 2.0).abs() < 1e-9,
            "{c:?}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A run without journals, summaries or costs (given readings, an old run) gives no
    /// curve, only notes.
    #[test]
    fn a_run_without_its_files_gives_notes_only() {
        let dir = testdir::fresh("cost-none");
        let layout = RunDirs {
            box_dir: &dir.join("box"),
            display_dir: &dir.join("display"),
            display_spots_dir: &dir.join("display-spots"),
        };
        let (c, notes) = curves(layout, "this run");
        assert!(c.is_empty());
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(measuring_cost(layout).is_empty());
        std::fs::remove_dir_all(&dir).ok();
    }
}
