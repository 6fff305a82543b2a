//! Who answers a session's requests, decided before anything is opened: the person at the
//! terminal, or nobody — and a physical instrument with nobody to place, aim or calibrate
//! it refused.

use std::io::IsTerminal;

use metamer_drivers::Spec;

use super::operator::{Operator, TerminalOperator, Unattended};

/// Who answers a session's requests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Attendance {
    /// Somebody at the terminal: ask them ([`TerminalOperator`]).
    Terminal,
    /// Nobody: the user said so, or no terminal and nothing physical measured (simulated
    /// or replayed instruments), so every request counts as done.
    Unattended,
}

impl Attendance {
    /// The operator that answers for this attendance.
    pub fn operator(self) -> Box<dyn Operator> {
        match self {
            Attendance::Terminal => Box::new(TerminalOperator),
            Attendance::Unattended => Box::new(Unattended),
        }
    }
}

/// A physical instrument would be driven with nobody to place, aim or calibrate it.
#[derive(Debug, thiserror::Error)]
#[error("{spec} is a real instrument and stdin is not a terminal: nobody can be asked to place, aim or calibrate it, and it would measure wherever it points")]
pub struct NobodyAtTheRig {
    /// The first physical instrument's spec.
    pub spec: String,
}

/// Who answers the requests of a session with the instruments `specs`: refused when one is physical, stdin is no terminal and the user did not say
/// `unattended`; nothing is opened, so the refusal comes before any reading.
pub fn attendance(specs: &[&Spec], unattended: bool) -> Result<Attendance, NobodyAtTheRig> {
    attendance_with(specs, unattended, std::io::stdin().is_terminal())
}

/// [`attendance`] with the terminal's presence given (for tests).
pub fn attendance_with(
    specs: &[&Spec],
    unattended: bool,
    terminal: bool,
) -> Result<Attendance, NobodyAtTheRig> {
    if unattended {
        return Ok(Attendance::Unattended);
    }
    if terminal {
        return Ok(Attendance::Terminal);
    }
    match specs.iter().find(|s| s.is_physical()) {
        Some(spec) => Err(NobodyAtTheRig {
            spec: spec.to_string(),
        }),
        None => Ok(Attendance::Unattended),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_real_instrument_needs_a_terminal_or_unattended() {
        let (sim, port) = (Spec::new("sim:i1pro"), Spec::new("cs100a:/dev/ttyUSB0"));
        let real = [&sim, &port];
        let e = attendance_with(&real, false, false).unwrap_err();
        assert_eq!(e.spec, "cs100a:/dev/ttyUSB0");
        assert_eq!(
            attendance_with(&real, true, false).unwrap(),
            Attendance::Unattended
        );
        assert_eq!(
            attendance_with(&real, false, true).unwrap(),
            Attendance::Terminal
        );
        // Said unattended at a terminal: nobody is asked.
        assert_eq!(
            attendance_with(&real, true, true).unwrap(),
            Attendance::Unattended
        );
        // Simulated and replayed instruments measure nothing real.
        let (sim, replay) = (Spec::new("sim:cs100a"), Spec::new("replay:a.jsonl"));
        let played = [&sim, &replay];
        assert_eq!(
            attendance_with(&played, false, false).unwrap(),
            Attendance::Unattended
        );
        assert_eq!(
            attendance_with(&played, false, true).unwrap(),
            Attendance::Terminal
        );
    }
}
