//! The instruments and their calibrations from the session journals: each journal's header
//! names its instruments by role (model, serial, firmware, connection), its `calibration`
//! lines say when each was calibrated, in which mode and under which condition.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::measure_box::assemble::iso_date;
use crate::validation::report::InstrumentUsed;

/// The session journals (`*.jsonl`) in `dir`, by name.
pub fn journals(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "jsonl") && p.is_file())
        .collect();
    v.sort();
    v
}

/// One instrument as the journals of a stage know it.
#[derive(Default)]
struct Seen {
    used: InstrumentUsed,
    /// Session kind → (journal names, earliest start).
    sessions: BTreeMap<String, (Vec<String>, Option<f64>)>,
}

impl Seen {
    /// Its calibrations in time order, then one line per session kind.
    fn finish(mut self) -> InstrumentUsed {
        // ISO times sort as text.
        self.used.calibrations.sort();
        for (kind, (names, start)) in self.sessions {
            self.used.calibrations.push(format!(
                "{kind} session ({}){}",
                names.join(", "),
                start
                    .map(|t| format!(", started {}", iso_date(t)))
                    .unwrap_or_default()
            ));
        }
        self.used
    }
}

/// The instruments of every journal under `stages` ((name, directory)), one per stage and
/// role, with notes on journals that could not be read.
pub fn used(stages: &[(&str, &Path)]) -> (Vec<InstrumentUsed>, Vec<String>) {
    let mut out = Vec::new();
    let mut notes = Vec::new();
    for (stage, dir) in stages {
        let mut by_role: BTreeMap<String, Seen> = BTreeMap::new();
        let files = journals(dir);
        if files.is_empty() {
            notes.push(format!(
                "no instruments of the {stage} stage: {} holds no session journal",
                dir.display()
            ));
        }
        for file in files {
            if let Err(why) = read_journal(&file, stage, &mut by_role) {
                notes.push(format!(
                    "the instruments of {} are not listed: {why}",
                    file.display()
                ));
            }
        }
        out.extend(by_role.into_values().map(Seen::finish));
    }
    (out, notes)
}

fn text(v: &Value) -> Option<String> {
    v.as_str().filter(|s| !s.is_empty()).map(str::to_string)
}

/// Reads one journal's header and calibration lines into `by_role`.
fn read_journal(
    file: &Path,
    stage: &str,
    by_role: &mut BTreeMap<String, Seen>,
) -> Result<(), String> {
    let body = std::fs::read_to_string(file).map_err(|e| format!("cannot be read: {e}"))?;
    let name = file
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut header_seen = false;
    for (i, line) in body.lines().enumerate() {
        let line = line.trim_start_matches('\u{feff}').trim();
        if line.is_empty() {
            continue;
        }
        // A torn last line (a crash mid-write) carries nothing a report needs.
        let Ok(v) = serde_json::from_str::<Value>(line) else {
            continue;
        };
        match v["type"].as_str() {
            Some("header") => {
                header_seen = true;
                let kind = v["kind"].as_str().unwrap_or("measuring");
                let started = v["started_s"].as_f64();
                let Some(instruments) = v["data"]["instruments"].as_object() else {
                    return Err(format!("line {}: the header names no instruments", i + 1));
                };
                for (role, rec) in instruments {
                    let info = &rec["info"];
                    let seen = by_role.entry(role.clone()).or_insert_with(|| Seen {
                        used: InstrumentUsed {
                            role: format!("{stage} ({role})"),
                            model: text(&info["model"]).unwrap_or_else(|| "unknown".into()),
                            serial: text(&info["serial"]),
                            firmware: text(&info["firmware"]),
                            connection: text(&info["connection"]),
                            calibrations: Vec::new(),
                        },
                        sessions: BTreeMap::new(),
                    });
                    let (names, first) = seen.sessions.entry(kind.to_string()).or_default();
                    names.push(name.clone());
                    *first = match (*first, started) {
                        (Some(a), Some(b)) => Some(a.min(b)),
                        (a, b) => a.or(b),
                    };
                }
            }
            Some("calibration") => {
                let role = v["role"].as_str().unwrap_or_default();
                let Some(seen) = by_role.get_mut(role) else {
                    continue;
                };
                let when = v["time_s"]
                    .as_f64()
                    .map(iso_date)
                    .unwrap_or_else(|| "time unknown".into());
                seen.used.calibrations.push(format!(
                    "{when}: {} mode, {} ({name})",
                    v["mode"].as_str().unwrap_or("?"),
                    v["condition"].as_str().unwrap_or("?").replace('_', " ")
                ));
            }
            _ => {}
        }
    }
    if header_seen {
        Ok(())
    } else {
        Err("it has no header line".into())
    }
}

#[cfg(test)]
mod tests {
    use super::super::files::testdir;
    use super::*;

    #[test]
    fn instruments_and_timed_calibrations_from_journals() {
        let dir = testdir::fresh("instruments");
        // 1796165633 s after the epoch is 2026-12-01T22:53:53Z (20788 days + 82433 s).
        testdir::write(
            &dir,
            "tiles.jsonl",
            concat!(
                r#"{"type":"header","kind":"measure-box","started_s":1796165633.6,"data":{"instruments":{"spectral":{"info":{"model":"i1pro","serial":"9000001","firmware":"505 (Rev A–D)","connection":"sim:i1pro"}},"spot":{"info":{"model":"cs100a","serial":null,"firmware":null,"connection":"/dev/ttyUSB0"}}}}}"#,
                "\n",
                r#"{"type":"calibration","role":"spectral","instrument":"i1pro","mode":"emissive","condition":"on_white_tile","before_step":0,"time_s":1796165633.65}"#,
                "\n",
                r#"{"type":"entry","index":0}"#,
                "\n{\"type\":\"calibr"
            ),
        );
        testdir::write(&dir, "broken.jsonl", "{\"type\":\"entry\"}\n");
        let (list, notes) = used(&[("box", &dir)]);
        assert_eq!(list.len(), 2);
        let i1 = &list[0];
        assert_eq!(i1.role, "box (spectral)");
        assert_eq!(i1.model, "i1pro");
        assert_eq!(i1.serial.as_deref(), Some("9000001"));
        assert_eq!(i1.firmware.as_deref(), Some("505 (Rev A–D)"));
        assert_eq!(
            i1.calibrations,
            [
                "2026-12-01T22:53:53Z: emissive mode, on white tile (tiles)",
                "measure-box session (tiles), started 2026-12-01T22:53:53Z"
            ]
        );
        let spot = &list[1];
        assert_eq!(
            (spot.serial.as_deref(), spot.connection.as_deref()),
            (None, Some("/dev/ttyUSB0"))
        );
        assert_eq!(spot.calibrations.len(), 1, "{:?}", spot.calibrations);
        assert!(
            notes.len() == 1
                && notes[0].contains("broken.jsonl")
                && notes[0].ends_with("it has no header line"),
            "{notes:?}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
