//! The person at the rig: asked to act (cap the sensor, place the instrument on a tile,
//! aim the meter) and to confirm when done, or to abort the session.

use std::io::{BufRead, IsTerminal, Write};

/// The operator's answer to a request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Answer {
    /// Done; go on.
    Confirmed,
    /// Stop the session here; what is measured stays in the journal.
    Abort,
}

/// The operator could not be asked.
#[derive(Debug, thiserror::Error)]
#[error("asking the operator: {0}")]
pub struct OperatorError(#[from] pub std::io::Error);

/// Someone (or something) that carries out requests.
pub trait Operator {
    /// Shows `prompt` and waits until the operator has done it or declines.
    fn ask(&mut self, prompt: &str) -> Result<Answer, OperatorError>;
}

/// The operator at the terminal: the prompt on stderr, Enter confirms, `q` (or `abort`)
/// then Enter, or end of input, aborts. Without a terminal on stdin (scripts, CI) nobody can
/// act on a prompt, so every request counts as done.
#[derive(Debug, Default)]
pub struct TerminalOperator;

impl Operator for TerminalOperator {
    fn ask(&mut self, prompt: &str) -> Result<Answer, OperatorError> {
        let stdin = std::io::stdin();
        if !stdin.is_terminal() {
            return Ok(Answer::Confirmed);
        }
        eprint!("{prompt}; press Enter when done (q to stop) ");
        std::io::stderr().flush()?;
        let mut line = String::new();
        if stdin.lock().read_line(&mut line)? == 0 {
            return Ok(Answer::Abort);
        }
        Ok(match line.trim() {
            "q" | "quit" | "abort" => Answer::Abort,
            _ => Answer::Confirmed,
        })
    }
}

/// An operator that follows a script and remembers every prompt it was shown: for tests
/// and simulated rigs, where nothing has to be done by hand.
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
}
