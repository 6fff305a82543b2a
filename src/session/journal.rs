//! The durable journal of a guided measurement session: a JSON Lines file whose first line
//! is a header and whose other lines are entries or calibrations, each written whole,
//! flushed and fsynced before the session goes on. A crash, a pulled cable or Ctrl-C loses
//! at most the line being written; [`Journal::resume`] reads the file back, sets aside a
//! torn last line and refuses a journal of another plan, naming the option that differs.
//!
//! An open journal holds an advisory lock (`flock`) on its file, which the system releases
//! when the process ends however it ends: a second session on the same file is refused
//! while the first runs. A journal that two sessions wrote at once (before there was a
//! lock, or over a network file system that ignores it) is recovered on resuming: the
//! first entry of each step is kept, the later ones are moved to a side file
//! ([`duplicates_path`]). The file itself is checked as an input is: a FIFO, a device or a
//! dangling link where the journal should be is an error naming what stands there.
//!
//! The header's and the entries' contents are the caller's (`H`, `E`, through serde), so
//! every kind of session shares one file discipline.

use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::marker::PhantomData;
use std::path::{Path, PathBuf};

use metamer_drivers::{CalibrationCondition, MeasureMode};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::output::owned_file;

mod entry;
mod error;
mod file;
mod resume;

pub use entry::{reading_problem, JournalEntry};
use error::io;
pub use error::JournalError;
use file::{lock, sync_dir};

/// `format` of every journal's header line.
pub const JOURNAL_FORMAT: &str = "metamer-session-journal";
pub const JOURNAL_VERSION: u32 = 2;

/// The first line of a journal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header<H> {
    pub format: String,
    pub version: u32,
    /// What kind of session wrote it (`characterize`, `measure-box`).
    pub kind: String,
    /// The plan's fingerprint: a journal is resumed only by the plan that wrote it.
    pub fingerprint: String,
    /// The options the plan was made from, by name, so a refusal can say which differs.
    pub options: BTreeMap<String, String>,
    /// Number of steps in the plan.
    pub steps: usize,
    /// When the session started, seconds since the Unix epoch.
    pub started_s: f64,
    /// The caller's part.
    pub data: H,
}

/// A calibration done during a session, journalled so a report can say what was
/// calibrated when.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CalibrationRecord {
    /// The instrument's role in the plan (`spot`, `spectral`).
    pub role: String,
    /// The instrument's model name.
    pub instrument: String,
    pub mode: MeasureMode,
    /// What the operator set up for it.
    pub condition: CalibrationCondition,
    /// The step it was done before (0-based plan index).
    pub before_step: usize,
    /// The step whose calibration noise a simulated instrument drew for it: `before_step`,
    /// or for a calibration made again on resuming, that of the calibration it stands for
    /// (absent in journals written before it was recorded: then `before_step`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise_step: Option<usize>,
    /// When, seconds since the Unix epoch.
    pub time_s: f64,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
enum Line<H, E> {
    Header(Header<H>),
    Entry(E),
    Calibration(CalibrationRecord),
}

/// Borrowing twin of [`Line`] for writing without cloning.
#[derive(Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
enum LineRef<'a, H, E> {
    Header(&'a Header<H>),
    Entry(&'a E),
    Calibration(&'a CalibrationRecord),
}

/// What resuming found: every line after the header with its 1-based line number.
#[derive(Debug, PartialEq)]
pub struct Recovered<H, E> {
    /// The header as it was written.
    pub header: Header<H>,
    pub entries: Vec<(usize, E)>,
    pub calibrations: Vec<CalibrationRecord>,
    /// Bytes of a torn last line moved to the side file ([`torn_path`]); 0 if none.
    pub torn_bytes: usize,
    /// Entries of a step already journalled (line, step), moved to [`duplicates_path`].
    pub duplicates: Vec<(usize, usize)>,
    /// Bytes of those lines, newlines included.
    pub duplicate_bytes: usize,
}

/// An open journal, appending.
pub struct Journal<H, E> {
    path: PathBuf,
    file: File,
    _types: PhantomData<fn(H, E)>,
}

/// Where a torn last line of the journal at `path` is kept: `log.jsonl` → `log.torn.txt`.
pub fn torn_path(path: &Path) -> PathBuf {
    path.with_extension("torn.txt")
}

/// Where the later entries of a step journalled twice are kept: `log.jsonl` →
/// `log.duplicates.jsonl`.
pub fn duplicates_path(path: &Path) -> PathBuf {
    path.with_extension("duplicates.jsonl")
}

impl<H, E> Journal<H, E>
where
    H: Serialize + DeserializeOwned,
    E: Serialize + DeserializeOwned + JournalEntry,
{
    /// Starts a new journal at `path` with `header`; an existing file is never overwritten.
    pub fn create(path: &Path, header: &Header<H>) -> Result<Self, JournalError> {
        let file = match OpenOptions::new().append(true).create_new(true).open(path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                return Err(existing(path));
            }
            Err(e) => return Err(io(path)(e)),
        };
        lock(&file, path)?;
        let mut journal = Journal {
            path: path.to_path_buf(),
            file,
            _types: PhantomData,
        };
        journal.append_line(&LineRef::<H, E>::Header(header))?;
        sync_dir(path)?;
        Ok(journal)
    }

    /// Appends one entry; it is on disk when this returns.
    pub fn append(&mut self, entry: &E) -> Result<(), JournalError> {
        self.append_line(&LineRef::<H, E>::Entry(entry))
    }

    /// Appends one calibration; it is on disk when this returns.
    pub fn append_calibration(&mut self, record: &CalibrationRecord) -> Result<(), JournalError> {
        self.append_line(&LineRef::<H, E>::Calibration(record))
    }

    fn append_line(&mut self, line: &LineRef<'_, H, E>) -> Result<(), JournalError> {
        let mut text = serde_json::to_string(line).map_err(|e| JournalError::Io {
            path: self.path.clone(),
            source: std::io::Error::other(e),
        })?;
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

/// The error [`Journal::create`] would give for `path`, checked before anything is opened
/// (a full-screen window, an instrument).
pub fn refuse_existing(path: &Path) -> Result<(), JournalError> {
    // A dangling link is something there too: it is named, not created through.
    if std::fs::symlink_metadata(path).is_ok() {
        return Err(existing(path));
    }
    Ok(())
}

/// Why the existing journal at `path` cannot be started anew: it holds a session, or it
/// holds nothing usable (and can be set aside).
fn existing(path: &Path) -> JournalError {
    // What stands there first: reading a FIFO would wait for ever.
    if let Err(e) = owned_file(path) {
        return e.into();
    }
    // A session measuring into it now is the reason, whatever the file holds yet.
    if let Ok(f) = File::open(path) {
        if let Err(e @ JournalError::InUse { .. }) = lock(&f, path) {
            return e;
        }
    }
    match metamer_color::text::read_bytes(path)
        .ok()
        .as_deref()
        .and_then(broken)
    {
        Some(what) => JournalError::Broken {
            path: path.to_path_buf(),
            what,
        },
        None => JournalError::Exists {
            path: path.to_path_buf(),
            entries: count_entries(path),
        },
    }
}

/// What makes a journal's bytes hold no session: nothing but blanks, or a first line cut
/// off before its end (the crash came while the header was written). None when there is a
/// header line to read (whether it is a valid one is for [`Journal::resume`] to say).
fn broken(bytes: &[u8]) -> Option<String> {
    let bytes = without_bom(bytes);
    let Some(start) = bytes.iter().position(|b| !b.is_ascii_whitespace()) else {
        return Some(if bytes.is_empty() {
            "it is empty".into()
        } else {
            "it holds only blank lines".into()
        });
    };
    let rest = &bytes[start..];
    let whole_line = rest.contains(&b'\n');
    if !whole_line && serde_json::from_slice::<serde_json::Value>(rest).is_err() {
        return Some(format!(
            "its header line was cut off after {} bytes",
            rest.len()
        ));
    }
    None
}

/// The bytes after a UTF-8 byte-order mark, if they start with one.
fn without_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix("\u{feff}".as_bytes()).unwrap_or(bytes)
}

/// Moves the journal at `path` aside to `PATH.broken-N` (the first N free) and returns
/// where; nothing is deleted, so whatever it held can still be looked at.
pub fn set_aside(path: &Path) -> Result<PathBuf, JournalError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut n = 1u64;
    loop {
        let aside = path.with_file_name(format!("{name}.broken-{n}"));
        if std::fs::symlink_metadata(&aside).is_ok() {
            n += 1;
            continue;
        }
        std::fs::rename(path, &aside).map_err(io(path))?;
        sync_dir(path)?;
        return Ok(aside);
    }
}

/// Entry lines in an existing journal (for the "exists" message; 0 if unreadable).
fn count_entries(path: &Path) -> usize {
    metamer_color::text::read_text(path)
        .map(|t| {
            t.lines()
                .filter(|l| l.starts_with("{\"type\":\"entry\""))
                .count()
        })
        .unwrap_or(0)
}

#[cfg(test)]
mod recovery_tests;
#[cfg(test)]
mod tests;
