//! The driver registry: every instrument model metamer knows, with everything the project
//! knows about it as data — the USB IDs it shows on the bus, the spec prefixes that name it
//! (and the words people use for it that do not), how to open it on a real link, on a
//! replayed transcript and as a simulation, the modes its readings are taken in, its stated
//! repeatability per mode, and why it is not supported where it is not. Spec parsing,
//! `metamer devices`, the sessions' flags, the validation's uncertainties and error messages
//! read this one table, asked by model, so adding a driver is its module plus one row here.

mod repeatability;

use serde::Serialize;

use crate::instrument::Instrument;
use crate::link::replay::Transcript;
use crate::mode::MeasureMode;
use crate::open::{OpenOptions, SimSettings};
use crate::DriverError;
pub use repeatability::{LevelNoise, Repeatability, XyNoise, DARK_CD_M2};

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

/// A word people use for a model that is not one of its spec prefixes (`i1pro2`): a spec
/// using it is refused with how to name the model instead.
#[derive(Clone, Copy, Debug)]
pub struct OtherName {
    /// The word (`i1pro2`).
    pub word: &'static str,
    /// What it names, as a noun (`an i1Pro 2 (Rev E)`).
    pub names: &'static str,
    /// The simulation's options that make the simulated unit one (`rev=e`); empty when the
    /// default simulation is one.
    pub sim_options: &'static str,
}

/// One instrument model: the registry's entry for it.
#[derive(Clone, Copy)]
pub struct ModelEntry {
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
    /// Simulated units whose capabilities describe the model (`metamer devices --describe`):
    /// what kind of unit each stands for (`i1Pro 2 (Rev E) with the diffuser`) and its
    /// simulation options (`rev=e&diffuser=on`).
    pub described_by: &'static [(&'static str, &'static str)],
    /// The modes its readings can be taken in. A model whose only mode is emissive reads
    /// nothing but emitted light, so a reading it took is emissive whatever a file says.
    pub modes: &'static [MeasureMode],
    /// Its stated repeatability in each mode it states one for (1σ of one reading).
    pub repeatability: &'static [(MeasureMode, Repeatability)],
    /// How long its readings and calibrations take, from its protocol facts
    /// ([`crate::budget`]); None while metamer has no driver for it.
    pub time_budget: Option<crate::budget::TimeBudgetFn>,
    /// Words for it that are not spec prefixes, refused with how to name it.
    pub other_names: &'static [OtherName],
    /// Why metamer does not drive it; None where it does.
    pub unsupported: Option<&'static str>,
}

impl ModelEntry {
    /// Its stated repeatability in `mode`, where its row states one.
    pub fn stated_repeatability(&self, mode: MeasureMode) -> Option<Repeatability> {
        self.repeatability
            .iter()
            .find(|(m, _)| *m == mode)
            .map(|(_, r)| *r)
    }

    /// Whether every reading it takes is of emitted light (a spot meter with no lamp and no
    /// diffuser).
    pub fn reads_only_emitted_light(&self) -> bool {
        self.modes == [MeasureMode::Emissive]
    }

    /// How a spec names it on real hardware (`cs100a:PORT`, `i1pro[:SERIAL]`); None without
    /// a driver for it.
    pub fn real_spec(&self) -> Option<String> {
        let real = self.real.as_ref()?;
        let prefix = self.spec_prefixes.first()?;
        Some(if real.address_required {
            format!("{prefix}:{}", real.address)
        } else {
            format!("{prefix}[:{}]", real.address)
        })
    }

    /// How `other` (one of its [`other_names`](Self::other_names)) is named instead.
    pub fn named_instead(&self, other: &OtherName) -> String {
        let mut s = format!("{} is the {}", other.names, self.title);
        if let Some(real) = self.real_spec() {
            s.push_str(&format!(": name it {real}"));
        }
        if self.sim.is_some() {
            let sim = crate::spec::words::sim_connection(self.name);
            let sim = match other.sim_options {
                "" => sim,
                options => format!("{sim}?{options}"),
            };
            s.push_str(&format!(", and simulate one with {sim}"));
        }
        s
    }
}

/// The repeatability taken for a model whose row states none for a mode: the CS-100A's
/// for light (emissive, ambient) and the i1Pro's for surfaces, the two figures metamer
/// has.
const LIGHT_FIGURE_OF: &str = crate::cs100a::MODEL;
const SURFACE_FIGURE_OF: &str = crate::i1pro::MODEL;

/// The stated repeatability of the model named `model` (its stable name, as readings
/// carry it) in `mode`: its row's figure, else the figure taken for any model (the
/// CS-100A's for light, the i1Pro's for surfaces).
pub fn stated_repeatability(model: &str, mode: MeasureMode) -> Repeatability {
    let figure =
        |name: &str, mode: MeasureMode| by_name(name).and_then(|m| m.stated_repeatability(mode));
    let fallback = match mode {
        MeasureMode::Reflective => figure(SURFACE_FIGURE_OF, MeasureMode::Reflective),
        MeasureMode::Emissive | MeasureMode::Ambient => {
            figure(LIGHT_FIGURE_OF, MeasureMode::Emissive)
        }
    };
    figure(model, mode)
        .or(fallback)
        .expect("the registry states the CS-100A's emissive and the i1Pro's reflective figure")
}

/// The CS-100A's repeatability (Konica Minolta's ±0.2 % in Y and ±0.001 in x, y, taken as
/// 2σ; four significant digits of Y and four decimals of x, y sent), as its emulator draws
/// it.
const CS100A_EMISSIVE: Repeatability = Repeatability {
    y_relative: crate::cs100a::emulator::SIGMA_Y_REL,
    y_absolute: 0.0,
    level: LevelNoise::Flat,
    y_digits: Some(4),
    xy: Some(XyNoise::Fixed(crate::cs100a::emulator::SIGMA_XY)),
    xy_decimals: Some(4),
    source: "general knowledge of the CS-100A, not yet confirmed by Konica Minolta's sheet \
             (protocols/cs100a/README.md)",
};

/// The i1Pro's emissive figure: the emulator's curve, checked against the simulated unit
/// from 0.5 to 400 cd/m² (protocols/i1pro/README.md; X-Rite states ±0.002 in x, y for the
/// i1Pro 2).
const I1PRO_EMISSIVE: Repeatability = Repeatability {
    y_relative: crate::i1pro::emulator::REPEATABILITY_Y,
    y_absolute: 0.0,
    level: LevelNoise::Shot {
        full_signal_cd_m2: crate::i1pro::emulator::FULL_SIGNAL_CD_M2,
        dark_cd_m2: crate::i1pro::emulator::DARK_NOISE_CD_M2,
    },
    y_digits: None,
    xy: Some(XyNoise::PerRelativeY(
        crate::i1pro::emulator::REPEATABILITY_XY_PER_Y,
    )),
    xy_decimals: None,
    source: "the simulated unit's shot and sensor noise below the driver's 2 s integration cap \
             (drivers/src/i1pro/emulator.rs, protocols/i1pro/README.md)",
};

/// The i1Pro's ambient figure: 0.15 % of the illuminance, x, y not stated.
const I1PRO_AMBIENT: Repeatability = Repeatability {
    y_relative: crate::i1pro::emulator::REPEATABILITY_Y,
    y_absolute: 0.0,
    level: LevelNoise::Flat,
    y_digits: None,
    xy: None,
    xy_decimals: None,
    source: "the emissive figure at full signal (drivers/src/i1pro/emulator.rs)",
};

/// The i1Pro's reflective figure: 0.002 absolute per band
/// ([`REPEATABILITY_REFLECTANCE`](crate::i1pro::emulator::REPEATABILITY_REFLECTANCE)), 0.2
/// in Y on the scale where white is 100; x, y not stated.
const I1PRO_REFLECTIVE: Repeatability = Repeatability {
    y_relative: 0.0,
    y_absolute: 0.2,
    level: LevelNoise::Flat,
    y_digits: None,
    xy: None,
    xy_decimals: None,
    source: "0.002 per band of reflectance (drivers/src/i1pro/emulator.rs)",
};

/// Every known model. USB IDs from ArgyllCMS `usb/55-Argyll.rules` (facts only).
pub const MODELS: &[ModelEntry] = &[
    ModelEntry {
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
        described_by: &[("CS-100A", "")],
        modes: &[MeasureMode::Emissive],
        repeatability: &[(MeasureMode::Emissive, CS100A_EMISSIVE)],
        time_budget: Some(crate::cs100a::budget::time_budget),
        other_names: &[],
        unsupported: None,
    },
    ModelEntry {
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
        described_by: &[
            ("i1Pro (Rev A–D) with the diffuser", "rev=d&diffuser=on"),
            ("i1Pro 2 (Rev E) with the diffuser", "rev=e&diffuser=on"),
        ],
        modes: &[
            MeasureMode::Emissive,
            MeasureMode::Reflective,
            MeasureMode::Ambient,
        ],
        repeatability: &[
            (MeasureMode::Emissive, I1PRO_EMISSIVE),
            (MeasureMode::Reflective, I1PRO_REFLECTIVE),
            (MeasureMode::Ambient, I1PRO_AMBIENT),
        ],
        time_budget: Some(crate::i1pro::budget::time_budget),
        // The i1Pro 2 is the Rev E unit on the same USB ID; the driver reads both
        // (protocols/i1pro/README.md, "Models").
        other_names: &[OtherName {
            word: "i1pro2",
            names: "an i1Pro 2 (Rev E)",
            sim_options: "rev=e",
        }],
        unsupported: None,
    },
    ModelEntry {
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
        described_by: &[],
        modes: &[],
        repeatability: &[],
        time_budget: None,
        other_names: &[],
        unsupported: Some(
            "it speaks a USB protocol of its own (ArgyllCMS drives it with a separate driver, \
             spectro/i1pro3.c, not its i1Pro one), and metamer's i1Pro codec knows only the \
             i1Pro's and the i1Pro 2's (protocols/i1pro/README.md)",
        ),
    },
    ModelEntry {
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
        described_by: &[],
        modes: &[],
        repeatability: &[],
        time_budget: None,
        other_names: &[],
        unsupported: Some("metamer has no codec for its protocol"),
    },
    ModelEntry {
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
        described_by: &[],
        modes: &[],
        repeatability: &[],
        time_budget: None,
        other_names: &[],
        unsupported: Some("metamer has no codec for its HID protocol"),
    },
];

/// Spec words that are not model prefixes.
pub use crate::spec::words::{REPLAY_PREFIX, SIM_PREFIX};

/// The model with this stable name.
pub fn by_name(name: &str) -> Option<&'static ModelEntry> {
    MODELS.iter().find(|m| m.name == name)
}

/// The model a real-hardware spec prefix opens.
pub fn by_prefix(prefix: &str) -> Option<&'static ModelEntry> {
    MODELS.iter().find(|m| m.spec_prefixes.contains(&prefix))
}

/// The model with this USB ID on this bus.
pub fn by_usb(vid: u16, pid: u16, bus: Bus) -> Option<&'static ModelEntry> {
    MODELS
        .iter()
        .find(|m| m.usb.contains(&UsbId { vid, pid, bus }))
}

/// Every USB ID of every model, with its model.
pub fn usb_ids() -> impl Iterator<Item = (&'static ModelEntry, UsbId)> {
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
    MODELS.iter().filter_map(ModelEntry::real_spec).collect()
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
        // A model metamer does not drive says why; one it drives does not, and states how
        // long its readings take.
        for m in MODELS {
            assert_eq!(m.real.is_none(), m.unsupported.is_some(), "{}", m.name);
            assert_eq!(m.real.is_some(), m.time_budget.is_some(), "{}", m.name);
        }
        // Another word for a model is nobody's name or prefix.
        for word in MODELS.iter().flat_map(|m| m.other_names).map(|o| o.word) {
            assert!(
                by_name(word).is_none() && by_prefix(word).is_none(),
                "{word}"
            );
        }
    }

    /// The figures as the library used them before they were registry data: the CS-100A's
    /// for any light, the i1Pro's for any surface, and the i1Pro's own in its modes.
    #[test]
    fn a_model_without_a_figure_takes_the_cs100as_for_light_and_the_i1pros_for_surfaces() {
        let cs = stated_repeatability("cs100a", MeasureMode::Emissive);
        assert_eq!((cs.y_relative, cs.y_digits), (0.001, Some(4)));
        assert_eq!(cs.xy, Some(XyNoise::Fixed(0.0005)));
        for model in ["mystery", "cs100a", "i1d3"] {
            assert_eq!(stated_repeatability(model, MeasureMode::Ambient), cs);
            assert_eq!(
                stated_repeatability(model, MeasureMode::Reflective).y_absolute,
                0.2
            );
        }
        assert_eq!(stated_repeatability("mystery", MeasureMode::Emissive), cs);
        let ambient = stated_repeatability("i1pro", MeasureMode::Ambient);
        assert_eq!((ambient.y_relative, ambient.xy), (0.0015, None));
        assert!(stated_repeatability("i1pro", MeasureMode::Emissive).follows_level());
        assert!(by_name("cs100a").unwrap().reads_only_emitted_light());
        assert!(!by_name("i1pro").unwrap().reads_only_emitted_light());
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
