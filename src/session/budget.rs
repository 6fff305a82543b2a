//! What a session costs: before the first reading, the readings, placements and time a
//! plan's steps still to take will need ([`estimate`]), and after, what they took
//! ([`super::Session::spent`]), in one type, [`Cost`].
//!
//! The instrument's time comes from each model's own protocol facts through the driver
//! registry ([`metamer_drivers::time_budget`]: integration by light, dark references,
//! calibrations and their lifetimes, wire time); the light of each reading from what the
//! caller's plan knows (a patch's drive level on a known display, the box's light); the
//! operator's time as a stated time per placement ([`PLACEMENT_S`], or the caller's); the
//! rig's as the steps' settle waits.

use std::collections::BTreeMap;

use metamer_drivers::spec::SpecForm;
use metamer_drivers::{Instrument, MeasureMode, Spec, TimeBudget, TimeQuery};
use serde::{Deserialize, Serialize};

use super::plan::{placements, Prepare, SessionPlan, Step};

/// The operator's time per placement when the caller gives none: a person's half minute
/// to read the request, put the instrument on the next target, aim it and confirm. It is
/// a round figure for planning, not a measured one; a rig's own pace is set per command.
pub const PLACEMENT_S: f64 = 30.0;

/// The longest placement time a caller may state: a day.
pub const MAX_PLACEMENT_S: f64 = 86_400.0;

/// A placement time out of range: not a finite number of seconds in 0 ..= a day.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("placement time {0}: expected seconds from 0 to {MAX_PLACEMENT_S} (a day)")]
pub struct PlacementTimeError(pub String);

/// Checks a placement time given as text (a command's option).
pub fn placement_s(text: &str) -> Result<f64, PlacementTimeError> {
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|s| s.is_finite() && (0.0..=MAX_PLACEMENT_S).contains(s))
        .ok_or_else(|| PlacementTimeError(text.to_string()))
}

/// Readings, placements and time of a measurement: an estimate before it, or what it took.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Cost {
    /// Readings journalled (steps taken).
    pub readings: usize,
    /// Times the operator places or aims an instrument for the plan's steps.
    pub placements: usize,
    /// Calibrations the instruments need (dark, white tile).
    pub calibrations: usize,
    /// The instruments' own time: readings and calibrations, at the real pace.
    pub instrument_s: f64,
    /// The operator's: the placements (estimated at the time per placement; measured as
    /// the time the requests waited for an answer).
    pub operator_s: f64,
    /// The rig's waits between showing a colour and reading it.
    pub settle_s: f64,
    /// Everything: the sum of the above for an estimate; the clock's for what was taken.
    pub wall_s: f64,
    /// What the estimate assumed (the light of each reading, the placement time, a model
    /// with no stated time); empty for what was taken.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub assumptions: Vec<String>,
}

impl Cost {
    /// The sum of two costs (an experiment's of its stages').
    pub fn add(&mut self, other: &Cost) {
        self.readings += other.readings;
        self.placements += other.placements;
        self.calibrations += other.calibrations;
        self.instrument_s += other.instrument_s;
        self.operator_s += other.operator_s;
        self.settle_s += other.settle_s;
        self.wall_s += other.wall_s;
        for a in &other.assumptions {
            if !self.assumptions.contains(a) {
                self.assumptions.push(a.clone());
            }
        }
    }

    /// One line for people: `554 readings in 92 placements, 2 calibrations: about 62.4
    /// min (instrument 8.3 min, operator 46.0 min, settle 8.1 min)`; `about` is said of an
    /// estimate.
    pub fn summary(&self, about: &str) -> String {
        format!(
            "{} readings in {} placements, {} calibrations: {about}{:.1} min (instrument {:.1} min, operator {:.1} min, settle {:.1} min)",
            self.readings,
            self.placements,
            self.calibrations,
            self.wall_s / 60.0,
            self.instrument_s / 60.0,
            self.operator_s / 60.0,
            self.settle_s / 60.0,
        )
    }

    /// What is said before the first reading of `what` (a stage, a command).
    pub fn before(&self, what: &str) -> String {
        let mut s = format!("budget of {what}: {}", self.summary("about "));
        if !self.assumptions.is_empty() {
            s.push_str(&format!("; assumed: {}", self.assumptions.join("; ")));
        }
        s
    }

    /// What is said when `what` has ended, with the estimate it was made with.
    pub fn after(&self, what: &str, estimate: &Cost) -> String {
        format!(
            "cost of {what}: {} (estimated {:.1} min, instrument {:.1} min)",
            self.summary(""),
            estimate.wall_s / 60.0,
            estimate.instrument_s / 60.0,
        )
    }
}

/// A stage's or command's estimate and, once it has run, what it took.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CostReport {
    /// Before the first reading, for the steps still to take.
    pub estimate: Cost,
    /// What this run took; None before it ran (or where it was re-used).
    pub actual: Option<Cost>,
}

/// An instrument as the budget asks about it: its model and the options that change its
/// time (`speed`, `rev`, `integration_s`).
#[derive(Clone, Debug, PartialEq)]
pub struct Meter {
    /// The registry's model name; None where it is not known before opening (a replayed
    /// transcript).
    pub model: Option<String>,
    pub options: Vec<(String, String)>,
}

/// A simulation's own settings among the option values (`sim_seed`) that do not change a
/// reading's time; `sim_rev` does and is asked for as `rev`.
const SIM_PREFIX: &str = metamer_drivers::simulated::SIM_OPTION_PREFIX;

impl Meter {
    /// An opened instrument.
    pub fn of(instrument: &dyn Instrument) -> Meter {
        let options = instrument
            .option_values()
            .into_iter()
            .map(|(k, v)| match k.strip_prefix(SIM_PREFIX) {
                Some(own) => (own.to_string(), v),
                None => (k, v),
            })
            .collect();
        Meter {
            model: Some(instrument.info().model),
            options,
        }
    }

    /// An instrument named by `spec`, before it is opened.
    pub fn of_spec(spec: &Spec) -> Meter {
        match spec.kind() {
            SpecForm::Simulated { model, options } => Meter {
                model: Some(model.clone()),
                options: options
                    .split('&')
                    .filter_map(|o| o.split_once('='))
                    .map(|(k, v)| (k.to_string(), v.to_string()))
                    .collect(),
            },
            SpecForm::Device { prefix, .. } => Meter {
                model: Some(prefix.clone()),
                options: Vec::new(),
            },
            SpecForm::Replay { .. } => Meter {
                model: None,
                options: Vec::new(),
            },
        }
    }
}

/// The cost of the steps of `plan` not yet taken (`taken(i)` true for a journalled step):
/// `meters` are the rig's instruments by role, `light(step)` the luminance (cd/m²;
/// illuminance in lx for an ambient reading) the step is expected to read, with
/// `light_assumption` saying where it comes from, and `placement_s` the operator's time
/// per placement.
///
/// Readings are the steps; placements the operator's requests, one per run of steps that
/// share it ([`placements`]); calibrations those each instrument and mode needs, one
/// before the first reading and one each time the last expires
/// ([`TimeBudget::session_s`]). A model with no stated time, or a light it cannot read,
/// counts its readings at 0 s and says so among the assumptions: a budget never stops a
/// measurement.
pub fn estimate<D>(
    plan: &SessionPlan<D>,
    taken: &dyn Fn(usize) -> bool,
    meters: &BTreeMap<String, Meter>,
    light: &dyn Fn(&Step<D>) -> f64,
    light_assumption: &str,
    placement_s: f64,
) -> Cost {
    let mut cost = Cost::default();
    let mut assumptions: Vec<String> = Vec::new();
    let mut note = |a: String| {
        if !assumptions.contains(&a) {
            assumptions.push(a);
        }
    };
    let steps = &plan.steps;
    let mut placements_left = std::collections::BTreeSet::new();
    // Per instrument and mode: the readings' seconds, their count, and the calibration.
    let mut groups: BTreeMap<(String, &'static str), (f64, usize, TimeBudget)> = BTreeMap::new();
    let mut any_read = false;
    for (i, (step, placement)) in steps.iter().zip(placements(steps)).enumerate() {
        if taken(i) {
            continue;
        }
        cost.readings += 1;
        cost.settle_s += step.settle.as_secs_f64();
        match (&step.prepare, placement) {
            (_, Some(range)) => {
                placements_left.insert(range.start);
            }
            (Prepare::Operator { .. }, None) => {
                placements_left.insert(i);
            }
            _ => {}
        }
        if matches!(step.prepare, Prepare::Show { .. }) || step.mode != MeasureMode::Reflective {
            any_read = true;
        }
        let Some(budget) = step_budget(step, meters, light, &mut note) else {
            continue;
        };
        let g = groups
            .entry((step.role.clone(), step.mode.name()))
            .or_insert((0.0, 0, budget));
        g.0 += budget.reading_s;
        g.1 += 1;
    }
    if any_read && !light_assumption.is_empty() {
        note(light_assumption.to_string());
    }
    for (reading_s, n, first) in groups.values() {
        let mean = TimeBudget {
            reading_s: reading_s / *n as f64,
            ..*first
        };
        let total = mean.session_s(*n);
        cost.instrument_s += total;
        if first.calibration_s > 0.0 {
            cost.calibrations += ((total - reading_s) / first.calibration_s).round() as usize;
        }
    }
    cost.placements = placements_left.len();
    cost.operator_s = cost.placements as f64 * placement_s;
    if cost.placements > 0 {
        note(format!("{placement_s} s per placement"));
    }
    cost.wall_s = cost.instrument_s + cost.operator_s + cost.settle_s;
    cost.assumptions = assumptions;
    cost
}

/// The time of one step's reading as its instrument's model states it, or None (said in
/// `note`) where it states none.
fn step_budget<D>(
    step: &Step<D>,
    meters: &BTreeMap<String, Meter>,
    light: &dyn Fn(&Step<D>) -> f64,
    note: &mut dyn FnMut(String),
) -> Option<TimeBudget> {
    let meter = meters.get(&step.role);
    let Some(model) = meter.and_then(|m| m.model.as_deref()) else {
        note(format!(
            "the {} instrument's model is not known before it opens: its readings counted at 0 s",
            step.role
        ));
        return None;
    };
    let query = TimeQuery {
        mode: step.mode,
        luminance_cd_m2: light(step).max(0.0),
        options: meter.map(|m| m.options.clone()).unwrap_or_default(),
    };
    match metamer_drivers::time_budget(model, &query) {
        Ok(b) => Some(b),
        Err(e) => {
            note(format!("{model}: {e}; its readings counted at 0 s"));
            None
        }
    }
}

/// The meters of a rig's instruments by role, as [`estimate`] takes them.
pub fn meters_of(instruments: &[(String, &mut dyn Instrument)]) -> BTreeMap<String, Meter> {
    instruments
        .iter()
        .map(|(role, i)| (role.clone(), Meter::of(&**i)))
        .collect()
}

/// The luminance of the drive values `rgb` on a display of white `white_cd_m2` that
/// follows sRGB (IEC 61966-2-1: its transfer function and the Rec. 709 primaries'
/// luminance weights 0.2126, 0.7152, 0.0722; no black level, as the standard's reference
/// display has none). For a real screen, whose response is not known before it is
/// measured.
pub fn srgb_luminance(rgb: [u8; 3], white_cd_m2: f64) -> f64 {
    let linear = |v: u8| {
        let c = f64::from(v) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    white_cd_m2 * (0.2126 * linear(rgb[0]) + 0.7152 * linear(rgb[1]) + 0.0722 * linear(rgb[2]))
}

/// The white of the sRGB standard's reference display (IEC 61966-2-1), cd/m²: the light
/// a real screen is budgeted at before it is measured.
pub const SRGB_WHITE_CD_M2: f64 = 80.0;

/// What an sRGB display of white `white_cd_m2` assumes, said once per budget.
pub fn srgb_assumption(white_cd_m2: f64) -> String {
    format!(
        "a patch's luminance from its drive values on an sRGB display of white {white_cd_m2} cd/m²"
    )
}
