//! What a model can do, as `metamer devices --describe MODEL` tells it: how it is named,
//! where it shows on USB, its modes with their calibrations and lifetimes and its options
//! (asked of its driver on simulated units, so they are the driver's own answer), and its
//! stated repeatability from the registry — or why metamer does not drive it.

use serde::Serialize;

use crate::instrument::Capabilities;
use crate::mode::MeasureMode;
use crate::registry::{self, Model};
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
    /// ([`crate::time_budget`]).
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
fn units(model: &Model) -> Result<Vec<Unit>, DriverError> {
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
            for option in options.split('&').filter(|o| !o.is_empty()) {
                let (key, value) = option.split_once('=').unwrap_or((option, ""));
                spec = spec.with_option(key, value);
            }
            let capabilities = spec.open(None)?.capabilities();
            Ok(Unit {
                stands_for,
                spec: spec.as_str().to_string(),
                capabilities,
            })
        })
        .collect()
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
        let d = describe("i1pro3").unwrap();
        assert!(d.units.is_empty() && d.unsupported.is_some());
        let e = describe("spectro").unwrap_err().to_string();
        assert_eq!(
            e,
            "no instrument model is named 'spectro' (known: cs100a, i1pro, i1pro3, colormunki, i1d3)"
        );
    }
}
