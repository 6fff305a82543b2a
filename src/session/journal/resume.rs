//! Resuming a journal: reading it back step by step — the text and a torn last line, the
//! header and its checks against the plan, the entries and calibrations — then repairing
//! the file so the session can append to it.
//!
//! Every check runs before the file is changed: a journal that cannot be resumed is left
//! as it was found.

use std::collections::BTreeSet;
use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::marker::PhantomData;
use std::ops::Range;
use std::path::Path;

use metamer_color::text::{echo, strip_bom};
use serde::de::DeserializeOwned;
use serde::Serialize;

use super::error::{io, JournalError};
use super::file::{keep_aside, open_locked, read_all, rewrite};
use super::{
    broken, duplicates_path, torn_path, without_bom, CalibrationRecord, Header, Journal,
    JournalEntry, Line, Recovered, JOURNAL_FORMAT, JOURNAL_VERSION,
};

impl<H, E> Journal<H, E>
where
    H: Serialize + DeserializeOwned,
    E: Serialize + DeserializeOwned + JournalEntry,
{
    /// Opens the journal at `path` to continue it: checks it was written for a plan with
    /// `expected`'s kind, fingerprint and options, and returns what it holds. A last line
    /// cut off by a crash is moved to [`torn_path`] and removed from the journal; later
    /// entries of a step journalled twice are moved to [`duplicates_path`]; any other
    /// damage is an error naming the line that leaves the file untouched. The journal is
    /// locked from the moment it is opened: another session holding it is an error.
    pub fn resume(
        path: &Path,
        expected: &Header<H>,
    ) -> Result<(Self, Recovered<H, E>), JournalError> {
        let file = open_locked(path)?;
        let bytes = read_all(&file, path)?;
        if let Some(what) = broken(&bytes) {
            return Err(JournalError::Broken {
                path: path.to_path_buf(),
                what,
            });
        }
        let tail = Tail::of::<H, E>(&bytes);
        let mut lines = numbered_lines(journal_text(path, &bytes, &tail)?).into_iter();
        let header = read_header::<H, E>(path, lines.next())?;
        check_same_plan(path, &header, expected)?;
        let read = read_lines::<H, E>(path, lines)?;
        let torn_bytes = set_torn_line_aside(path, &tail)?;
        let (file, duplicate_bytes) = repair(path, file, &bytes, &tail, &read.duplicate_ranges)?;
        let journal = Journal {
            path: path.to_path_buf(),
            file,
            _types: PhantomData,
        };
        Ok((
            journal,
            Recovered {
                header,
                entries: read.entries,
                calibrations: read.calibrations,
                torn_bytes,
                duplicates: read.duplicates,
                duplicate_bytes,
            },
        ))
    }
}

/// The journal's bytes after its last newline, and whether they are a line of their own.
struct Tail<'a> {
    /// Where the last complete line ends (0 if there is none).
    complete: usize,
    bytes: &'a [u8],
    /// A tail that parses is a whole line that lost only its newline: kept.
    whole: bool,
}

impl<'a> Tail<'a> {
    fn of<H, E>(bytes: &'a [u8]) -> Tail<'a>
    where
        H: DeserializeOwned,
        E: DeserializeOwned,
    {
        let complete = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        let tail = &bytes[complete..];
        let json = if complete == 0 {
            without_bom(tail)
        } else {
            tail
        };
        Tail {
            complete,
            bytes: tail,
            whole: !tail.is_empty() && serde_json::from_slice::<Line<H, E>>(json).is_ok(),
        }
    }

    /// Where the lines read end: the file's end, or before a torn last line.
    fn text_end(&self) -> usize {
        if self.whole {
            self.complete + self.bytes.len()
        } else {
            self.complete
        }
    }

    /// A last line cut off by a crash.
    fn torn(&self) -> bool {
        !self.bytes.is_empty() && !self.whole
    }
}

fn bad(path: &Path, line: usize, message: String) -> JournalError {
    JournalError::Bad {
        path: path.to_path_buf(),
        line,
        message,
    }
}

/// The journal's lines up to a torn last one, as text.
fn journal_text<'a>(path: &Path, bytes: &'a [u8], tail: &Tail) -> Result<&'a str, JournalError> {
    std::str::from_utf8(&bytes[..tail.text_end()]).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        bad(path, line, "not UTF-8 text".into())
    })
}

/// Each line with its 1-based number and byte range. Blank lines carry nothing (an
/// editor's trailing newline, a line a tool added): skipped. A byte-order mark (an
/// editor's) is not part of the header line.
fn numbered_lines(text: &str) -> Vec<(usize, Range<usize>, &str)> {
    let mut at = 0;
    let mut lines = Vec::new();
    for (i, raw) in text.split_inclusive('\n').enumerate() {
        let range = at..at + raw.len();
        at = range.end;
        let mut l = raw.strip_suffix('\n').unwrap_or(raw);
        l = l.strip_suffix('\r').unwrap_or(l);
        if i == 0 {
            l = strip_bom(l);
        }
        if !l.trim().is_empty() {
            lines.push((i + 1, range, l));
        }
    }
    lines
}

/// The header from the first line that is not blank.
fn read_header<H, E>(
    path: &Path,
    first: Option<(usize, Range<usize>, &str)>,
) -> Result<Header<H>, JournalError>
where
    H: DeserializeOwned,
    E: DeserializeOwned,
{
    let Some((n, _, l)) = first else {
        return Err(bad(path, 1, "empty journal: no header line".into()));
    };
    // The header's fixed fields first, so a journal of another format or version says so
    // rather than failing on the caller's part.
    let v: serde_json::Value =
        serde_json::from_str(l).map_err(|e| bad(path, n, format!("not a journal header: {e}")))?;
    if v["format"] != JOURNAL_FORMAT || v["version"] != JOURNAL_VERSION {
        return Err(bad(
            path,
            n,
            format!(
                "format {} version {} is not {JOURNAL_FORMAT} version {JOURNAL_VERSION}",
                echo(&v["format"].to_string()),
                echo(&v["version"].to_string())
            ),
        ));
    }
    match serde_json::from_value::<Line<H, E>>(v) {
        Ok(Line::Header(h)) => Ok(h),
        Ok(_) => Err(bad(path, n, "the first line must be the header".into())),
        Err(e) => Err(bad(path, n, format!("not a journal header: {e}"))),
    }
}

/// Whether the journal's header `logged` was written for the plan `now` describes.
fn check_same_plan<H>(
    path: &Path,
    logged: &Header<H>,
    now: &Header<H>,
) -> Result<(), JournalError> {
    if logged.kind != now.kind {
        return Err(JournalError::KindDiffers {
            path: path.to_path_buf(),
            logged: logged.kind.clone(),
            now: now.kind.clone(),
        });
    }
    if logged.fingerprint == now.fingerprint {
        return Ok(());
    }
    let absent = || "(not set)".to_string();
    let names: BTreeSet<&String> = logged.options.keys().chain(now.options.keys()).collect();
    for name in names {
        let (a, b) = (logged.options.get(name), now.options.get(name));
        if a != b {
            return Err(JournalError::OptionDiffers {
                path: path.to_path_buf(),
                option: name.clone(),
                logged: a.cloned().unwrap_or_else(absent),
                now: b.cloned().unwrap_or_else(absent),
            });
        }
    }
    Err(JournalError::StepsDiffer {
        path: path.to_path_buf(),
        logged: logged.fingerprint.clone(),
        now: now.fingerprint.clone(),
    })
}

/// The lines after the header, sorted out.
struct Lines<E> {
    entries: Vec<(usize, E)>,
    calibrations: Vec<CalibrationRecord>,
    /// Later entries of a step already journalled (line, step) and their byte ranges.
    duplicates: Vec<(usize, usize)>,
    duplicate_ranges: Vec<Range<usize>>,
}

/// The entries and calibrations after the header; the first entry of each step is kept.
fn read_lines<'a, H, E>(
    path: &Path,
    lines: impl Iterator<Item = (usize, Range<usize>, &'a str)>,
) -> Result<Lines<E>, JournalError>
where
    H: DeserializeOwned,
    E: DeserializeOwned + JournalEntry,
{
    let mut read = Lines {
        entries: Vec::new(),
        calibrations: Vec::new(),
        duplicates: Vec::new(),
        duplicate_ranges: Vec::new(),
    };
    let mut steps = BTreeSet::new();
    for (n, range, l) in lines {
        match serde_json::from_str::<Line<H, E>>(l) {
            Ok(Line::Entry(e)) => {
                if let Some(message) = e.problem() {
                    return Err(JournalError::Entry {
                        path: path.to_path_buf(),
                        line: n,
                        message,
                    });
                }
                match e.step() {
                    // A second session's reading of a step the first had taken.
                    Some(step) if !steps.insert(step) => {
                        read.duplicates.push((n, step));
                        read.duplicate_ranges.push(range);
                    }
                    _ => read.entries.push((n, e)),
                }
            }
            Ok(Line::Calibration(c)) => read.calibrations.push(c),
            Ok(Line::Header(_)) => return Err(bad(path, n, "a second header line".into())),
            Err(e) => return Err(bad(path, n, format!("not an entry or calibration: {e}"))),
        }
    }
    Ok(read)
}

/// Keeps a torn last line in [`torn_path`] before it is cut off (nothing measured is
/// thrown away); its length, 0 if there is none.
fn set_torn_line_aside(path: &Path, tail: &Tail) -> Result<usize, JournalError> {
    if !tail.torn() {
        return Ok(0);
    }
    let mut kept = tail.bytes.to_vec();
    kept.push(b'\n');
    keep_aside(&torn_path(path), &kept)?;
    Ok(tail.bytes.len())
}

/// Leaves the journal ready to append to: duplicates moved out, a last line given its
/// newline or a torn one cut off, the file positioned at its end. Returns the file (a
/// rewrite replaces it) and the bytes of the duplicates moved out.
fn repair(
    path: &Path,
    mut file: File,
    bytes: &[u8],
    tail: &Tail,
    duplicate_ranges: &[Range<usize>],
) -> Result<(File, usize), JournalError> {
    let mut duplicate_bytes = 0;
    if !duplicate_ranges.is_empty() {
        let kept = set_duplicates_aside(path, bytes, tail.text_end(), duplicate_ranges)?;
        duplicate_bytes = duplicate_ranges.iter().map(|r| r.len()).sum();
        file = rewrite(path, &file, &kept)?;
    } else if tail.whole {
        file.write_all(b"\n").map_err(io(path))?;
        file.sync_data().map_err(io(path))?;
    } else if tail.torn() {
        file.set_len(tail.complete as u64).map_err(io(path))?;
        file.sync_data().map_err(io(path))?;
    }
    file.seek(SeekFrom::End(0)).map_err(io(path))?;
    Ok((file, duplicate_bytes))
}

/// Writes the duplicate lines to [`duplicates_path`] and returns the journal's bytes up to
/// `text_end` without them, ending in a newline.
fn set_duplicates_aside(
    path: &Path,
    bytes: &[u8],
    text_end: usize,
    duplicate_ranges: &[Range<usize>],
) -> Result<Vec<u8>, JournalError> {
    // Set aside first: if the rewrite fails, the journal is unchanged and the side file
    // holds copies, never the only ones.
    let mut aside = Vec::new();
    let mut kept = Vec::with_capacity(text_end);
    let mut from = 0;
    for r in duplicate_ranges {
        kept.extend_from_slice(&bytes[from..r.start]);
        aside.extend_from_slice(&bytes[r.clone()]);
        if !aside.ends_with(b"\n") {
            aside.push(b'\n');
        }
        from = r.end;
    }
    kept.extend_from_slice(&bytes[from..text_end]);
    if !kept.ends_with(b"\n") {
        kept.push(b'\n');
    }
    keep_aside(&duplicates_path(path), &aside)?;
    Ok(kept)
}
