//! The process's standard output and standard error, written so that a failure is an error
//! and never a panic.
//!
//! `println!` and `eprintln!` panic when the write fails (a full disk behind `> file`,
//! `/dev/full`, a closed pipe), so a command that printed that way died with exit 101 and a
//! backtrace hint instead of an error. Every line the program prints goes through
//! [`out_fmt`] or [`err_fmt`] instead (the command line wraps them in its `outln!` and
//! `errln!` macros), which return a [`ConsoleError`] naming the stream.
//!
//! A failure is also remembered, per stream: a write from inside a library callback that
//! cannot return an error (a progress note, an event printed as it happens) is not lost,
//! because the command line asks [`failure`] before it exits and reports the first one. Once
//! a stream failed, later writes to it are not attempted: a line after a gap would be worse
//! than no line.

use std::fmt;
use std::io::{self, Write};
use std::sync::Mutex;

/// One of the two streams.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream {
    Stdout,
    Stderr,
}

impl fmt::Display for Stream {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Stream::Stdout => "standard output",
            Stream::Stderr => "standard error",
        })
    }
}

/// A write to standard output or standard error that failed.
#[derive(Debug, thiserror::Error)]
#[error("cannot write to {stream}: {source}")]
pub struct ConsoleError {
    pub stream: Stream,
    #[source]
    pub source: io::Error,
}

impl ConsoleError {
    /// The same failure again: `io::Error` is not `Clone`, so it is rebuilt from its OS
    /// error number, or its kind and text.
    fn again(&self) -> ConsoleError {
        let source = match self.source.raw_os_error() {
            Some(code) => io::Error::from_raw_os_error(code),
            None => io::Error::new(self.source.kind(), self.source.to_string()),
        };
        ConsoleError {
            stream: self.stream,
            source,
        }
    }
}

/// For callers whose callbacks return `io::Result` (e.g. `spot::run`'s events): the text
/// still names the stream.
impl From<ConsoleError> for io::Error {
    fn from(e: ConsoleError) -> io::Error {
        io::Error::new(e.source.kind(), e)
    }
}

/// The first failure of each stream: `[stdout, stderr]`.
static FAILED: Mutex<[Option<ConsoleError>; 2]> = Mutex::new([None, None]);

fn slot(stream: Stream) -> usize {
    match stream {
        Stream::Stdout => 0,
        Stream::Stderr => 1,
    }
}

fn write_to(stream: Stream, args: fmt::Arguments<'_>, newline: bool) -> Result<(), ConsoleError> {
    let mut failed = FAILED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(e) = &failed[slot(stream)] {
        return Err(e.again());
    }
    // The lock on the remembered failures also keeps two threads' lines whole.
    let result = match stream {
        Stream::Stdout => write_lines(&mut io::stdout().lock(), args, newline),
        Stream::Stderr => write_lines(&mut io::stderr().lock(), args, newline),
    };
    result.map_err(|source| {
        let e = ConsoleError { stream, source };
        failed[slot(stream)] = Some(e.again());
        e
    })
}

fn write_lines(w: &mut dyn Write, args: fmt::Arguments<'_>, newline: bool) -> io::Result<()> {
    w.write_fmt(args)?;
    if newline {
        w.write_all(b"\n")?;
    }
    Ok(())
}

/// Writes `args` and a newline to standard output.
pub fn out_fmt(args: fmt::Arguments<'_>) -> Result<(), ConsoleError> {
    write_to(Stream::Stdout, args, true)
}

/// Writes `args` to standard output, without a newline.
pub fn out_part(args: fmt::Arguments<'_>) -> Result<(), ConsoleError> {
    write_to(Stream::Stdout, args, false)
}

/// Writes `args` and a newline to standard error.
pub fn err_fmt(args: fmt::Arguments<'_>) -> Result<(), ConsoleError> {
    write_to(Stream::Stderr, args, true)
}

/// Writes `args` to standard error without a newline and flushes it (a prompt).
pub fn err_part(args: fmt::Arguments<'_>) -> Result<(), ConsoleError> {
    write_to(Stream::Stderr, args, false)?;
    flush_stream(Stream::Stderr)
}

/// For a write inside a callback that has no way to return its error: the failure is
/// already remembered, and the command reports it when it ends ([`failure`]).
pub fn reported_at_exit(_: Result<(), ConsoleError>) {}

fn flush_stream(stream: Stream) -> Result<(), ConsoleError> {
    let mut failed = FAILED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(e) = &failed[slot(stream)] {
        return Err(e.again());
    }
    let result = match stream {
        Stream::Stdout => io::stdout().lock().flush(),
        Stream::Stderr => io::stderr().lock().flush(),
    };
    result.map_err(|source| {
        let e = ConsoleError { stream, source };
        failed[slot(stream)] = Some(e.again());
        e
    })
}

/// Flushes standard output (a line without its newline is still buffered; the runtime's
/// own flush at exit drops its error).
pub fn flush() -> Result<(), ConsoleError> {
    flush_stream(Stream::Stdout)
}

/// The first write that failed, standard output's before standard error's.
pub fn failure() -> Option<ConsoleError> {
    let failed = FAILED.lock().unwrap_or_else(|e| e.into_inner());
    failed.iter().flatten().next().map(ConsoleError::again)
}
