//! Choosing an instrument by one string, read by one type, [`Spec`] (docs/architecture.md,
//! "Instrument specs"):
//!
//! - `cs100a:PORT` — a CS-100A on a serial port (`cs100a:/dev/ttyUSB0`, `cs100a:COM3`);
//! - `replay:FILE.jsonl` — a transcript played through the real driver;
//! - `sim:cs100a` — the emulated CS-100A, answering from a world. Options after `?`,
//!   separated by `&`: `time_scale=F` (1 = the real meter's ≈100/400 ms per reading,
//!   0.01 a hundred times faster, 0 instant; default 1, or the environment variable
//!   `METAMER_SIM_TIME_SCALE`), `seed=N` (noise seed, default 1), `noise=off`;
//! - `sim:i1pro` — the emulated i1Pro on the in-process USB pair, with the same options and
//!   its own (`rev=d|e`, `diffuser=on`), listed in its registry row;
//! - `i1pro[:SERIAL]` — an i1Pro on USB (`i1pro` alone: the first one found).
//!
//! Which models exist and how each is opened is the driver registry's; this module only
//! reads the spec. Nothing outside it looks at a spec's words: callers ask a [`Spec`].
//!
//! A spec keeps its text exactly as given: the experiment hashes the text into its stage
//! records, so `sim:cs100a?` must stay `sim:cs100a?`. Reading the form never fails; whether
//! the registry can open it is [`Spec::check`]'s question, asked where a command wants a
//! typo refused early, and asked again by opening.

mod sim_options;
#[cfg(test)]
mod tests;
pub mod words;

use std::fmt;
use std::path::Path;
use std::sync::Arc;

use crate::instrument::Instrument;
use crate::link::replay::Transcript;
use crate::open::OpenOptions;
use crate::registry::{self, ModelEntry};
use crate::world::World;
use crate::DriverError;
use sim_options::sim_settings;
pub use sim_options::MAX_TIME_SCALE;
use words::{REPLAY_PREFIX, SIM_PREFIX};

/// An instrument named by one string: its text as given, and the form it has.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Spec {
    text: String,
    kind: SpecForm,
}

/// The form of a spec, read from its words alone (the registry is not asked).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum SpecForm {
    /// `sim:MODEL[?OPTIONS]`: an emulator.
    Simulated {
        /// The model's name.
        model: String,
        /// What follows `?`, unparsed (empty when there is none).
        options: String,
    },
    /// `replay:FILE`: a recorded transcript.
    Replay {
        /// The transcript's path (empty when none is given, which opens nothing).
        file: String,
    },
    /// `PREFIX[:ADDRESS]`: an instrument on a port or a bus, if the registry knows the prefix.
    Device {
        /// The model's prefix (`cs100a`, `i1pro`).
        prefix: String,
        /// The port or serial number (empty when left out).
        address: String,
    },
}

impl Spec {
    /// Reads the form of `text`. Never fails: an unknown form is refused by
    /// [`check`](Self::check) or when opened, with the forms the registry offers.
    pub fn new(text: impl Into<String>) -> Spec {
        let text = text.into();
        // A word without a colon (`sim`, `replay`, `i1pro`) is a device prefix: only
        // `sim:` and `replay:` begin a simulation or a transcript.
        let kind = match text.split_once(':') {
            Some((SIM_PREFIX, rest)) => {
                let (model, options) = rest.split_once('?').unwrap_or((rest, ""));
                SpecForm::Simulated {
                    model: model.to_string(),
                    options: options.to_string(),
                }
            }
            Some((REPLAY_PREFIX, rest)) => SpecForm::Replay {
                file: rest.to_string(),
            },
            Some((prefix, address)) => SpecForm::Device {
                prefix: prefix.to_string(),
                address: address.to_string(),
            },
            None => SpecForm::Device {
                prefix: text.clone(),
                address: String::new(),
            },
        };
        Spec { text, kind }
    }

    /// The emulated `model` with its default options (`sim:cs100a`); add options with
    /// [`with_option`](Self::with_option).
    pub fn simulated(model: &str) -> Spec {
        Spec::new(words::sim_connection(model))
    }

    /// The transcript `file` played through its model's driver.
    pub fn replay(file: &Path) -> Spec {
        Spec::new(words::replay_connection(&file.display().to_string()))
    }

    /// This spec with `key=value` appended to its options (`?` for the first, then `&`).
    pub fn with_option(&self, key: &str, value: impl fmt::Display) -> Spec {
        let joint = if self.text.contains('?') { '&' } else { '?' };
        Spec::new(format!("{}{joint}{key}={value}", self.text))
    }

    /// A simulation with `seed` added unless its text already names one: the simulated box
    /// and its instruments draw their noise from seeds derived from the session's. Real
    /// and replayed instruments have no seed and are returned as they are.
    pub fn with_seed_unless_set(&self, seed: u64) -> Spec {
        if !self.is_simulated() || self.text.contains("seed=") {
            self.clone()
        } else {
            self.with_option("seed", seed)
        }
    }

    /// The text as given.
    pub fn as_str(&self) -> &str {
        &self.text
    }

    /// The form of the spec.
    pub fn kind(&self) -> &SpecForm {
        &self.kind
    }

    /// Whether an emulator answers (`sim:…`): it sees only the world it is given, never a
    /// real screen or box.
    pub fn is_simulated(&self) -> bool {
        matches!(self.kind, SpecForm::Simulated { .. })
    }

    /// The transcript a replayed instrument reads, when one is named.
    pub fn replay_file(&self) -> Option<&Path> {
        match &self.kind {
            SpecForm::Replay { file } if !file.is_empty() => Some(Path::new(file)),
            _ => None,
        }
    }

    /// Whether this names a physical instrument (`cs100a:PORT`, `i1pro[:SERIAL]`): not a
    /// simulation and not a replayed transcript, so something real is measured and somebody
    /// has to place, aim or calibrate it. A spec naming no model is not (opening it fails).
    pub fn is_physical(&self) -> bool {
        self.is_physical_in(registry::MODELS)
    }

    /// Whether the spec names an instrument that could be opened, without opening it: the
    /// form, the model and a simulation's options. A command that opens its instruments
    /// only after minutes of other work checks them first, so a typo fails at once. A real
    /// instrument's port and a transcript's content are only looked at when opened.
    pub fn check(&self) -> Result<(), DriverError> {
        self.check_in(registry::MODELS)
    }

    /// A simulation's pace: its `time_scale` option, else `METAMER_SIM_TIME_SCALE`, else 1
    /// (the real instrument's). None for a real or replayed instrument, or a simulation
    /// whose spec does not check.
    pub fn sim_time_scale(&self) -> Option<f64> {
        let SpecForm::Simulated { model, options } = &self.kind else {
            return None;
        };
        let row = registry::MODELS
            .iter()
            .find(|m| m.name == model && m.sim.is_some())?;
        sim_settings(&self.text, options, row.sim_options)
            .ok()
            .map(|s| s.time_scale)
    }

    /// Opens the instrument; `stimulus` is what a simulated one sees.
    pub fn open(
        &self,
        stimulus: Option<Arc<dyn World>>,
    ) -> Result<Box<dyn Instrument>, DriverError> {
        self.open_with(&OpenOptions {
            stimulus,
            record: None,
        })
    }

    /// [`open`](Self::open) with recording and other options.
    pub fn open_with(&self, options: &OpenOptions) -> Result<Box<dyn Instrument>, DriverError> {
        self.open_in(registry::MODELS, options)
    }

    /// The registry model this spec names by its stable name (`sim:MODEL`) or a prefix
    /// (`PREFIX[:ADDRESS]`), whether or not it could be opened; None for a transcript, whose
    /// model only its header says.
    pub fn model(&self) -> Option<&'static ModelEntry> {
        self.model_in(registry::MODELS)
    }

    fn model_in<'m>(&self, models: &'m [ModelEntry]) -> Option<&'m ModelEntry> {
        match &self.kind {
            SpecForm::Simulated { model, .. } => models.iter().find(|m| m.name == model),
            SpecForm::Device { prefix, .. } => models
                .iter()
                .find(|m| m.spec_prefixes.contains(&prefix.as_str())),
            SpecForm::Replay { .. } => None,
        }
    }

    /// Why the spec opens nothing: a word for a model that is named otherwise (`i1pro2`),
    /// a model metamer does not drive (`i1pro3`), or else an unknown form, with every
    /// form the registry offers.
    fn unknown_in(&self, models: &[ModelEntry]) -> DriverError {
        let word = match &self.kind {
            SpecForm::Simulated { model, .. } => model.as_str(),
            SpecForm::Device { prefix, .. } => prefix.as_str(),
            SpecForm::Replay { .. } => "",
        };
        let spec = self.text.clone();
        for m in models {
            if let Some(other) = m.other_names.iter().find(|o| o.word == word) {
                return DriverError::NamedOtherwise {
                    spec,
                    message: m.named_instead(other),
                };
            }
            if let (Some(why), true) = (m.unsupported, m.name == word) {
                return DriverError::NamedOtherwise {
                    spec,
                    message: format!(
                        "the {} is not supported: {why}; known: {}",
                        m.title,
                        registry::spec_forms()
                    ),
                };
            }
        }
        DriverError::UnknownSpec {
            spec,
            expected: registry::spec_forms(),
        }
    }

    fn is_physical_in(&self, models: &[ModelEntry]) -> bool {
        match &self.kind {
            SpecForm::Device { prefix, .. } => models
                .iter()
                .any(|m| m.spec_prefixes.contains(&prefix.as_str()) && m.real.is_some()),
            _ => false,
        }
    }

    fn check_in(&self, models: &[ModelEntry]) -> Result<(), DriverError> {
        match &self.kind {
            SpecForm::Replay { file } if !file.is_empty() => Ok(()),
            SpecForm::Simulated { model, options } => {
                let row = models
                    .iter()
                    .find(|m| m.name == model && m.sim.is_some())
                    .ok_or_else(|| self.unknown_in(models))?;
                sim_settings(&self.text, options, row.sim_options).map(drop)
            }
            _ => self.real_in(models).map(drop),
        }
    }

    /// The registry row and address of a physical instrument, or the unknown-spec error.
    fn real_in<'m>(
        &self,
        models: &'m [ModelEntry],
    ) -> Result<(&'m registry::Real, &str), DriverError> {
        // A bare prefix (`i1pro`) names a model whose address may be left out; `replay:`
        // with no file, or a prefix no row has, names nothing.
        let SpecForm::Device { prefix, address } = &self.kind else {
            return Err(self.unknown_in(models));
        };
        match models
            .iter()
            .find(|m| m.spec_prefixes.contains(&prefix.as_str()))
            .and_then(|m| m.real.as_ref())
        {
            Some(real) if !address.is_empty() || !real.address_required => Ok((real, address)),
            _ => Err(self.unknown_in(models)),
        }
    }

    /// Opens the spec from the rows of `models` (the registry's, or a test's own).
    fn open_in(
        &self,
        models: &[ModelEntry],
        options: &OpenOptions,
    ) -> Result<Box<dyn Instrument>, DriverError> {
        let by_name = |name: &str| models.iter().find(|m| m.name == name);
        match &self.kind {
            SpecForm::Replay { file } if !file.is_empty() => {
                let transcript = Transcript::load(Path::new(file))?;
                let instrument = transcript.header.instrument.clone();
                let open = by_name(&instrument).and_then(|m| m.replay).ok_or_else(|| {
                    DriverError::Transcript {
                        file: file.clone(),
                        line: 1,
                        message: format!(
                            "the transcript is of instrument '{instrument}', which has no driver \
                             yet (known: {})",
                            registry::replayable().join(", ")
                        ),
                    }
                })?;
                open(transcript, options)
            }
            SpecForm::Simulated {
                model,
                options: query,
            } => {
                let row = by_name(model)
                    .filter(|m| m.sim.is_some())
                    .ok_or_else(|| self.unknown_in(models))?;
                let open = row.sim.ok_or_else(|| self.unknown_in(models))?;
                open(&sim_settings(&self.text, query, row.sim_options)?, options)
            }
            _ => {
                let (real, address) = self.real_in(models)?;
                (real.open)(address, options)
            }
        }
    }
}

impl fmt::Display for Spec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

impl AsRef<str> for Spec {
    fn as_ref(&self) -> &str {
        &self.text
    }
}

impl From<&str> for Spec {
    fn from(text: &str) -> Spec {
        Spec::new(text)
    }
}

impl From<String> for Spec {
    fn from(text: String) -> Spec {
        Spec::new(text)
    }
}

impl std::str::FromStr for Spec {
    type Err = std::convert::Infallible;
    fn from_str(text: &str) -> Result<Spec, Self::Err> {
        Ok(Spec::new(text))
    }
}

/// Written as its text, so a stored spec reads back as given.
impl serde::Serialize for Spec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.text)
    }
}

impl<'de> serde::Deserialize<'de> for Spec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Spec, D::Error> {
        String::deserialize(d).map(Spec::new)
    }
}

/// Opens the instrument `spec` names; `stimulus` is what a simulated one sees.
pub fn open_instrument(
    spec: &str,
    stimulus: Option<Arc<dyn World>>,
) -> Result<Box<dyn Instrument>, DriverError> {
    Spec::new(spec).open(stimulus)
}

/// [`open_instrument`] with recording and other options.
pub fn open_instrument_with(
    spec: &str,
    options: &OpenOptions,
) -> Result<Box<dyn Instrument>, DriverError> {
    Spec::new(spec).open_with(options)
}

/// [`Spec::check`] of the text `spec`.
pub fn check_spec(spec: &str) -> Result<(), DriverError> {
    Spec::new(spec).check()
}

/// The model a name from a reading, a file or a command line stands for: a model's stable
/// name (`cs100a`, `CS-100A`: case and hyphens aside), another word for it (`i1pro2`), or
/// a spec naming it (`sim:i1pro?seed=2`, `cs100a:/dev/ttyUSB0`). None for anything else,
/// a transcript among them (only its header says its model).
pub fn model_named(name: &str) -> Option<&'static ModelEntry> {
    let word: String = name
        .trim()
        .chars()
        .filter(|c| *c != '-')
        .flat_map(char::to_lowercase)
        .collect();
    registry::MODELS
        .iter()
        .find(|m| m.name == word || m.other_names.iter().any(|o| o.word == word))
        .or_else(|| Spec::new(name.trim()).model())
}

/// [`Spec::is_physical`] of the text `spec`.
pub fn is_physical(spec: &str) -> bool {
    Spec::new(spec).is_physical()
}
