//! Two lab runs on the same seed compared against the bars of "measure only what the
//! verdict needs": a run with the fixed plans and a run with other plan options (adaptive
//! display patches, display spots until decided, box spots by a width rule, …). Everything
//! is read from the two folders as the stages left them, so a study, the report or a chart
//! can ask the same figures of any pair of finished runs.
//!
//! - **Readings** are counted from the journals (every `entry` line of each stage's
//!   `*.jsonl`), not from the budgets, so they are what was measured.
//! - **Placements** are the stages' own record of what they took (`lab.json`'s `budget`):
//!   a journal does not say where the operator moved the instrument.
//! - **Minutes** are the journals' readings costed at the real pace: each reading's time
//!   from its model's stated facts at the luminance it read
//!   ([`metamer_drivers::time_budget`]), with the calibrations each stage's instrument and
//!   mode need ([`TimeBudget::session_s`]), plus [`PLACEMENT_S`] per placement; the display
//!   and display-spots readings costed once as the CS-100A's and once as an i1Pro's (the
//!   same readings, the other meter), the box's as the instruments that read them.
//! - **Verdicts** and interval widths are each patch's of `validation/comparisons.json`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metamer_drivers::{MeasureMode, TimeBudget, TimeQuery};
use serde::Deserialize;

use super::LAB_FILE;
use crate::experiment::budget::StageBudget;
use crate::experiment::validate::FILE as COMPARISONS_FILE;
use crate::experiment::Stage;
use crate::session::budget::PLACEMENT_S;
use crate::session::CostReport;
use crate::validation::JndVerdict;

#[cfg(test)]
mod tests;

/// The bar on all readings: at most this share of the fixed plan's.
pub const READINGS_SHARE: f64 = 0.4;
/// The bar on the box's placements (the fixed plan's are 92).
pub const MOST_BOX_PLACEMENTS: usize = 70;
/// The bar on the estimated real-pace minutes: at most this share of the fixed plan's.
pub const MINUTES_SHARE: f64 = 0.4;
/// The bar on the median 95 % interval width of display-vs-box ΔE*ab: at most this times
/// the fixed plan's.
pub const WIDTH_RATIO: f64 = 1.1;
/// The meters the display's readings are costed as: the lab's own and the i1Pro.
pub const DISPLAY_METERS: [&str; 2] = ["cs100a", "i1pro"];
/// The three comparisons, as `comparisons.json` names them.
pub const COMPARISONS: [&str; 3] = [
    "display_vs_box",
    "simulation_vs_box",
    "display_vs_simulation",
];

/// A folder that does not give the figures.
#[derive(Debug, thiserror::Error)]
pub enum FiguresError {
    #[error("{}: {message}", file.display())]
    Read { file: PathBuf, message: String },
    #[error("{}:{line}: {message}", file.display())]
    Line {
        file: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{}: no stage {stage} in its budget", file.display())]
    NoStage { file: PathBuf, stage: String },
    #[error("{}: stage {stage} keeps no record of what it took", file.display())]
    NotTaken { file: PathBuf, stage: String },
    #[error("{}: no comparison {name}", file.display())]
    NoComparison { file: PathBuf, name: String },
}

/// One journal's readings.
#[derive(Clone, Debug, PartialEq)]
pub struct JournalReadings {
    /// The stage's directory name.
    pub stage: String,
    /// The journal's file name.
    pub journal: String,
    pub readings: usize,
}

/// One patch of one comparison: its JND verdict and the width (hi − lo) of its 95 %
/// ΔE*ab interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchWidth {
    pub patch: usize,
    pub jnd: JndVerdict,
    pub width: f64,
}

/// The figures of one finished lab run.
#[derive(Clone, Debug, PartialEq)]
pub struct LabFigures {
    pub dir: PathBuf,
    pub journals: Vec<JournalReadings>,
    /// Placements each measuring stage took, by its directory name.
    pub placements: BTreeMap<String, usize>,
    /// The real-pace minutes with the display read by each of [`DISPLAY_METERS`].
    pub minutes: Vec<(String, f64)>,
    /// Each of [`COMPARISONS`]' patches.
    pub comparisons: Vec<(String, Vec<PatchWidth>)>,
    /// `lab.json`'s total: the budget before the first reading and what was taken.
    pub budget_total: CostReport,
}

/// The measuring stages, in the order they run.
fn measuring_stages() -> [&'static str; 3] {
    [
        Stage::Box.name(),
        Stage::Display.name(),
        Stage::DisplaySpots.name(),
    ]
}

/// The part of a journal line this reads.
#[derive(Deserialize)]
struct Line {
    #[serde(rename = "type")]
    kind: String,
    #[serde(default)]
    mode: Option<MeasureMode>,
    #[serde(default)]
    reading: Option<LineReading>,
}

#[derive(Deserialize)]
struct LineReading {
    xyz: [f64; 3],
    instrument: String,
}

/// The part of `lab.json` this reads.
#[derive(Deserialize)]
struct LabFile {
    budget: Vec<StageBudget>,
    budget_total: CostReport,
}

/// The part of `comparisons.json` this reads.
#[derive(Deserialize)]
struct PatchPart {
    patch: usize,
    de76_interval: crate::validation::propagate::Interval,
    jnd: JndVerdict,
}

#[derive(Deserialize)]
struct AssessmentPart {
    patches: Vec<PatchPart>,
}

fn read_text(file: &Path) -> Result<String, FiguresError> {
    std::fs::read_to_string(file).map_err(|e| FiguresError::Read {
        file: file.to_path_buf(),
        message: e.to_string(),
    })
}

/// One reading as the minutes need it: model, mode, luminance.
struct Taken {
    model: String,
    mode: MeasureMode,
    luminance: f64,
}

/// The entries of the journal `file`.
fn entries(file: &Path) -> Result<Vec<Taken>, FiguresError> {
    let text = read_text(file)?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let bad = |message: String| FiguresError::Line {
            file: file.to_path_buf(),
            line: i + 1,
            message,
        };
        let l: Line = serde_json::from_str(line).map_err(|e| bad(e.to_string()))?;
        if l.kind != "entry" {
            continue;
        }
        let r = l
            .reading
            .ok_or_else(|| bad("an entry without its reading".into()))?;
        out.push(Taken {
            model: r.instrument,
            mode: l.mode.unwrap_or_default(),
            luminance: r.xyz[1].max(0.0),
        });
    }
    Ok(out)
}

/// The journals of the stage directory `dir`, by file name.
fn journals(dir: &Path) -> Result<Vec<PathBuf>, FiguresError> {
    let list = std::fs::read_dir(dir).map_err(|e| FiguresError::Read {
        file: dir.to_path_buf(),
        message: e.to_string(),
    })?;
    let mut out: Vec<PathBuf> = list
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "jsonl") && p.is_file())
        .collect();
    out.sort();
    Ok(out)
}

/// Instrument seconds of `taken`, grouped by model and mode: each group's mean reading
/// time at the lights read, with the calibrations its count needs.
fn instrument_s(taken: &[Taken]) -> f64 {
    let mut groups: BTreeMap<(String, &'static str), (f64, usize, TimeBudget)> = BTreeMap::new();
    for t in taken {
        // A model without stated times (a replayed transcript's) costs nothing.
        let Ok(b) = metamer_drivers::time_budget(&t.model, &TimeQuery::new(t.mode, t.luminance))
        else {
            continue;
        };
        let g = groups
            .entry((t.model.clone(), t.mode.name()))
            .or_insert((0.0, 0, b));
        g.0 += b.reading_s;
        g.1 += 1;
    }
    groups
        .values()
        .map(|(sum, n, first)| {
            TimeBudget {
                reading_s: sum / *n as f64,
                ..*first
            }
            .session_s(*n)
        })
        .sum()
}

impl LabFigures {
    /// The figures of the finished lab run in `dir`.
    pub fn read(dir: &Path) -> Result<LabFigures, FiguresError> {
        let lab_file = dir.join(LAB_FILE);
        let lab: LabFile =
            serde_json::from_str(&read_text(&lab_file)?).map_err(|e| FiguresError::Read {
                file: lab_file.clone(),
                message: e.to_string(),
            })?;
        let mut journals_read = Vec::new();
        let mut placements = BTreeMap::new();
        // Per stage, its readings.
        let mut taken: Vec<(&str, Vec<Taken>)> = Vec::new();
        for stage in measuring_stages() {
            let mut all = Vec::new();
            for j in journals(&dir.join(stage))? {
                let e = entries(&j)?;
                journals_read.push(JournalReadings {
                    stage: stage.to_string(),
                    journal: j
                        .file_name()
                        .map(|n| n.to_string_lossy().into_owned())
                        .unwrap_or_default(),
                    readings: e.len(),
                });
                all.extend(e);
            }
            let b = lab
                .budget
                .iter()
                .find(|b| b.stage == stage)
                .ok_or_else(|| FiguresError::NoStage {
                    file: lab_file.clone(),
                    stage: stage.to_string(),
                })?;
            let actual = b
                .cost
                .actual
                .as_ref()
                .ok_or_else(|| FiguresError::NotTaken {
                    file: lab_file.clone(),
                    stage: stage.to_string(),
                })?;
            placements.insert(stage.to_string(), actual.placements);
            taken.push((stage, all));
        }
        let all_placements: usize = placements.values().sum();
        let minutes = DISPLAY_METERS
            .iter()
            .map(|&meter| {
                let mut seconds = all_placements as f64 * PLACEMENT_S;
                for (stage, readings) in &mut taken {
                    if *stage != Stage::Box.name() {
                        for t in readings.iter_mut() {
                            t.model = meter.to_string();
                        }
                    }
                    seconds += instrument_s(readings);
                }
                (meter.to_string(), seconds / 60.0)
            })
            .collect();
        let comparisons = read_comparisons(&dir.join(Stage::Validation.name()))?;
        Ok(LabFigures {
            dir: dir.to_path_buf(),
            journals: journals_read,
            placements,
            minutes,
            comparisons,
            budget_total: lab.budget_total,
        })
    }

    /// Every reading of the measuring stages.
    pub fn readings(&self) -> usize {
        self.journals.iter().map(|j| j.readings).sum()
    }

    /// The readings of one stage (by its directory name), and of its journals whose name
    /// starts with `prefix` (`""` for all).
    pub fn stage_readings(&self, stage: &str, prefix: &str) -> usize {
        self.journals
            .iter()
            .filter(|j| j.stage == stage && j.journal.starts_with(prefix))
            .map(|j| j.readings)
            .sum()
    }

    pub fn box_placements(&self) -> usize {
        self.placements.get(Stage::Box.name()).copied().unwrap_or(0)
    }

    /// The minutes with the display read by `meter`.
    pub fn minutes_with(&self, meter: &str) -> Option<f64> {
        self.minutes
            .iter()
            .find(|(m, _)| m == meter)
            .map(|(_, v)| *v)
    }

    pub fn comparison(&self, name: &str) -> Option<&[PatchWidth]> {
        self.comparisons
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, p)| p.as_slice())
    }

    /// Whether `lab.json` states the budget before measuring and what was taken.
    pub fn states_cost(&self) -> bool {
        let t = &self.budget_total;
        t.estimate.readings > 0
            && t.estimate.wall_s > 0.0
            && t.actual
                .as_ref()
                .is_some_and(|a| a.readings > 0 && a.instrument_s > 0.0)
    }
}

fn read_comparisons(dir: &Path) -> Result<Vec<(String, Vec<PatchWidth>)>, FiguresError> {
    let file = dir.join(COMPARISONS_FILE);
    let mut all: BTreeMap<String, serde_json::Value> = serde_json::from_str(&read_text(&file)?)
        .map_err(|e| FiguresError::Read {
            file: file.clone(),
            message: e.to_string(),
        })?;
    COMPARISONS
        .iter()
        .map(|&name| {
            let value = all.remove(name).ok_or_else(|| FiguresError::NoComparison {
                file: file.clone(),
                name: name.to_string(),
            })?;
            let a: AssessmentPart =
                serde_json::from_value(value).map_err(|e| FiguresError::Read {
                    file: file.clone(),
                    message: format!("{name}: {e}"),
                })?;
            let patches = a
                .patches
                .into_iter()
                .map(|p| PatchWidth {
                    patch: p.patch,
                    jnd: p.jnd,
                    width: p.de76_interval.hi - p.de76_interval.lo,
                })
                .collect();
            Ok((name.to_string(), patches))
        })
        .collect()
}

/// How a patch's verdict under other plans stands to the fixed plan's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VerdictClass {
    /// The fixed plan's verdict.
    Same,
    /// Decided where the fixed plan left it undecided.
    Decided,
    /// Any other change: another decision, or undecided where the fixed plan decided.
    Changed,
}

impl VerdictClass {
    pub fn of(fixed: JndVerdict, other: JndVerdict) -> VerdictClass {
        if fixed == other {
            VerdictClass::Same
        } else if fixed == JndVerdict::Undecided {
            VerdictClass::Decided
        } else {
            VerdictClass::Changed
        }
    }
}

/// One comparison's verdicts, patch by patch, against the fixed plan's.
#[derive(Clone, Debug, PartialEq)]
pub struct ComparisonVerdicts {
    pub name: String,
    pub same: usize,
    pub decided: usize,
    /// The changed patches: (patch, fixed verdict, other verdict).
    pub changed: Vec<(usize, JndVerdict, JndVerdict)>,
    /// Patches in one run only.
    pub unmatched: usize,
}

/// The fixed run against another on the same seed.
#[derive(Clone, Debug, PartialEq)]
pub struct LabComparison {
    pub fixed: LabFigures,
    pub other: LabFigures,
    pub verdicts: Vec<ComparisonVerdicts>,
    /// The median display-vs-box ΔE*ab interval width, other over fixed.
    pub width_ratio: f64,
}

/// One bar of the done-when, its figure and whether it holds.
#[derive(Clone, Debug, PartialEq)]
pub struct BarCheck {
    pub bar: String,
    pub figure: String,
    pub holds: bool,
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The median width of a comparison's 95 % ΔE*ab intervals.
pub fn median_width(patches: &[PatchWidth]) -> f64 {
    median(patches.iter().map(|p| p.width).collect())
}

impl LabComparison {
    pub fn new(fixed: LabFigures, other: LabFigures) -> LabComparison {
        let verdicts = COMPARISONS
            .iter()
            .map(|&name| {
                let a = fixed.comparison(name).unwrap_or(&[]);
                let b = other.comparison(name).unwrap_or(&[]);
                let mut v = ComparisonVerdicts {
                    name: name.to_string(),
                    same: 0,
                    decided: 0,
                    changed: Vec::new(),
                    unmatched: 0,
                };
                for p in a {
                    match b.iter().find(|q| q.patch == p.patch) {
                        None => v.unmatched += 1,
                        Some(q) => match VerdictClass::of(p.jnd, q.jnd) {
                            VerdictClass::Same => v.same += 1,
                            VerdictClass::Decided => v.decided += 1,
                            VerdictClass::Changed => v.changed.push((p.patch, p.jnd, q.jnd)),
                        },
                    }
                }
                v.unmatched += b
                    .iter()
                    .filter(|q| !a.iter().any(|p| p.patch == q.patch))
                    .count();
                v
            })
            .collect();
        let width = |f: &LabFigures| median_width(f.comparison(COMPARISONS[0]).unwrap_or(&[]));
        let width_ratio = width(&other) / width(&fixed);
        LabComparison {
            fixed,
            other,
            verdicts,
            width_ratio,
        }
    }

    /// The bars of the done-when, in order: readings, box placements, minutes per display
    /// meter, verdicts, display-vs-box width, `lab.json`'s statement of the cost.
    pub fn bars(&self) -> Vec<BarCheck> {
        let (f, o) = (&self.fixed, &self.other);
        let mut out = Vec::new();
        let limit = READINGS_SHARE * f.readings() as f64;
        out.push(BarCheck {
            bar: format!("readings ≤ {:.0} % of fixed", 100.0 * READINGS_SHARE),
            figure: format!("{} of {} (bar {limit:.0})", o.readings(), f.readings()),
            holds: o.readings() as f64 <= limit,
        });
        out.push(BarCheck {
            bar: format!("box placements ≤ {MOST_BOX_PLACEMENTS}"),
            figure: format!("{} (fixed {})", o.box_placements(), f.box_placements()),
            holds: o.box_placements() <= MOST_BOX_PLACEMENTS,
        });
        for meter in DISPLAY_METERS {
            let (a, b) = (
                f.minutes_with(meter).unwrap_or(f64::NAN),
                o.minutes_with(meter).unwrap_or(f64::NAN),
            );
            out.push(BarCheck {
                bar: format!(
                    "minutes ≤ {:.0} % of fixed, display by {meter}",
                    100.0 * MINUTES_SHARE
                ),
                figure: format!("{b:.1} of {a:.1} ({:.0} %)", 100.0 * b / a),
                holds: b <= MINUTES_SHARE * a,
            });
        }
        for v in &self.verdicts {
            let changed: Vec<String> = v
                .changed
                .iter()
                .map(|(p, a, b)| format!("{p}: {} → {}", verdict_word(*a), verdict_word(*b)))
                .collect();
            out.push(BarCheck {
                bar: format!("{} verdicts as fixed or decided", v.name),
                figure: format!(
                    "same {}, decided {}, changed {}{}",
                    v.same,
                    v.decided,
                    v.changed.len(),
                    if changed.is_empty() {
                        String::new()
                    } else {
                        format!(" ({})", changed.join(", "))
                    }
                ),
                holds: v.changed.is_empty() && v.unmatched == 0,
            });
        }
        out.push(BarCheck {
            bar: format!("display-vs-box median width ≤ {WIDTH_RATIO} × fixed"),
            figure: format!("{:.2}", self.width_ratio),
            holds: self.width_ratio <= WIDTH_RATIO,
        });
        out.push(BarCheck {
            bar: "lab.json states the estimate and the time taken".into(),
            figure: match &o.budget_total.actual {
                Some(a) => format!(
                    "estimate {:.1} min, instrument taken {:.1} min",
                    o.budget_total.estimate.wall_s / 60.0,
                    a.instrument_s / 60.0
                ),
                None => "nothing taken".into(),
            },
            holds: o.states_cost(),
        });
        out
    }
}

/// A verdict in the report's words.
pub fn verdict_word(v: JndVerdict) -> &'static str {
    match v {
        JndVerdict::Below => "below",
        JndVerdict::Above => "above",
        JndVerdict::Undecided => "undecided",
    }
}
