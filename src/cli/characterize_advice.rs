//! What to do next after a characterization stops or fails, said with `characterize`'s
//! flags: the session engine's errors know what went wrong, not which flag resumes, which
//! option differs or where the readings taken so far are.

use metamer::display::characterize::{CharacterizeError, Outcome};
use metamer::session::{JournalError, RunEnd, SessionError};

/// The error with what to do next, where the session engine's own message cannot say it;
/// None for the others, whose message is complete.
pub(super) fn advice(e: &CharacterizeError) -> Option<String> {
    let CharacterizeError::Session(e) = e else {
        return None;
    };
    match e {
        SessionError::Journal(j) => journal_text(j),
        SessionError::InstrumentDiffers {
            path, logged, now, ..
        } => Some(format!(
            "{} was measured with the instrument {logged}, this session has {now}: resume with the instrument it was started with (--instrument), or choose another output directory",
            path.display()
        )),
        SessionError::InstrumentSettingDiffers(d) => Some(format!(
            "{} was measured with the {} whose {} was {}, this session's is {}: resume with the settings it was started with, or choose another output directory",
            d.path.display(),
            d.model,
            setting_flag(&d.setting),
            d.logged,
            d.now
        )),
        SessionError::Step {
            index,
            total,
            label,
            prepare,
            done,
            journal,
            source,
        } => Some(format!(
            "patch {} of {total} ({label}, {prepare}): {source}\n  {done} of {total} readings are safe in {}; fix the cause and run the same command with --resume",
            index + 1,
            journal.display()
        )),
        _ => None,
    }
}

/// What is still to measure and how to continue; None when finished.
pub(super) fn left_to_do(outcome: &Outcome) -> Option<String> {
    let Outcome::Incomplete {
        end,
        done,
        total,
        log,
    } = outcome
    else {
        return None;
    };
    let (done, total) = (*done, *total);
    let missing = total - done;
    let log = log.display();
    Some(match end {
        RunEnd::Stopped { .. } | RunEnd::Complete => format!(
            "stopped with {missing} of {total} readings still to take; continue with --resume (log: {log})"
        ),
        RunEnd::Interrupted { .. } => format!(
            "interrupted with {missing} of {total} readings still to take; the others are safe in {log}: continue with --resume"
        ),
        RunEnd::Aborted { .. } if done == 0 => format!(
            "stopped at your request before any of the {total} readings: continue with --resume (log: {log})"
        ),
        RunEnd::Aborted { .. } => format!(
            "stopped at your request with {missing} of {total} readings still to take; the others are safe in {log}: continue with --resume"
        ),
    })
}

fn journal_text(e: &JournalError) -> Option<String> {
    Some(match e {
        JournalError::Exists { path, entries } => format!(
            "{} exists with {entries} reading(s) of an earlier session: continue it with --resume, or choose another output directory",
            path.display()
        ),
        JournalError::Broken { path, what } => format!(
            "{} holds no session to continue: {what}; run with --resume to set it aside (as {}.broken-N, kept) and start afresh",
            path.display(),
            path.display()
        ),
        JournalError::OptionDiffers {
            path,
            option,
            logged,
            now,
        } => format!(
            "{} was written by another session: its --{} is {logged}, this one's is {now}; run with the options it was started with and --resume, or choose another output directory",
            path.display(),
            option.replace('_', "-")
        ),
        _ => return None,
    })
}

/// An instrument setting as the user gave it: a flag, or an option of the `--instrument`
/// spec of a simulation.
fn setting_flag(setting: &str) -> String {
    match setting {
        "speed" => "--speed".into(),
        s => match s.strip_prefix(metamer_drivers::simulated::SIM_OPTION_PREFIX) {
            Some(sim) => format!("simulation's {sim} (--instrument sim:…?{sim}=)"),
            None => s.to_string(),
        },
    }
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;
    use metamer::session::{Prepare, StepFailure};

    fn failed_step() -> SessionError {
        SessionError::Step {
            index: 6,
            total: 62,
            label: "red 3".into(),
            prepare: Prepare::Show { rgb: [128, 0, 0] },
            done: 6,
            journal: PathBuf::from("out/log.jsonl"),
            source: Box::new(StepFailure::NoScreen),
        }
    }

    /// The words a user acts on after a reading failed, written out by hand: which patch,
    /// what failed, what is safe, and the flag that goes on. measure-box's says the same, its command adding
    /// how to go on.
    #[test]
    fn a_failed_reading_says_which_patch_what_is_safe_and_how_to_go_on() {
        let e = CharacterizeError::Session(failed_step());
        assert_eq!(
            advice(&e).unwrap(),
            "patch 7 of 62 (red 3, RGB [128, 0, 0]): the plan shows drive values but the rig \
             has no screen\n  6 of 62 readings are safe in out/log.jsonl; fix the cause and \
             run the same command with --resume"
        );
        let box_error = metamer::measure_box::MeasureBoxError::Session {
            stage: metamer::measure_box::BoxStage::Spots,
            source: failed_step(),
        };
        assert_eq!(
            box_error.advice().unwrap(),
            "stage spots, reading 7 of 62 (red 3: RGB [128, 0, 0]): the plan shows drive \
             values but the rig has no screen\n  6 of 62 readings are safe in out/log.jsonl"
        );
    }
}
