//! The durable log of a characterization (architecture: "append every reading to a durable
//! JSON Lines log as it arrives"): a header line naming the plan, display and instrument,
//! then one line per reading, each written whole, flushed and fsynced before the next
//! patch is shown. A crash, a pulled cable or Ctrl-C loses at most the reading being
//! written; [`SessionLog::resume`] reads the log back, sets aside a torn last line and
//! refuses a log of another plan.

use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use metamer_drivers::{InstrumentInfo, Reading};
use serde::{Deserialize, Serialize};

use super::plan::{Plan, PlannedPatch};

/// The log's file name inside the output directory.
pub const LOG_FILE: &str = "log.jsonl";
/// Where a torn last line is kept when a log is resumed.
pub const TORN_FILE: &str = "log.torn.txt";
/// `format` of the header line.
pub const LOG_FORMAT: &str = "metamer-characterize-log";
pub const LOG_VERSION: u32 = 1;

/// The first line of a log.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LogHeader {
    pub format: String,
    pub version: u32,
    /// [`Plan::hash`] of the plan being measured.
    pub plan_hash: String,
    pub ramp_steps: usize,
    pub repeats: usize,
    pub grid_steps: usize,
    /// Number of readings the plan takes.
    pub readings: usize,
    /// The display as given to `--display`, canonical (`virtual:ips-lcd`, `window:0`).
    pub display: String,
    /// The instrument as given to `--instrument`.
    pub instrument: String,
    pub instrument_info: InstrumentInfo,
    /// When the session started, seconds since the Unix epoch.
    pub started_s: f64,
}

impl LogHeader {
    /// The header of a log of `plan` starting now.
    pub fn new(
        plan: &Plan,
        display: &str,
        instrument: &str,
        instrument_info: InstrumentInfo,
    ) -> LogHeader {
        LogHeader {
            format: LOG_FORMAT.into(),
            version: LOG_VERSION,
            plan_hash: plan.hash(),
            ramp_steps: plan.options.ramp_steps,
            repeats: plan.options.repeats,
            grid_steps: plan.options.grid_steps,
            readings: plan.patches.len(),
            display: display.into(),
            instrument: instrument.into(),
            instrument_info,
            started_s: metamer_drivers::instrument::now_s(),
        }
    }
}

/// One reading line.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LogReading {
    /// [`PlannedPatch::index`].
    pub index: usize,
    /// The drive values shown, repeated so the log reads on its own.
    pub rgb: [u8; 3],
    pub label: String,
    pub reading: Reading,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
enum Line {
    Header(LogHeader),
    Reading(LogReading),
}

/// The log could not be written, read or resumed.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    #[error("{} exists with {readings} reading(s) of an earlier session: continue it with --resume, or choose another output directory", path.display())]
    Exists { path: PathBuf, readings: usize },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}, line {line}: {message}", path.display())]
    Bad {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{} was written by another session: its {what} is {logged}, this one's is {now}; resume with the options it was started with, or choose another output directory", path.display())]
    Mismatch {
        path: PathBuf,
        what: &'static str,
        logged: String,
        now: String,
    },
}

/// What resuming found.
#[derive(Debug, Default, PartialEq)]
pub struct Recovered {
    /// The readings already in the log, by plan index.
    pub readings: Vec<LogReading>,
    /// Bytes of a torn last line that were moved to [`TORN_FILE`].
    pub torn_bytes: usize,
}

/// An open log, appending.
pub struct SessionLog {
    path: PathBuf,
    file: File,
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> LogError + '_ {
    move |source| LogError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Makes a new file's directory entry durable too (POSIX: fsync of the file alone does
/// not guarantee its name survives a crash).
fn sync_dir(path: &Path) -> Result<(), LogError> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    File::open(dir).and_then(|d| d.sync_all()).map_err(io(dir))
}

impl SessionLog {
    /// Starts a new log in `dir` with `header`; an existing log is never overwritten.
    pub fn create(dir: &Path, header: &LogHeader) -> Result<SessionLog, LogError> {
        let path = dir.join(LOG_FILE);
        let file = match OpenOptions::new().append(true).create_new(true).open(&path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                let readings = count_readings(&path);
                return Err(LogError::Exists { path, readings });
            }
            Err(e) => return Err(io(&path)(e)),
        };
        let mut log = SessionLog { path, file };
        log.append_line(&Line::Header(header.clone()))?;
        sync_dir(&log.path)?;
        Ok(log)
    }

    /// Opens the log in `dir` to continue it: checks it belongs to `plan` and `header`'s
    /// display and instrument model, and returns the readings it holds. A last line cut
    /// off by a crash is moved to [`TORN_FILE`] and removed from the log; any other damage
    /// is an error that leaves the file untouched.
    pub fn resume(
        dir: &Path,
        plan: &Plan,
        header: &LogHeader,
    ) -> Result<(SessionLog, Recovered), LogError> {
        let path = dir.join(LOG_FILE);
        let mut file = OpenOptions::new()
            .read(true)
            .append(true)
            .open(&path)
            .map_err(io(&path))?;
        let mut bytes = Vec::new();
        file.read_to_end(&mut bytes).map_err(io(&path))?;
        let complete = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        let tail = &bytes[complete..];
        // A tail that parses is a whole line that lost only its newline: keep it.
        let tail_is_whole = !tail.is_empty() && serde_json::from_slice::<Line>(tail).is_ok();
        let bad = |line: usize, message: String| LogError::Bad {
            path: path.clone(),
            line,
            message,
        };
        let text_end = if tail_is_whole { bytes.len() } else { complete };
        let text = std::str::from_utf8(&bytes[..text_end]).map_err(|e| {
            bad(
                1 + bytes[..e.valid_up_to()]
                    .iter()
                    .filter(|&&b| b == b'\n')
                    .count(),
                "not UTF-8 text".into(),
            )
        })?;
        let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
        let logged = match lines.next() {
            None => return Err(bad(1, "empty log: no header line".into())),
            Some((n, l)) => match serde_json::from_str::<Line>(l) {
                Ok(Line::Header(h)) => h,
                Ok(Line::Reading(_)) => {
                    return Err(bad(n, "the first line must be the header".into()))
                }
                Err(e) => return Err(bad(n, format!("not a log header: {e}"))),
            },
        };
        if logged.format != LOG_FORMAT || logged.version != LOG_VERSION {
            return Err(bad(
                1,
                format!(
                    "format {} version {} is not {LOG_FORMAT} version {LOG_VERSION}",
                    logged.format, logged.version
                ),
            ));
        }
        let mismatch = |what, logged: String, now: String| LogError::Mismatch {
            path: path.clone(),
            what,
            logged,
            now,
        };
        if logged.plan_hash != header.plan_hash {
            return Err(mismatch(
                "plan",
                format!(
                    "{} (--ramp-steps {} --repeats {} --grid-steps {})",
                    logged.plan_hash, logged.ramp_steps, logged.repeats, logged.grid_steps
                ),
                format!(
                    "{} (--ramp-steps {} --repeats {} --grid-steps {})",
                    header.plan_hash, header.ramp_steps, header.repeats, header.grid_steps
                ),
            ));
        }
        if logged.display != header.display {
            return Err(mismatch("display", logged.display, header.display.clone()));
        }
        if logged.instrument_info.model != header.instrument_info.model {
            return Err(mismatch(
                "instrument model",
                logged.instrument_info.model,
                header.instrument_info.model.clone(),
            ));
        }
        let mut seen = vec![false; plan.patches.len()];
        let mut readings = Vec::new();
        for (n, l) in lines {
            let r = match serde_json::from_str::<Line>(l) {
                Ok(Line::Reading(r)) => r,
                Ok(Line::Header(_)) => return Err(bad(n, "a second header line".into())),
                Err(e) => return Err(bad(n, format!("not a reading: {e}"))),
            };
            let planned: &PlannedPatch = plan.patches.get(r.index).ok_or_else(|| {
                bad(
                    n,
                    format!(
                        "patch index {} is beyond the plan's {}",
                        r.index,
                        plan.patches.len()
                    ),
                )
            })?;
            if planned.rgb != r.rgb {
                return Err(bad(
                    n,
                    format!(
                        "patch {} was planned as {:?} but logged as {:?}",
                        r.index, planned.rgb, r.rgb
                    ),
                ));
            }
            if std::mem::replace(&mut seen[r.index], true) {
                return Err(bad(n, format!("patch {} is logged twice", r.index)));
            }
            readings.push(r);
        }
        let mut torn_bytes = 0;
        if tail_is_whole {
            file.write_all(b"\n").map_err(io(&path))?;
            file.sync_data().map_err(io(&path))?;
        } else if !tail.is_empty() {
            // Keep the fragment before cutting it off: nothing measured is thrown away.
            let torn_path = dir.join(TORN_FILE);
            let mut torn = OpenOptions::new()
                .create(true)
                .append(true)
                .open(&torn_path)
                .map_err(io(&torn_path))?;
            torn.write_all(tail)
                .and_then(|()| torn.write_all(b"\n"))
                .and_then(|()| torn.sync_data())
                .map_err(io(&torn_path))?;
            file.set_len(complete as u64).map_err(io(&path))?;
            file.seek(SeekFrom::End(0)).map_err(io(&path))?;
            file.sync_data().map_err(io(&path))?;
            torn_bytes = tail.len();
        }
        Ok((
            SessionLog { path, file },
            Recovered {
                readings,
                torn_bytes,
            },
        ))
    }

    /// Appends one reading; it is on disk when this returns.
    pub fn append(&mut self, reading: &LogReading) -> Result<(), LogError> {
        self.append_line(&Line::Reading(reading.clone()))
    }

    fn append_line(&mut self, line: &Line) -> Result<(), LogError> {
        let mut text = serde_json::to_string(line).expect("log lines serialize");
        text.push('\n');
        // One write of the whole line, so a crash leaves at most one torn line at the end.
        self.file
            .write_all(text.as_bytes())
            .map_err(io(&self.path))?;
        self.file.flush().map_err(io(&self.path))?;
        self.file.sync_data().map_err(io(&self.path))
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// The error [`SessionLog::create`] would give for `dir`, checked before anything is
/// opened (a full-screen window, an instrument).
pub fn refuse_existing(dir: &Path) -> Result<(), LogError> {
    let path = dir.join(LOG_FILE);
    if path.exists() {
        let readings = count_readings(&path);
        return Err(LogError::Exists { path, readings });
    }
    Ok(())
}

/// Reading lines in an existing log (for the "exists" message; 0 if unreadable).
fn count_readings(path: &Path) -> usize {
    std::fs::read_to_string(path)
        .map(|t| {
            t.lines()
                .filter(|l| l.contains("\"type\":\"reading\""))
                .count()
        })
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::display::characterize::plan::PlanOptions;

    fn header(plan: &Plan) -> LogHeader {
        LogHeader {
            started_s: 1.0,
            ..LogHeader::new(
                plan,
                "virtual:ips-lcd",
                "sim:cs100a",
                InstrumentInfo {
                    model: "cs100a".into(),
                    serial: None,
                    firmware: None,
                    connection: "sim:cs100a".into(),
                },
            )
        }
    }

    fn reading(plan: &Plan, index: usize) -> LogReading {
        LogReading {
            index,
            rgb: plan.patches[index].rgb,
            label: plan.patches[index].label.clone(),
            reading: Reading {
                timestamp_s: index as f64,
                ..Reading::from_yxy(10.0 + index as f64, 0.3, 0.3, "cs100a")
            },
        }
    }

    fn tempdir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("metamer-log-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn readings_survive_and_a_torn_line_is_set_aside() {
        let dir = tempdir("torn");
        let plan = Plan::new(PlanOptions::default()).unwrap();
        let h = header(&plan);
        let mut log = SessionLog::create(&dir, &h).unwrap();
        for i in 0..3 {
            log.append(&reading(&plan, i)).unwrap();
        }
        drop(log);
        // A crash in the middle of writing the fourth line.
        let line = serde_json::to_string(&Line::Reading(reading(&plan, 3))).unwrap();
        let cut = &line[..line.len() / 2];
        OpenOptions::new()
            .append(true)
            .open(dir.join(LOG_FILE))
            .unwrap()
            .write_all(cut.as_bytes())
            .unwrap();
        let (mut log, rec) = SessionLog::resume(&dir, &plan, &h).unwrap();
        assert_eq!(
            rec.readings,
            (0..3).map(|i| reading(&plan, i)).collect::<Vec<_>>()
        );
        assert_eq!(rec.torn_bytes, cut.len());
        assert_eq!(
            std::fs::read_to_string(dir.join(TORN_FILE)).unwrap(),
            format!("{cut}\n")
        );
        log.append(&reading(&plan, 3)).unwrap();
        drop(log);
        let (_, rec) = SessionLog::resume(&dir, &plan, &h).unwrap();
        assert_eq!(rec.readings.len(), 4);
        assert_eq!(rec.torn_bytes, 0);
        // Every line of the file is whole JSON.
        let text = std::fs::read_to_string(dir.join(LOG_FILE)).unwrap();
        assert_eq!(text.lines().count(), 5);
        assert!(text.ends_with('\n'));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_line_that_lost_only_its_newline_is_kept() {
        let dir = tempdir("newline");
        let plan = Plan::new(PlanOptions::default()).unwrap();
        let h = header(&plan);
        drop(SessionLog::create(&dir, &h).unwrap());
        let line = serde_json::to_string(&Line::Reading(reading(&plan, 0))).unwrap();
        OpenOptions::new()
            .append(true)
            .open(dir.join(LOG_FILE))
            .unwrap()
            .write_all(line.as_bytes())
            .unwrap();
        let (mut log, rec) = SessionLog::resume(&dir, &plan, &h).unwrap();
        assert_eq!(rec.readings, vec![reading(&plan, 0)]);
        log.append(&reading(&plan, 1)).unwrap();
        drop(log);
        let (_, rec) = SessionLog::resume(&dir, &plan, &h).unwrap();
        assert_eq!(rec.readings.len(), 2);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn existing_other_and_damaged_logs_are_refused_untouched() {
        let dir = tempdir("refuse");
        let plan = Plan::new(PlanOptions::default()).unwrap();
        let h = header(&plan);
        let mut log = SessionLog::create(&dir, &h).unwrap();
        log.append(&reading(&plan, 0)).unwrap();
        drop(log);
        let before = std::fs::read(dir.join(LOG_FILE)).unwrap();
        let e = SessionLog::create(&dir, &h).err().unwrap();
        assert!(matches!(e, LogError::Exists { readings: 1, .. }), "{e}");
        assert!(e.to_string().contains("--resume"), "{e}");
        let other = Plan::new(PlanOptions {
            ramp_steps: 5,
            repeats: 2,
            grid_steps: 0,
        })
        .unwrap();
        let e = SessionLog::resume(&dir, &other, &header(&other))
            .err()
            .unwrap();
        assert!(
            e.to_string().contains("its plan is")
                && e.to_string()
                    .contains("--ramp-steps 9 --repeats 1 --grid-steps 0)"),
            "{e}"
        );
        let mut elsewhere = h.clone();
        elsewhere.display = "virtual:ideal-crt".into();
        let e = SessionLog::resume(&dir, &plan, &elsewhere).err().unwrap();
        assert!(
            e.to_string()
                .contains("its display is virtual:ips-lcd, this one's is virtual:ideal-crt"),
            "{e}"
        );
        assert_eq!(std::fs::read(dir.join(LOG_FILE)).unwrap(), before);
        // Damage before the last line is not a crash: an error naming the line.
        let mut damaged = before.clone();
        damaged.extend_from_slice(b"{\"type\":\"reading\",\"oops\n");
        damaged.extend_from_slice(
            serde_json::to_string(&Line::Reading(reading(&plan, 1)))
                .unwrap()
                .as_bytes(),
        );
        damaged.push(b'\n');
        std::fs::write(dir.join(LOG_FILE), &damaged).unwrap();
        let e = SessionLog::resume(&dir, &plan, &h).err().unwrap();
        assert!(
            e.to_string().contains("log.jsonl, line 3: not a reading"),
            "{e}"
        );
        assert_eq!(std::fs::read(dir.join(LOG_FILE)).unwrap(), damaged);
        // A reading whose drive values are not the plan's.
        let mut wrong = reading(&plan, 1);
        wrong.rgb = [1, 2, 3];
        let mut bytes = before.clone();
        bytes.extend_from_slice(
            serde_json::to_string(&Line::Reading(wrong))
                .unwrap()
                .as_bytes(),
        );
        bytes.push(b'\n');
        std::fs::write(dir.join(LOG_FILE), &bytes).unwrap();
        let e = SessionLog::resume(&dir, &plan, &h).err().unwrap();
        assert!(
            e.to_string()
                .contains("line 3: patch 1 was planned as [255, 0, 0] but logged as [1, 2, 3]"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
