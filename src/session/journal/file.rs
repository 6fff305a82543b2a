//! The journal's file: its lock, opening it checked and locked, reading it bounded, and
//! rewriting it without losing the lock.

use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::Path;

use super::error::{io, JournalError};
use crate::output::owned_file;

/// Takes the journal's advisory lock without waiting: held until the file is closed (the
/// process's end included, however it ends).
pub(super) fn lock(file: &File, path: &Path) -> Result<(), JournalError> {
    use std::os::unix::io::AsRawFd;
    // SAFETY: flock on a descriptor `file` owns, with integer flags only.
    let rc = unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) };
    if rc == 0 {
        return Ok(());
    }
    let e = std::io::Error::last_os_error();
    if e.raw_os_error() == Some(libc::EWOULDBLOCK) {
        Err(JournalError::InUse {
            path: path.to_path_buf(),
        })
    } else {
        Err(io(path)(e))
    }
}

/// Whether `path` still names the file `file` has open (another session may have renamed
/// it aside between the open and the lock).
fn still_at(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

/// Opens the existing journal at `path` for reading and appending, locked: checks first
/// that a regular file stands there (a FIFO would block the open for ever).
pub(super) fn open_locked(path: &Path) -> Result<File, JournalError> {
    for _ in 0..3 {
        owned_file(path)?;
        let file = OpenOptions::new()
            .read(true)
            .append(true)
            .open(path)
            .map_err(io(path))?;
        lock(&file, path)?;
        if still_at(&file, path) {
            return Ok(file);
        }
    }
    Err(JournalError::InUse {
        path: path.to_path_buf(),
    })
}

/// The bytes of an open journal, at most the size every reader of text takes.
pub(super) fn read_all(mut file: &File, path: &Path) -> Result<Vec<u8>, JournalError> {
    let limit = metamer_color::text::MAX_INPUT_BYTES;
    let mut bytes = Vec::new();
    file.seek(SeekFrom::Start(0)).map_err(io(path))?;
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(io(path))?;
    if bytes.len() as u64 > limit {
        return Err(io(path)(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "more than {} MB, larger than any journal a session writes",
                limit >> 20
            ),
        )));
    }
    Ok(bytes)
}

/// Appends `bytes` to the side file `side`, synced.
pub(super) fn keep_aside(side: &Path, bytes: &[u8]) -> Result<(), JournalError> {
    let mut f = OpenOptions::new()
        .create(true)
        .append(true)
        .open(side)
        .map_err(io(side))?;
    f.write_all(bytes)
        .and_then(|()| f.sync_data())
        .map_err(io(side))
}

/// Replaces the journal at `path` by `bytes`: a locked temporary sibling, synced and
/// renamed over it, so a crash leaves the old journal or the new one and no other session
/// can take the new file between the rename and the lock.
pub(super) fn rewrite(path: &Path, old: &File, bytes: &[u8]) -> Result<File, JournalError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let temp = path.with_file_name(format!(".{name}.{}.rewrite", std::process::id()));
    let _ = std::fs::remove_file(&temp);
    let mut file = OpenOptions::new()
        .read(true)
        .append(true)
        .create_new(true)
        .open(&temp)
        .map_err(io(&temp))?;
    let written = lock(&file, &temp)
        .and_then(|()| {
            if let Ok(m) = old.metadata() {
                file.set_permissions(m.permissions()).map_err(io(&temp))?;
            }
            file.write_all(bytes)
                .and_then(|()| file.sync_all())
                .map_err(io(&temp))
        })
        .and_then(|()| std::fs::rename(&temp, path).map_err(io(path)));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&temp);
        return Err(e);
    }
    sync_dir(path)?;
    Ok(file)
}

/// Makes a new file's directory entry durable too (POSIX: fsync of the file alone does
/// not guarantee its name survives a crash).
pub(super) fn sync_dir(path: &Path) -> Result<(), JournalError> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    File::open(dir).and_then(|d| d.sync_all()).map_err(io(dir))
}
