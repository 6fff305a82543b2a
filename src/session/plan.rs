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
    /// Slide the image the screen shows by this many of its pixels (right, down), so
    /// that another part of it lies under an instrument that stays where it is
    /// ([`super::Screen::shift_image`]).
    ShiftImage { by: [i64; 2] },
    /// Nothing to do (a simulated rig, or a step that measures what the last one set up).
    None,
}

impl std::fmt::Display for Prepare {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Prepare::Show { rgb } => write!(f, "RGB {rgb:?}"),
            Prepare::Operator { prompt } => write!(f, "{prompt}"),
            Prepare::ShiftImage { by } => {
                write!(f, "the image slid {} right, {} down", by[0], by[1])
            }
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
    /// no whitespace) of its kind, options and steps, in hex. The words of an operator's
    /// request are left out: they say how to set up what the step's label and data name,
    /// and a better worded request must not orphan a journal half measured. Fails only
    /// where the caller's data does not serialize to JSON (a map with non-text keys).
    pub fn fingerprint(&self) -> Result<String, serde_json::Error> {
        let mut steps = serde_json::to_value(&self.steps)?;
        for step in steps.as_array_mut().into_iter().flatten() {
            if let Some(prompt) = step.pointer_mut("/prepare/operator/prompt") {
                *prompt = serde_json::Value::Null;
            }
        }
        // serde_json::Value keeps object keys in a BTreeMap (sorted), so the text of a value
        // does not depend on field order in the source.
        let canonical = serde_json::to_value((&self.kind, &self.options, &steps))?;
        let digest = Sha256::digest(canonical.to_string().as_bytes());
        Ok(digest.iter().map(|b| format!("{b:02x}")).collect())
    }
}

/// The steps each step shares its placement with: a run of steps of one instrument and
/// mode that begins with an operator's request and goes on with the same request or with
/// steps that need no preparation (the instrument stays where it was put). `[i]` is the
/// range of step i's placement, None for a step outside any (a colour shown on a screen,
/// or a step with nothing to prepare that follows none).
pub fn placements<D>(steps: &[Step<D>]) -> Vec<Option<std::ops::Range<usize>>> {
    let mut starts: Vec<Option<usize>> = Vec::with_capacity(steps.len());
    // The open placement: its first step and its request.
    let mut open: Option<(usize, &str)> = None;
    for (i, step) in steps.iter().enumerate() {
        let continues = |start: usize| {
            let first = &steps[start];
            first.role == step.role && first.mode == step.mode
        };
        open = match (&step.prepare, open) {
            (Prepare::Operator { prompt }, Some((start, p)))
                if p == prompt.as_str() && continues(start) =>
            {
                Some((start, p))
            }
            (Prepare::Operator { prompt }, _) => Some((i, prompt.as_str())),
            (Prepare::None, Some((start, p))) if continues(start) => Some((start, p)),
            _ => None,
        };
        starts.push(open.map(|(start, _)| start));
    }
    let mut ranges = vec![None; steps.len()];
    let mut i = 0;
    while i < steps.len() {
        let Some(start) = starts[i] else {
            i += 1;
            continue;
        };
        let end = (i..steps.len())
            .find(|&j| starts[j] != Some(start))
            .unwrap_or(steps.len());
        ranges[i..end].fill(Some(start..end));
        i = end;
    }
    ranges
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(role: &str, prepare: Prepare) -> Step<usize> {
        Step {
            label: String::new(),
            role: role.into(),
            mode: MeasureMode::Emissive,
            prepare,
            settle: Duration::ZERO,
            data: 0,
        }
    }

    fn ask(p: &str) -> Prepare {
        Prepare::Operator { prompt: p.into() }
    }

    #[test]
    fn repeats_of_one_request_and_the_steps_after_it_share_a_placement() {
        let show = Prepare::Show { rgb: [1, 2, 3] };
        let steps = vec![
            step("spot", ask("a")),
            step("spot", ask("a")),
            step("spot", Prepare::None),
            step("spot", ask("b")),
            step("spectral", ask("b")),
            step("spectral", Prepare::None),
            step("spot", show.clone()),
            step("spot", Prepare::None),
            step("spot", ask("a")),
        ];
        assert_eq!(
            placements(&steps),
            vec![
                Some(0..3),
                Some(0..3),
                Some(0..3),
                Some(3..4),
                Some(4..6),
                Some(4..6),
                None,
                None,
                Some(8..9),
            ]
        );
    }

    #[test]
    fn the_words_of_a_request_are_not_part_of_the_fingerprint() {
        let plan = |prompt: &str, rgb: u8| SessionPlan {
            kind: "test".into(),
            options: BTreeMap::new(),
            steps: vec![
                step("spot", ask(prompt)),
                step("spot", Prepare::Show { rgb: [rgb; 3] }),
            ],
        };
        let fp = |p: SessionPlan<usize>| p.fingerprint().unwrap();
        assert_eq!(fp(plan("aim at it", 1)), fp(plan("aim the meter at it", 1)));
        assert_ne!(fp(plan("aim at it", 1)), fp(plan("aim at it", 2)));
    }
}
