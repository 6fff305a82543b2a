//! What a session's journal records: its header's engine part (the instruments by role)
//! and one entry per measured step.

use std::collections::BTreeMap;

use metamer_color::text::echo;
use metamer_drivers::{Instrument, InstrumentInfo, MeasureMode, Reading};
use serde::{Deserialize, Serialize};

use super::journal::{reading_problem, Journal, JournalEntry};
use super::plan::Step;

/// One measured step as journalled.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Entry<D> {
    /// The step's plan index.
    pub index: usize,
    pub label: String,
    pub role: String,
    pub mode: MeasureMode,
    pub data: D,
    pub reading: Reading,
}

impl<D: Clone> Entry<D> {
    /// The entry of step `index` of a plan, measured as `reading`.
    pub fn of_step(index: usize, step: &Step<D>, reading: Reading) -> Entry<D> {
        Entry {
            index,
            label: step.label.clone(),
            role: step.role.clone(),
            mode: step.mode,
            data: step.data.clone(),
            reading,
        }
    }
}

/// Entries of a session journal: the step is the plan index, and the reading must be one
/// an instrument can have given.
impl<D> JournalEntry for Entry<D> {
    fn step(&self) -> Option<usize> {
        Some(self.index)
    }

    fn problem(&self) -> Option<String> {
        reading_problem(&self.reading)
            .map(|p| format!("step {} ({}): {p}", self.index, echo(&self.label)))
    }
}

/// The header's caller part the engine adds to: the instruments by role.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionHeader<H> {
    /// Every instrument of the rig by role, with its model-specific settings in force.
    pub instruments: BTreeMap<String, InstrumentRecord>,
    /// The caller's part.
    pub details: H,
}

/// An instrument as the journal records it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InstrumentRecord {
    pub info: InstrumentInfo,
    /// Model-specific settings in force, name → value.
    pub options: BTreeMap<String, String>,
}

impl InstrumentRecord {
    pub fn of(instrument: &dyn Instrument) -> InstrumentRecord {
        InstrumentRecord {
            info: instrument.info(),
            options: instrument.option_values().into_iter().collect(),
        }
    }
}

/// The journal type of a session with header data `H` and step data `D`.
pub type SessionJournal<H, D> = Journal<SessionHeader<H>, Entry<D>>;
