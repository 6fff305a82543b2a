//! The person at the rig: asked to act (cap the sensor, place the instrument on a tile,
//! aim the meter) and to confirm when done, or to abort the session; and whether anybody
//! is there to ask at all.

use std::io::{BufRead, IsTerminal};

use crate::output::console;

/// The operator's answer to a request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Answer {
    /// Done; go on.
    Confirmed,
    /// Stop the session here; what is measured stays in the journal.
    Abort,
}

/// What to do with a reading that differs from its placement's earlier readings by more
/// than the instrument repeats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Recheck {
    /// The instrument was re-aimed or re-placed: set this reading aside and read again.
    Again,
    /// Keep it (the target did change, or the operator trusts it).
    Keep,
    /// Stop the session here; the reading is not kept.
    Stop,
}

/// The readings one placement is for, so a request can say how many are coming.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlacementReadings {
    /// The first reading this request is for, 1-based (above 1 when a placement is asked
    /// again: after a calibration, or when a resumed session continues mid-placement).
    pub first: usize,
    /// Readings of the placement in all.
    pub of: usize,
}

impl std::fmt::Display for PlacementReadings {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (self.first, self.of) {
            (_, 1) => f.write_str("1 reading"),
            (1, n) => write!(f, "{n} readings"),
            (k, n) if k == n => write!(f, "reading {n} of {n}"),
            (k, n) => write!(f, "readings {k}–{n} of {n}"),
        }
    }
}

/// A placement request as the terminal shows it: `{what} — 5 readings`.
pub fn placement_prompt(what: &str, readings: PlacementReadings) -> String {
    format!("{what} — {readings}")
}

/// The operator could not be asked.
#[derive(Debug, thiserror::Error)]
#[error("asking the operator: {0}")]
pub struct OperatorError(#[from] pub std::io::Error);

/// Someone (or something) that carries out requests.
pub trait Operator {
    /// Shows `prompt` and waits until the operator has done it or declines.
    fn ask(&mut self, prompt: &str) -> Result<Answer, OperatorError>;

    /// Asks for the placement `what` (the plan's words, the same for each of its readings)
    /// before `readings` of it are taken. By default [`Operator::ask`] with `what` alone:
    /// a simulated rig acts on the plan's words.
    fn ask_placement(
        &mut self,
        what: &str,
        readings: PlacementReadings,
    ) -> Result<Answer, OperatorError> {
        let _ = readings;
        self.ask(what)
    }

    /// A reading differs from its placement's earlier ones (`why` says how): read it again,
    /// keep it, or stop. By default kept: a script or a simulated rig has nothing to re-aim.
    fn recheck(&mut self, why: &str) -> Result<Recheck, OperatorError> {
        let _ = why;
        Ok(Recheck::Keep)
    }
}

/// The operator at the terminal: the prompt on stderr, Enter confirms, `q` (or `abort`)
/// then Enter, or end of input, aborts. Without a terminal on stdin nobody can act on a
/// prompt, so every request counts as done: a command lets that happen only where nothing
/// physical is measured or the user said the rig runs unattended ([`attendance`]).
#[derive(Debug, Default)]
pub struct TerminalOperator;

/// One line from the terminal after `prompt`; None without a terminal.
fn read_answer(prompt: &str) -> Result<Option<String>, OperatorError> {
    let stdin = std::io::stdin();
    if !stdin.is_terminal() {
        return Ok(None);
    }
    console::err_part(format_args!("{prompt} ")).map_err(std::io::Error::from)?;
    let mut line = String::new();
    if stdin.lock().read_line(&mut line)? == 0 {
        // End of input (Ctrl-D) stops, as `q` does; end the prompt's line.
        console::err_fmt(format_args!("")).map_err(std::io::Error::from)?;
        return Ok(Some("q".into()));
    }
    Ok(Some(line.trim().to_lowercase()))
}

fn is_stop(answer: &str) -> bool {
    matches!(answer, "q" | "quit" | "abort" | "stop")
}

impl Operator for TerminalOperator {
    fn ask(&mut self, prompt: &str) -> Result<Answer, OperatorError> {
        Ok(
            match read_answer(&format!("{prompt}; press Enter when done (q to stop)"))? {
                Some(a) if is_stop(&a) => Answer::Abort,
                _ => Answer::Confirmed,
            },
        )
    }

    fn ask_placement(
        &mut self,
        what: &str,
        readings: PlacementReadings,
    ) -> Result<Answer, OperatorError> {
        self.ask(&placement_prompt(what, readings))
    }

    fn recheck(&mut self, why: &str) -> Result<Recheck, OperatorError> {
        let prompt = format!(
            "{why}: re-aim and press Enter to read it again, k then Enter to keep it (q to stop)"
        );
        Ok(match read_answer(&prompt)? {
            None => Recheck::Keep,
            Some(a) if is_stop(&a) => Recheck::Stop,
            Some(a) if matches!(a.as_str(), "k" | "keep") => Recheck::Keep,
            Some(_) => Recheck::Again,
        })
    }
}

/// Nobody at the rig, by the user's choice: every request counts as done without a word.
#[derive(Debug, Default)]
pub struct Unattended;

impl Operator for Unattended {
    fn ask(&mut self, _: &str) -> Result<Answer, OperatorError> {
        Ok(Answer::Confirmed)
    }
}

/// An operator that follows a script and remembers every prompt it was shown: for tests
/// and simulated rigs, where nothing has to be done by hand. Placement requests are
/// remembered as the terminal shows them (with their reading count).
#[derive(Debug, Default)]
pub struct ScriptedOperator {
    /// Answers in order; when they run out, every further request is confirmed.
    pub answers: std::collections::VecDeque<Answer>,
    /// Every prompt shown, in order.
    pub prompts: Vec<String>,
}

impl ScriptedOperator {
    /// Confirms everything.
    pub fn confirming() -> ScriptedOperator {
        ScriptedOperator::default()
    }

    /// Gives `answers` in order, then confirms.
    pub fn with_answers(answers: impl IntoIterator<Item = Answer>) -> ScriptedOperator {
        ScriptedOperator {
            answers: answers.into_iter().collect(),
            prompts: Vec::new(),
        }
    }
}

impl Operator for ScriptedOperator {
    fn ask(&mut self, prompt: &str) -> Result<Answer, OperatorError> {
        self.prompts.push(prompt.to_string());
        Ok(self.answers.pop_front().unwrap_or(Answer::Confirmed))
    }

    fn ask_placement(
        &mut self,
        what: &str,
        readings: PlacementReadings,
    ) -> Result<Answer, OperatorError> {
        self.ask(&placement_prompt(what, readings))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_placement_says_how_many_readings_it_is_for() {
        let p = |first, of| placement_prompt("aim at patch 1", PlacementReadings { first, of });
        assert_eq!(p(1, 1), "aim at patch 1 — 1 reading");
        assert_eq!(p(1, 5), "aim at patch 1 — 5 readings");
        assert_eq!(p(3, 5), "aim at patch 1 — readings 3–5 of 5");
        assert_eq!(p(5, 5), "aim at patch 1 — reading 5 of 5");
    }
}
