//! How keeping a journal fails, each with the file and what to do.

use std::path::{Path, PathBuf};

use metamer_color::text::{echo, echo_message};

use crate::output::OutputError;

/// The journal could not be written, read or resumed.
#[derive(Debug, thiserror::Error)]
pub enum JournalError {
    /// A new session was asked for where one already is.
    #[error("{} exists with {entries} entries of an earlier session: resume that session, or choose another output directory", path.display())]
    Exists { path: PathBuf, entries: usize },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}, line {line}: {}", path.display(), echo_message(message))]
    Bad {
        path: PathBuf,
        line: usize,
        message: String,
    },
    /// The journal belongs to a plan made from other options.
    #[error("{} was written by another session: its option {} is {}, this one's is {}; resume with the options it was started with, or choose another output directory", path.display(), echo(option), echo(logged), echo(now))]
    OptionDiffers {
        path: PathBuf,
        option: String,
        logged: String,
        now: String,
    },
    /// The same options, yet other steps: the program that plans them changed.
    #[error("{} was written by another session: every option is the same but its steps differ (plan {}, this one {now}); it was planned by another version of this program", path.display(), echo(logged))]
    StepsDiffer {
        path: PathBuf,
        logged: String,
        now: String,
    },
    /// The file holds no session to continue: empty, or its header was cut off by a crash
    /// while it was being written. Nothing was measured into it.
    #[error("{} holds no session to continue: {what}; resuming sets it aside and starts afresh", path.display())]
    Broken { path: PathBuf, what: String },
    #[error("{} was written by a {} session, not a {now} session", path.display(), echo(logged))]
    KindDiffers {
        path: PathBuf,
        logged: String,
        now: String,
    },
    /// An entry whose reading no instrument gave (edited or damaged).
    #[error("{}, line {line}: {message}", path.display())]
    Entry {
        path: PathBuf,
        line: usize,
        message: String,
    },
    /// Something other than a journal stands where it should be (a FIFO, a device, a
    /// directory, a dangling link).
    #[error(transparent)]
    NotAJournal(#[from] OutputError),
    /// Another session holds the journal's lock.
    #[error("{} is in use by another session, a metamer process measuring into it now: wait for it to end (or stop it), then resume; two sessions on one journal would take the same steps twice", path.display())]
    InUse { path: PathBuf },
}

pub(super) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> JournalError + '_ {
    move |source| JournalError::Io {
        path: path.to_path_buf(),
        source,
    }
}
