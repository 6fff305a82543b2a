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
    /// Asks the operator for one placement outside a plan's steps (aiming at a screen
    /// before a stage whose steps need none): what it took, or None when the operator
    /// aborts.
    pub fn ask_placement(
        operator: &mut dyn super::Operator,
        prompt: &str,
    ) -> Result<Option<Cost>, super::OperatorError> {
        let asked = std::time::Instant::now();
        if operator.ask(prompt)? == super::Answer::Abort {
            return Ok(None);
        }
        let operator_s = asked.elapsed().as_secs_f64();
        Ok(Some(Cost {
            placements: 1,
            operator_s,
            wall_s: operator_s,
            ..Cost::default()
        }))
    }

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

    /// The counts for people: `554 readings in 92 placements, 2 calibrations`.
    pub fn counts(&self) -> String {
        let calibrations = match self.calibrations {
            1 => "1 calibration".to_string(),
            n => format!("{n} calibrations"),
        };
        format!(
            "{} readings in {} placements, {calibrations}",
            self.readings, self.placements
        )
    }

    /// What is said before the first reading of `what` (a stage, a command): `budget of
    /// the box's tiles stage: 125 readings in 25 placements, 1 calibration; about 16.8 min:
    /// instrument 4.3 min, operator 12.5 min, settle 0 s (assumed: …)`.
    pub fn before(&self, what: &str) -> String {
        let mut s = format!(
            "budget of {what}: {}; about {}: instrument {}, operator {}, settle {}",
            self.counts(),
            duration(self.wall_s),
            duration(self.instrument_s),
            duration(self.operator_s),
            duration(self.settle_s),
        );
        if !self.assumptions.is_empty() {
            s.push_str(&format!(" (assumed: {})", self.assumptions.join("; ")));
        }
        s
    }

    /// What is said when `what` has ended, against the `estimate` it was budgeted at:
    /// `cost of …: 125 readings in 25 placements, 1 calibration; instrument 4.7 min
    /// (budget 4.3 min), wall 0.2 s (budget 16.8 min)`.
    pub fn after(&self, what: &str, estimate: &Cost) -> String {
        format!(
            "cost of {what}: {}; instrument {} (budget {}), wall {} (budget {})",
            self.counts(),
            duration(self.instrument_s),
            duration(estimate.instrument_s),
            duration(self.wall_s),
            duration(estimate.wall_s),
        )
    }
}

/// Seconds for people: `0.2 s`, `17 s`, `4.3 min`, `2.5 h`.
pub fn duration(s: f64) -> String {
    if s < 10.0 {
        format!("{s:.1} s")
    } else if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
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

#[cfg(test)]
mod tests {
    use std::sync::Arc;
    use std::time::Duration;

    use metamer_drivers::{SharedWorld, View, World};

    use super::*;
    use crate::session::{Answer, Operator, OperatorError, RunOptions, Session};

    /// Puts the simulated i1Pro on its white tile to calibrate, and in front of 100 cd/m²
    /// of LED light to read.
    struct Placing(Arc<SharedWorld>);

    impl Operator for Placing {
        fn ask(&mut self, prompt: &str) -> Result<Answer, OperatorError> {
            if prompt.contains("calibration") {
                self.0.set(View::WhiteTile);
            } else {
                let light = metamer_drivers::i1pro::emulator::default_light();
                self.0.set(View::radiance(light).unwrap());
            }
            Ok(Answer::Confirmed)
        }
    }

    fn step(role: &str, mode: MeasureMode, prepare: Prepare, settle_ms: u64) -> Step<u32> {
        Step {
            label: String::new(),
            role: role.into(),
            mode,
            prepare,
            settle: Duration::from_millis(settle_ms),
            data: 0,
        }
    }

    fn ask(p: &str) -> Prepare {
        Prepare::Operator { prompt: p.into() }
    }

    /// A spot meter placed twice (three readings, then two) and a spectral instrument
    /// reading two colours shown on a screen, 0.5 s settle each.
    fn small_plan() -> SessionPlan<u32> {
        use MeasureMode::Emissive;
        let show = |v| Prepare::Show { rgb: [v; 3] };
        SessionPlan {
            kind: "test".into(),
            options: BTreeMap::new(),
            steps: vec![
                step("spot", Emissive, ask("a"), 0),
                step("spot", Emissive, ask("a"), 0),
                step("spot", Emissive, Prepare::None, 0),
                step("spot", Emissive, ask("b"), 0),
                step("spot", Emissive, Prepare::None, 0),
                step("spectral", Emissive, show(255), 500),
                step("spectral", Emissive, show(128), 500),
            ],
        }
    }

    fn meters() -> BTreeMap<String, Meter> {
        [
            ("spot".to_string(), Meter::of_spec(&Spec::new("sim:cs100a"))),
            (
                "spectral".to_string(),
                Meter::of_spec(&Spec::new("sim:i1pro?rev=d&time_scale=0")),
            ),
        ]
        .into()
    }

    /// By hand from the drivers' stated facts: a CS-100A reading is its FAST 0.1 s plus
    /// the 5-character command and 28-character reply at 11 bits a character, 4800 baud
    /// (0.175625 s); an i1Pro Rev D reading of 100 cd/m² is the 0.1 s trial and an
    /// integration of 37 000 / (45 000 / (2 s · 110 cd/m²) · 100 cd/m²) = 1.80889 s, and its
    /// emissive dark 212 readings of 4.716 ms and nine of 2 s (18.99979 s), valid 30 min.
    #[test]
    fn the_budget_of_a_small_plan_is_the_hand_count() {
        let plan = small_plan();
        let cs100a = 0.1 + 33.0 * 11.0 / 4800.0;
        let i1pro = 0.1 + 37_000.0 * 220.0 / 4_500_000.0;
        let dark = 212.0 * 4.716e-3 + 18.0;
        let light = |_: &Step<u32>| 100.0;
        let all = estimate(&plan, &|_| false, &meters(), &light, "100 cd/m²", 20.0);
        assert_eq!((all.readings, all.placements, all.calibrations), (7, 2, 1));
        let instrument = 5.0 * cs100a + 2.0 * i1pro + dark;
        // The wire time is whole nanoseconds a character, as the driver states it.
        assert!((all.instrument_s - instrument).abs() < 1e-6, "{all:?}");
        assert_eq!((all.operator_s, all.settle_s), (40.0, 1.0));
        assert!((all.wall_s - (instrument + 41.0)).abs() < 1e-6);
        assert_eq!(all.assumptions, vec!["100 cd/m²", "20 s per placement"]);

        // Resumed after the first placement and one colour: what is left.
        let left = estimate(&plan, &|i| i < 3 || i == 5, &meters(), &light, "", 20.0);
        assert_eq!(
            (left.readings, left.placements, left.calibrations),
            (3, 1, 1)
        );
        assert!((left.instrument_s - (2.0 * cs100a + i1pro + dark)).abs() < 1e-6);
        assert_eq!((left.operator_s, left.settle_s), (20.0, 0.5));

        // A model that states no time counts at 0 s and says so.
        let mut unknown = meters();
        unknown.insert("spot".into(), Meter::of_spec(&Spec::new("replay:x.jsonl")));
        let u = estimate(&plan, &|_| false, &unknown, &light, "", 20.0);
        assert!((u.instrument_s - (2.0 * i1pro + dark)).abs() < 1e-6);
        assert!(
            u.assumptions[0].contains("not known before it opens"),
            "{u:?}"
        );
    }

    #[test]
    fn a_placement_time_is_seconds_from_zero_to_a_day() {
        assert_eq!(placement_s(" 12.5 "), Ok(12.5));
        assert_eq!(placement_s("0"), Ok(0.0));
        for bad in ["-1", "nan", "inf", "86401", "half a minute", ""] {
            assert!(placement_s(bad).is_err(), "{bad}");
        }
    }

    /// The small plan's spot readings on the simulated CS-100A at its real pace, and its
    /// i1Pro readings at no pace (its own clock counts the real unit's time), placed once:
    /// its dark calibration and two readings of 100 cd/m². The budget within a fifth of what the session took, by the instruments'
    /// clocks and, for the paced meter, by the wall clock.
    #[test]
    fn the_budget_comes_within_a_fifth_of_a_simulated_session_at_real_pace() {
        let mut plan = small_plan();
        for s in &mut plan.steps {
            if matches!(s.prepare, Prepare::Show { .. }) {
                s.prepare = ask("c");
            }
            s.settle = Duration::ZERO;
        }
        let dir = std::env::temp_dir().join(format!("metamer-budget-{}", std::process::id()));
        let journal = dir.join("journal.jsonl");
        let _ = std::fs::remove_file(&journal);
        let mut spot = Spec::new("sim:cs100a?time_scale=1").open(None).unwrap();
        let world = Arc::new(SharedWorld::new(View::WhiteTile));
        let mut spectral = Spec::new("sim:i1pro?time_scale=0")
            .open(Some(world.clone() as Arc<dyn World>))
            .unwrap();
        let light = |_: &Step<u32>| 100.0;
        let mut session: Session<(), u32> =
            Session::open(&journal, plan, (), BTreeMap::new(), false).unwrap();
        let mut operator = Placing(world);
        let mut rig = crate::session::Rig {
            screen: None,
            instruments: vec![
                ("spot".to_string(), spot.as_mut()),
                ("spectral".to_string(), spectral.as_mut()),
            ],
            operator: &mut operator,
        };
        let budget = session.estimate(&meters_of(&rig.instruments), &light, "", 0.0);
        session
            .run(
                &mut rig,
                &RunOptions::default(),
                &mut crate::session::NoProgress,
            )
            .unwrap();
        let spent = session.spent();
        eprintln!("budget {budget:?}\nspent {spent:?}");
        assert_eq!(
            (spent.readings, spent.placements, spent.calibrations),
            (budget.readings, budget.placements, budget.calibrations)
        );
        let near = |a: f64, b: f64| (a / b - 1.0).abs() < 0.2;
        assert!(
            near(budget.instrument_s, spent.instrument_s),
            "{budget:?} {spent:?}"
        );
        // The paced meter's five readings by the wall clock: the session's whole run, the
        // unpaced i1Pro's next to nothing.
        let paced = 5.0 * (0.1 + 33.0 * 11.0 / 4800.0);
        assert!(near(paced, spent.wall_s), "{paced} s budgeted, {spent:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
