//! What resuming a journal checks before a session goes on: each journalled entry at the
//! step the plan has for it, the same instrument in each role with the same settings, and
//! what the operator should know of readings a second session wrote at the same time.

use std::path::Path;

use serde::Serialize;

use super::error::{SessionError, SettingDiffers};
use crate::session::plan::SessionPlan;
use crate::session::record::{Entry, InstrumentRecord};

/// Puts each journalled entry of `recovered` (with its line) at its step in `entries`,
/// refusing one the plan does not have or planned otherwise.
pub(super) fn place_entries<D: Serialize + PartialEq>(
    path: &Path,
    plan: &SessionPlan<D>,
    recovered: Vec<(usize, Entry<D>)>,
    entries: &mut [Option<Entry<D>>],
) -> Result<(), SessionError> {
    let bad = |line: usize, message: String| SessionError::Entry {
        path: path.to_path_buf(),
        line,
        message,
    };
    for (line, entry) in recovered {
        let step = plan.steps.get(entry.index).ok_or_else(|| {
            bad(
                line,
                format!(
                    "step index {} is beyond the plan's {}",
                    entry.index,
                    plan.steps.len()
                ),
            )
        })?;
        if step.label != entry.label || step.data != entry.data {
            return Err(bad(
                line,
                format!(
                    "step {} was planned as '{}' ({}) but journalled as '{}' ({})",
                    entry.index,
                    step.label,
                    serde_json::to_string(&step.data).unwrap_or_default(),
                    entry.label,
                    serde_json::to_string(&entry.data).unwrap_or_default(),
                ),
            ));
        }
        // The journal has refused readings no instrument gave and set aside a step's
        // later entries (see JournalEntry), so each step is here once.
        let i = entry.index;
        entries[i] = Some(entry);
    }
    Ok(())
}

/// What the operator should know of the readings of steps already journalled (`(line,
/// step)`) that resuming moved aside, if any.
pub(super) fn duplicates_note(path: &Path, duplicates: &[(usize, usize)]) -> Option<String> {
    if duplicates.is_empty() {
        return None;
    }
    let lines: Vec<String> = duplicates
        .iter()
        .map(|(line, step)| format!("line {line} (step {step})"))
        .collect();
    Some(format!(
        "{} held {} reading(s) of steps it already had, written by a second session at the same time: the first of each is kept, the others were moved to {} ({})",
        path.display(),
        lines.len(),
        crate::session::journal::duplicates_path(path).display(),
        lines.join(", ")
    ))
}

/// Whether readings of the instrument `now` are comparable with those of `logged`: the same
/// model, the same unit where both report a serial, and every setting the same.
pub(super) fn same_instrument(
    path: &Path,
    role: &str,
    logged: &InstrumentRecord,
    now: &InstrumentRecord,
) -> Result<(), SessionError> {
    if logged.info.model != now.info.model {
        return Err(SessionError::InstrumentDiffers {
            path: path.to_path_buf(),
            role: role.to_string(),
            logged: logged.info.model.clone(),
            now: now.info.model.clone(),
        });
    }
    let differs = |setting: &str, a: Option<&String>, b: Option<&String>| {
        let shown = |v: Option<&String>| v.cloned().unwrap_or_else(|| "(not set)".into());
        SessionError::InstrumentSettingDiffers(Box::new(SettingDiffers {
            path: path.to_path_buf(),
            role: role.to_string(),
            model: now.info.model.clone(),
            setting: setting.to_string(),
            logged: shown(a),
            now: shown(b),
        }))
    };
    if logged.info.serial != now.info.serial {
        return Err(differs(
            "serial number",
            logged.info.serial.as_ref(),
            now.info.serial.as_ref(),
        ));
    }
    let names: std::collections::BTreeSet<&String> =
        logged.options.keys().chain(now.options.keys()).collect();
    for name in names {
        let (a, b) = (logged.options.get(name), now.options.get(name));
        if a != b {
            return Err(differs(name, a, b));
        }
    }
    Ok(())
}
