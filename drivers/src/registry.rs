//! The driver registry: every instrument model metamer knows, with the USB IDs it shows on
//! the bus, the spec prefixes that name it, and how to open it on a real link, on a replayed
//! transcript and as a simulation. Spec parsing, `metamer devices` and error messages read
//! this one table, so adding a driver is its module plus one row here.

use serde::Serialize;

use crate::instrument::Instrument;
use crate::link::replay::Transcript;
use crate::open::{OpenOptions, SimSettings};
use crate::DriverError;

/// How a USB instrument is talked to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Bus {
    /// Raw USB transfers (libusb).
    Usb,
    /// A HID class device (hidraw).
    Hid,
}

impl Bus {
    pub fn name(self) -> &'static str {
        match self {
            Bus::Usb => "usb",
            Bus::Hid => "hid",
        }
    }
}

/// A USB vendor/product ID pair a model shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UsbId {
    pub vid: u16,
    pub pid: u16,
    pub bus: Bus,
}

/// Opens a model on the real link `address` names (a serial port, a USB serial number).
pub type OpenReal = fn(&str, &OpenOptions) -> Result<Box<dyn Instrument>, DriverError>;
/// Runs the model's driver against a recorded transcript.
pub type OpenReplay = fn(Transcript, &OpenOptions) -> Result<Box<dyn Instrument>, DriverError>;
/// Starts the model's emulator behind its real driver.
pub type OpenSim = fn(&SimSettings, &OpenOptions) -> Result<Box<dyn Instrument>, DriverError>;

/// Opening a model on real hardware.
#[derive(Clone, Copy)]
pub struct Real {
    /// What follows `PREFIX:` in a spec, as the user is told (`PORT`).
    pub address: &'static str,
    /// False where the model can be found without it (the only one of its kind on USB), so
    /// `PREFIX` alone opens it.
    pub address_required: bool,
    pub open: OpenReal,
}

/// One instrument model.
#[derive(Clone, Copy)]
pub struct Model {
    /// Short stable name used in readings, transcripts and `sim:NAME` (`cs100a`).
    pub name: &'static str,
    /// What people call it (`Konica Minolta CS-100A`).
    pub title: &'static str,
    /// The IDs it has on USB; none for instruments on a serial cable.
    pub usb: &'static [UsbId],
    /// Spec prefixes that open it on real hardware (`cs100a` in `cs100a:/dev/ttyUSB0`); the
    /// first is the one messages show.
    pub spec_prefixes: &'static [&'static str],
    /// None while metamer has no driver for it (it is still recognised on the bus).
    pub real: Option<Real>,
    pub replay: Option<OpenReplay>,
    pub sim: Option<OpenSim>,
    /// Options of its simulation beyond `time_scale`, `seed` and `noise`.
    pub sim_options: &'static [&'static str],
    /// How long its readings and calibrations take, from its protocol facts
    /// ([`crate::budget`]); None while metamer has no driver for it.
    pub time_budget: Option<crate::budget::TimeBudgetFn>,
}

/// Every known model. USB IDs from ArgyllCMS `usb/55-Argyll.rules` (facts only).
pub const MODELS: &[Model] = &[
    Model {
        name: crate::cs100a::MODEL,
        title: "Konica Minolta CS-100A",
        usb: &[],
        spec_prefixes: &["cs100a"],
        real: Some(Real {
            address: "PORT",
            address_required: true,
            open: crate::cs100a::open::real,
        }),
        replay: Some(crate::cs100a::open::replay),
        sim: Some(crate::cs100a::open::sim),
        sim_options: &[],
        time_budget: Some(crate::cs100a::budget::time_budget),
    },
    Model {
        name: crate::i1pro::MODEL,
        title: "X-Rite i1Pro / i1Pro 2",
        usb: &[UsbId {
            vid: 0x0971,
            pid: 0x2000,
            bus: Bus::Usb,
        }],
        spec_prefixes: &["i1pro"],
        real: Some(Real {
            address: "SERIAL",
            address_required: false,
            open: crate::i1pro::open::real,
        }),
        replay: Some(crate::i1pro::open::replay),
        sim: Some(crate::i1pro::open::sim),
        sim_options: &["rev", "diffuser"],
        time_budget: Some(crate::i1pro::budget::time_budget),
    },
    Model {
        name: "i1pro3",
        title: "X-Rite i1Pro 3",
        usb: &[UsbId {
            vid: 0x0765,
            pid: 0x6009,
            bus: Bus::Usb,
        }],
        spec_prefixes: &[],
        real: None,
        replay: None,
        sim: None,
        sim_options: &[],
        time_budget: None,
    },
    Model {
        name: "colormunki",
        title: "X-Rite ColorMunki",
        usb: &[UsbId {
            vid: 0x0971,
            pid: 0x2007,
            bus: Bus::Usb,
        }],
        spec_prefixes: &[],
        real: None,
        replay: None,
        sim: None,
        sim_options: &[],
        time_budget: None,
    },
    Model {
        name: "i1d3",
        title: "X-Rite i1Display Pro",
        usb: &[UsbId {
            vid: 0x0765,
            pid: 0x5020,
            bus: Bus::Hid,
        }],
        spec_prefixes: &[],
        real: None,
        replay: None,
        sim: None,
        sim_options: &[],
        time_budget: None,
    },
];

/// Spec words that are not model prefixes.
pub use crate::spec::words::{REPLAY_PREFIX, SIM_PREFIX};

/// The model with this stable name.
pub fn by_name(name: &str) -> Option<&'static Model> {
    MODELS.iter().find(|m| m.name == name)
}

/// The model a real-hardware spec prefix opens.
pub fn by_prefix(prefix: &str) -> Option<&'static Model> {
    MODELS.iter().find(|m| m.spec_prefixes.contains(&prefix))
}

/// The model with this USB ID on this bus.
pub fn by_usb(vid: u16, pid: u16, bus: Bus) -> Option<&'static Model> {
    MODELS
        .iter()
        .find(|m| m.usb.contains(&UsbId { vid, pid, bus }))
}

/// Every USB ID of every model, with its model.
pub fn usb_ids() -> impl Iterator<Item = (&'static Model, UsbId)> {
    MODELS
        .iter()
        .flat_map(|m| m.usb.iter().map(move |id| (m, *id)))
}

/// The simulation specs that open something (`sim:cs100a`).
pub fn simulated_specs() -> Vec<String> {
    MODELS
        .iter()
        .filter(|m| m.sim.is_some())
        .map(|m| crate::spec::words::sim_connection(m.name))
        .collect()
}

/// Names of the models whose transcripts can be replayed.
pub fn replayable() -> Vec<&'static str> {
    MODELS
        .iter()
        .filter(|m| m.replay.is_some())
        .map(|m| m.name)
        .collect()
}

/// The real-hardware spec forms (`cs100a:PORT`, `i1pro[:SERIAL]` where the address may be
/// left out), each with the model's first prefix.
pub fn real_specs() -> Vec<String> {
    MODELS
        .iter()
        .filter_map(|m| {
            let real = m.real.as_ref()?;
            let prefix = m.spec_prefixes.first()?;
            Some(if real.address_required {
                format!("{prefix}:{}", real.address)
            } else {
                format!("{prefix}[:{}]", real.address)
            })
        })
        .collect()
}

/// Every spec form, for "expected …" messages: `cs100a:PORT, replay:FILE.jsonl or
/// sim:cs100a`.
pub fn spec_forms() -> String {
    let mut forms = real_specs();
    if !replayable().is_empty() {
        forms.push(crate::spec::words::replay_connection("FILE.jsonl"));
    }
    forms.extend(simulated_specs());
    match forms.split_last() {
        None => String::new(),
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
    }
}

/// The time budget of model `name` (a registry name: `i1pro`, `cs100a`).
pub fn time_budget(
    name: &str,
    query: &crate::budget::TimeQuery,
) -> Result<crate::budget::TimeBudget, DriverError> {
    let model = by_name(name).ok_or_else(|| DriverError::UnknownSpec {
        spec: name.to_string(),
        expected: spec_forms(),
    })?;
    let budget = model.time_budget.ok_or_else(|| DriverError::Unsupported {
        instrument: name.to_string(),
        what: "a time budget (metamer has no driver for it)".into(),
    })?;
    if !query.luminance_cd_m2.is_finite() || query.luminance_cd_m2 < 0.0 {
        return Err(DriverError::BadOption {
            instrument: name.to_string(),
            option: "expected luminance".into(),
            value: query.luminance_cd_m2.to_string(),
            message: "expected a luminance of 0 or more".into(),
        });
    }
    budget(query)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_prefixes_and_usb_ids_are_unique() {
        let mut names: Vec<&str> = MODELS.iter().map(|m| m.name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), MODELS.len());
        let prefixes: Vec<&str> = MODELS
            .iter()
            .flat_map(|m| m.spec_prefixes)
            .copied()
            .collect();
        for p in &prefixes {
            assert!(*p != REPLAY_PREFIX && *p != SIM_PREFIX, "{p}");
            assert_eq!(prefixes.iter().filter(|q| *q == p).count(), 1, "{p}");
        }
        let ids: Vec<UsbId> = usb_ids().map(|(_, id)| id).collect();
        for id in &ids {
            assert_eq!(ids.iter().filter(|j| *j == id).count(), 1, "{id:?}");
        }
        // A model opened on real hardware must have a prefix to name it.
        for m in MODELS.iter().filter(|m| m.real.is_some()) {
            assert!(!m.spec_prefixes.is_empty(), "{}", m.name);
        }
    }

    #[test]
    fn the_table_gives_the_known_forms_and_ids() {
        assert_eq!(
            spec_forms(),
            "cs100a:PORT, i1pro[:SERIAL], replay:FILE.jsonl, sim:cs100a or sim:i1pro"
        );
        assert_eq!(simulated_specs(), vec!["sim:cs100a", "sim:i1pro"]);
        assert_eq!(replayable(), vec!["cs100a", "i1pro"]);
        assert_eq!(by_prefix("i1pro").unwrap().name, "i1pro");
        assert!(by_name("cs100a").unwrap().usb.is_empty());
        assert_eq!(by_prefix("cs100a").unwrap().name, "cs100a");
        assert!(by_prefix("sim").is_none());
        assert_eq!(
            by_usb(0x0971, 0x2000, Bus::Usb).unwrap().title,
            "X-Rite i1Pro / i1Pro 2"
        );
        assert!(by_usb(0x0971, 0x2000, Bus::Hid).is_none());
        assert_eq!(by_usb(0x0765, 0x5020, Bus::Hid).unwrap().name, "i1d3");
    }
}
