//! What a session measures: an ordered list of steps, each naming the instrument (by its
//! role in the rig), the mode, a label, how to prepare it and the caller's data that goes
//! into its journal entry, with a fingerprint that ties a journal to the plan.

use std::collections::BTreeMap;
use std::time::Duration;

use metamer_drivers::MeasureMode;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// How the rig is made ready for a step.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Prepare {
    /// Show these 8-bit drive values on the screen.
    Show { rgb: [u8; 3] },
    /// Ask the operator to do something and wait for confirmation ("place the i1Pro on
    /// tile row 2, column 3").
    Operator { prompt: String },
    /// Nothing to do (a simulated rig, or a step that measures what the last one set up).
    None,
}

impl std::fmt::Display for Prepare {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Prepare::Show { rgb } => write!(f, "RGB {rgb:?}"),
            Prepare::Operator { prompt } => write!(f, "{prompt}"),
            Prepare::None => f.write_str("no preparation"),
        }
    }
}

/// One measurement of a plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Step<D> {
    /// For people: `black`, `red ramp 64`, `tile 2,3 at −40°`.
    pub label: String,
    /// Which instrument of the rig takes it (`spot`, `spectral`).
    pub role: String,
    pub mode: MeasureMode,
    pub prepare: Prepare,
    /// Wait between preparing and measuring. Not part of the fingerprint: it changes how a
    /// step is taken, not what is measured, so a resumed session may wait differently.
    #[serde(skip)]
    pub settle: Duration,
    /// The caller's data, copied into the step's journal entry.
    pub data: D,
}

/// An ordered list of steps and the options it was made from.
#[derive(Clone, Debug, PartialEq)]
pub struct SessionPlan<D> {
    /// What kind of session this is (`characterize`), recorded in the journal.
    pub kind: String,
    /// The options the steps were made from, by name; a resume with another value of one
    /// is refused naming it.
    pub options: BTreeMap<String, String>,
    pub steps: Vec<Step<D>>,
}

impl<D: Serialize> SessionPlan<D> {
    /// A stable fingerprint of the plan: SHA-256 of the canonical JSON (object keys sorted,
    /// no whitespace) of its kind, options and steps, in hex. Fails only where the caller's
    /// data does not serialize to JSON (a map with non-text keys).
    pub fn fingerprint(&self) -> Result<String, serde_json::Error> {
        // serde_json::Value keeps object keys in a BTreeMap (sorted), so the text of a value
        // does not depend on field order in the source.
        let canonical = serde_json::to_value((&self.kind, &self.options, &self.steps))?;
        let digest = Sha256::digest(canonical.to_string().as_bytes());
        Ok(digest.iter().map(|b| format!("{b:02x}")).collect())
    }
}
