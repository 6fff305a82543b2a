//! What a model can do, as `metamer devices --describe MODEL` tells it: how it is named,
//! where it shows on USB, its modes with their calibrations and lifetimes and its options
//! (asked of its driver on simulated units, so they are the driver's own answer), and its
//! stated repeatability from the registry — or why metamer does not drive it.

use serde::Serialize;

use crate::budget::TimeQuery;
use crate::instrument::Capabilities;
use crate::mode::MeasureMode;
use crate::registry::{self, ModelEntry};
use crate::spec::{self, words, Spec};
use crate::DriverError;

/// Everything metamer knows about one model.
#[derive(Clone, Debug, Serialize)]
pub struct ModelDescription {
    /// Its stable name (`i1pro`).
    pub name: &'static str,
    pub title: &'static str,
    /// How a spec names it on real hardware (`i1pro[:SERIAL]`), where metamer drives it.
    pub real: Option<String>,
    /// Its simulation's spec and the options beyond `time_scale`, `seed` and `noise`.
    pub simulated: Option<String>,
    pub sim_options: &'static [&'static str],
    /// Whether its transcripts replay (`replay:FILE.jsonl`).
    pub replay: bool,
    /// Its USB IDs (`0971:2000 usb`).
    pub usb: Vec<String>,
    /// Other words for it and how to name it instead.
    pub other_names: Vec<String>,
    /// Why metamer does not drive it.
    pub unsupported: Option<&'static str>,
    /// What its driver says it can do, on each simulated unit that stands for it.
    pub units: Vec<Unit>,
    /// Its stated repeatability per mode.
    pub repeatability: Vec<Figure>,
    /// Whether its driver states how long its readings and calibrations take
    /// ([`crate::time_budget`]; each unit's [`Unit::times`]).
    pub time_budget_stated: bool,
}

/// A simulated unit's capabilities, standing for a kind of real unit.
#[derive(Clone, Debug, Serialize)]
pub struct Unit {
    /// What kind of unit it stands for (`i1Pro 2 (Rev E) with the diffuser`).
    pub stands_for: &'static str,
    /// The spec it was opened with.
    pub spec: String,
    pub capabilities: Capabilities,
    /// How long its readings and calibrations take in each of its modes, from its time
    /// budget; empty where the model states none.
    pub times: Vec<ModeTime>,
}

/// The light a described reading time is of: a display's white of 100 cd/m² (100 lx in
/// ambient mode; reflective readings do not depend on it).
pub const DESCRIBED_CD_M2: f64 = 100.0;

/// A mode's instrument time ([`crate::budget::TimeBudget`]) on a unit.
#[derive(Clone, Debug, Serialize)]
pub struct ModeTime {
    pub mode: MeasureMode,
    /// One reading of [`DESCRIBED_CD_M2`], seconds.
    pub reading_s: f64,
    /// The calibration the mode needs first, seconds (0: none).
    pub calibration_s: f64,
}

/// A stated repeatability in one mode, in words (2σ) and with its source.
#[derive(Clone, Debug, Serialize)]
pub struct Figure {
    pub mode: MeasureMode,
    pub stated: String,
    pub source: &'static str,
}

/// Describes the model `name` names: its stable name (`i1pro`), another word for it
/// (`i1pro2`) or a spec naming it (`sim:cs100a`).
///
/// # Examples
///
/// ```
/// let d = metamer_drivers::describe::describe("cs100a")?;
/// assert_eq!(d.title, "Konica Minolta CS-100A");
/// assert_eq!(d.units[0].capabilities.modes[0].mode.name(), "emissive");
/// # Ok::<(), metamer_drivers::DriverError>(())
/// ```
pub fn describe(name: &str) -> Result<ModelDescription, DriverError> {
    let model = spec::model_named(name).ok_or_else(|| DriverError::UnknownModel {
        name: name.to_string(),
        known: registry::MODELS
            .iter()
            .map(|m| m.name)
            .collect::<Vec<_>>()
            .join(", "),
    })?;
    Ok(ModelDescription {
        name: model.name,
        title: model.title,
        real: model.real_spec(),
        simulated: model.sim.map(|_| words::sim_connection(model.name)),
        sim_options: model.sim_options,
        replay: model.replay.is_some(),
        usb: model
            .usb
            .iter()
            .map(|id| format!("{:04x}:{:04x} {}", id.vid, id.pid, id.bus.name()))
            .collect(),
        other_names: model
            .other_names
            .iter()
            .map(|o| format!("{}: {}", o.word, model.named_instead(o)))
            .collect(),
        unsupported: model.unsupported,
        units: units(model)?,
        repeatability: model
            .repeatability
            .iter()
            .map(|(mode, r)| Figure {
                mode: *mode,
                stated: r.describe(),
                source: r.source,
            })
            .collect(),
        time_budget_stated: model.time_budget.is_some(),
    })
}

/// The capabilities its driver reports on each simulated unit its row names, opened
/// instantly and without noise.
fn units(model: &ModelEntry) -> Result<Vec<Unit>, DriverError> {
    if model.sim.is_none() {
        return Ok(Vec::new());
    }
    model
        .described_by
        .iter()
        .map(|(stands_for, options)| {
            let mut spec = Spec::simulated(model.name)
                .with_option("time_scale", 0)
                .with_option("noise", "off");
            for (key, value) in option_pairs(options) {
                spec = spec.with_option(key, value);
            }
            let capabilities = spec.open(None)?.capabilities();
            let times = match model.time_budget {
                None => Vec::new(),
                Some(budget) => capabilities
                    .modes
                    .iter()
                    .map(|m| {
                        let mut query = TimeQuery::new(m.mode, DESCRIBED_CD_M2);
                        query.options = option_pairs(options)
                            .map(|(k, v)| (k.to_string(), v.to_string()))
                            .collect();
                        budget(&query).map(|b| ModeTime {
                            mode: m.mode,
                            reading_s: b.reading_s,
                            calibration_s: b.calibration_s,
                        })
                    })
                    .collect::<Result<_, _>>()?,
            };
            Ok(Unit {
                stands_for,
                spec: spec.as_str().to_string(),
                capabilities,
                times,
            })
        })
        .collect()
}

/// The `key=value` pairs of a row's simulation options (`rev=e&diffuser=on`).
fn option_pairs(options: &str) -> impl Iterator<Item = (&str, &str)> {
    options
        .split('&')
        .filter(|o| !o.is_empty())
        .map(|o| o.split_once('=').unwrap_or((o, "")))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every mode a row lists is one its simulated units offer, and the other way round;
    /// every stated figure is for a mode it has.
    #[test]
    fn a_rows_modes_are_its_drivers() {
        for m in registry::MODELS.iter().filter(|m| m.sim.is_some()) {
            let d = describe(m.name).unwrap();
            assert!(!d.units.is_empty(), "{}", m.name);
            let mut offered: Vec<MeasureMode> = d
                .units
                .iter()
                .flat_map(|u| u.capabilities.modes.iter().map(|i| i.mode))
                .collect();
            offered.sort_by_key(|m| m.name());
            offered.dedup();
            let mut listed = m.modes.to_vec();
            listed.sort_by_key(|m| m.name());
            assert_eq!(offered, listed, "{}", m.name);
            for (mode, _) in m.repeatability {
                assert!(m.modes.contains(mode), "{} {mode}", m.name);
            }
        }
    }

    #[test]
    fn the_i1pro_2_is_described_as_the_i1pro_and_an_unknown_model_is_refused() {
        let d = describe("i1pro2").unwrap();
        assert_eq!(d.name, "i1pro");
        // The i1Pro 2's dark lasts 1 h, the older units' 30 min (protocols/i1pro/README.md).
        let dark = |u: &Unit| u.capabilities.modes[0].calibrations[0].valid_for_s.unwrap();
        assert_eq!(dark(&d.units[0]), 1800.0);
        assert_eq!(dark(&d.units[1]), 3600.0);
        // Its time budget on each unit, by hand from the facts (i1pro/budget.rs): the
        // emissive dark is 212 readings of 4.716 ms (Rev A–D) or 204 of 4.896 ms (Rev E)
        // and nine of 2 s; 100 cd/m² integrates 37 000 / (45 000 / 220 · 100) = 1.8089 s
        // after the 0.1 s trial; a reflective reading is the lamp's 0.2 s and 8 × 0.02 s.
        let emissive = |u: &Unit| {
            let t = u.times.iter().find(|t| t.mode == MeasureMode::Emissive);
            t.map(|t| (t.reading_s, t.calibration_s)).unwrap()
        };
        let reading = 0.1 + 37_000.0 * 220.0 / 4_500_000.0;
        for (unit, dark) in [(0, 212.0 * 4.716e-3), (1, 204.0 * 4.896e-3)] {
            let (r, c) = emissive(&d.units[unit]);
            assert!((r - reading).abs() < 1e-9, "{r}");
            assert!((c - (dark + 18.0)).abs() < 1e-9, "{c}");
            let times = &d.units[unit].times;
            let lit = times.iter().find(|t| t.mode == MeasureMode::Reflective);
            let lit = lit.unwrap();
            assert!((lit.reading_s - 0.36).abs() < 1e-12);
        }
        // The CS-100A at FAST: 0.1 s and 33 characters × 11 bits at 4800 baud.
        let cs = describe("cs100a").unwrap();
        assert_eq!(cs.units[0].times.len(), 1);
        let fast = cs.units[0].times[0].reading_s;
        // The character time is a whole number of nanoseconds.
        assert!((fast - 0.175_625).abs() < 1e-6, "{fast}");
        assert_eq!(cs.units[0].times[0].calibration_s, 0.0);
        let d = describe("i1pro3").unwrap();
        assert!(d.units.is_empty() && d.unsupported.is_some());
        let e = describe("spectro").unwrap_err().to_string();
        assert_eq!(
            e,
            "no instrument model is named 'spectro' (known: cs100a, i1pro, i1pro3, colormunki, i1d3)"
        );
    }
}
