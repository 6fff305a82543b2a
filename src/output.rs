//! One policy for every file a command writes.
//!
//! A command registers the files it reads ([`OutputPolicy::input`]) and then writes each
//! output through the policy. The rules:
//!
//! * **Atomic.** A regular file is written to a temporary sibling in the target's own
//!   directory, flushed, fsynced and renamed over the target, so a reader (or a crash) sees
//!   the old file or the whole new one, never half of it. On any error — a writer that
//!   fails, a full disk, a failed rename — the temporary file is removed.
//! * **Symlinks are followed.** Writing `out.json → data/profile.json` replaces
//!   `data/profile.json` and keeps the link (a rename onto the link itself would replace the
//!   link by a regular file).
//! * **Devices and FIFOs are written in place.** `-o /dev/stdout`, `/dev/null` or a named
//!   pipe get the bytes directly (a rename would replace the device node by a file, which
//!   is what a careless `rename` does to `/dev/null` as root). Writing in place is not
//!   atomic, and nothing else is possible for a stream. A block device is refused: no
//!   command's output is a disk image.
//!   A FIFO waits for its reader at most [`FIFO_READER_WAIT`]: one that nothing reads is
//!   an error, not a command that hangs in `open`.
//! * **Never onto an input.** An output that is one of the command's inputs — same canonical
//!   path, or same device and inode (hard links, bind mounts) — is refused, naming both.
//!   Inputs registered with [`guard_inputs`] are refused by every policy of the process
//!   while the guard lives: a command whose outputs are written by many parts (the
//!   experiment's stages) registers a user's files once.
//! * **Never onto an existing file unless forced.** `force` is the command's `--force` (or
//!   its documented resume option for the files it owns). Devices and FIFOs are streams,
//!   not files with content to lose, so they need no force.
//!
//! Files a command owns and reads back (a journal it appends to, a stage record) are
//! checked with [`owned_file`] before they are opened: a FIFO would block the read for ever
//! and a device never ends, so only a regular file (or a link to one) is read.

use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

pub mod console;

/// Why an output was not written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("refusing to write {output}: it is the input {input}")]
    IsInput { output: PathBuf, input: PathBuf },
    #[error("refusing to overwrite the existing file {path}")]
    Exists { path: PathBuf },
    #[error("cannot write {path}: it is a directory")]
    IsDirectory { path: PathBuf },
    #[error("cannot write {path}: it is a block device")]
    BlockDevice { path: PathBuf },
    #[error("cannot use {path} as an output directory: it exists and is not a directory")]
    NotADirectory { path: PathBuf },
    #[error("cannot write {path}: the directory {dir} does not exist")]
    NoDirectory { path: PathBuf, dir: PathBuf },
    #[error("cannot write {path}: too many levels of symbolic links")]
    SymlinkLoop { path: PathBuf },
    #[error("cannot write {path}: it is a named pipe (FIFO) that nothing is reading")]
    NoReader { path: PathBuf },
    /// A file the command owns (a journal, a record) is something else.
    #[error("{path} is {what}, not a file this program wrote: move it away, or choose another output directory")]
    NotAFile { path: PathBuf, what: &'static str },
    #[error("{path} is a symbolic link to {target}, which does not exist: remove the link, or point it at the file")]
    DanglingLink { path: PathBuf, target: PathBuf },
    #[error("cannot write {path}: {action}: {source}")]
    Io {
        path: PathBuf,
        action: &'static str,
        #[source]
        source: io::Error,
    },
}

impl OutputError {
    /// True for the one refusal that `--force` (or a resume option) lifts.
    pub fn needs_force(&self) -> bool {
        matches!(self, OutputError::Exists { .. })
    }
}

/// An input as registered: what the user named, and what it resolves to.
#[derive(Debug, Clone)]
struct Input {
    given: PathBuf,
    canonical: Option<PathBuf>,
    id: Option<(u64, u64)>,
}

/// What an output path resolves to once symlinks are followed.
enum Target {
    /// A regular file (existing or not) at this symlink-free path.
    File { path: PathBuf },
    /// A character device or FIFO, written in place.
    Stream,
}

/// The output rules of one command run (see the module documentation).
#[derive(Debug, Clone, Default)]
pub struct OutputPolicy {
    force: bool,
    inputs: Vec<Input>,
}

impl OutputPolicy {
    /// A policy that replaces existing files only when `force` is set.
    pub fn new(force: bool) -> Self {
        OutputPolicy {
            force,
            inputs: Vec::new(),
        }
    }

    /// Whether existing files are replaced.
    pub fn force(&self) -> bool {
        self.force
    }

    /// The same inputs with another force setting (e.g. a resume that may replace the
    /// files the interrupted run already wrote).
    pub fn with_force(&self, force: bool) -> Self {
        OutputPolicy {
            force,
            inputs: self.inputs.clone(),
        }
    }

    /// Registers a file the command reads; no output may be written onto it. A path that
    /// does not exist (yet) is remembered as given.
    pub fn input(&mut self, p: &Path) {
        self.inputs.push(Input::of(p));
    }

    /// Registers several inputs.
    pub fn inputs<'a>(&mut self, ps: impl IntoIterator<Item = &'a Path>) {
        for p in ps {
            self.input(p);
        }
    }

    /// Whether `out` may be written: not an input, not an existing file unless forced,
    /// not a directory or block device, its directory exists.
    pub fn check(&self, out: &Path) -> Result<(), OutputError> {
        self.resolve(out).map(|_| ())
    }

    /// Writes `bytes` to `out` under the policy.
    pub fn write(&self, out: &Path, bytes: &[u8]) -> Result<(), OutputError> {
        self.write_with(out, |w| w.write_all(bytes))
    }

    /// Writes what `f` produces to `out` under the policy. If `f` fails, the target is left
    /// as it was and no temporary file remains.
    pub fn write_with(
        &self,
        out: &Path,
        f: impl FnOnce(&mut dyn Write) -> io::Result<()>,
    ) -> Result<(), OutputError> {
        match self.resolve(out)? {
            Target::Stream => {
                let io_err = |action| {
                    move |source| OutputError::Io {
                        path: out.to_path_buf(),
                        action,
                        source,
                    }
                };
                let file = open_stream(out).map_err(|e| match e.raw_os_error() {
                    Some(libc::ENXIO) => OutputError::NoReader {
                        path: out.to_path_buf(),
                    },
                    _ => io_err("open")(e),
                })?;
                let mut w = BufWriter::new(file);
                f(&mut w).map_err(io_err("write"))?;
                w.flush().map_err(io_err("write"))
            }
            Target::File { path } => write_atomically(&path, f),
        }
    }

    /// Creates the output directory `dir` (and its parents) or accepts an existing one.
    /// The files inside are written through [`OutputPolicy::write`], which applies the
    /// rules to each.
    pub fn dir(&self, dir: &Path) -> Result<(), OutputError> {
        match std::fs::metadata(dir) {
            Ok(m) if m.is_dir() => Ok(()),
            Ok(_) => Err(OutputError::NotADirectory {
                path: dir.to_path_buf(),
            }),
            Err(e) if e.kind() == io::ErrorKind::NotFound => {
                std::fs::create_dir_all(dir).map_err(|source| OutputError::Io {
                    path: dir.to_path_buf(),
                    action: "create the directory",
                    source,
                })
            }
            Err(source) => Err(OutputError::Io {
                path: dir.to_path_buf(),
                action: "inspect",
                source,
            }),
        }
    }

    fn resolve(&self, out: &Path) -> Result<Target, OutputError> {
        let path = follow_links(out)?;
        let meta = match std::fs::metadata(&path) {
            Ok(m) => Some(m),
            Err(e) if e.kind() == io::ErrorKind::NotFound => None,
            Err(source) => {
                return Err(OutputError::Io {
                    path: out.to_path_buf(),
                    action: "inspect",
                    source,
                })
            }
        };
        if let Some(input) = self.input_matching(&path, meta.as_ref()) {
            return Err(OutputError::IsInput {
                output: out.to_path_buf(),
                input: input.given,
            });
        }
        let Some(meta) = meta else {
            let dir = parent_dir(&path);
            if !dir.is_dir() {
                return Err(OutputError::NoDirectory {
                    path: out.to_path_buf(),
                    dir,
                });
            }
            return Ok(Target::File { path });
        };
        let kind = kind_of(&meta);
        match kind {
            Kind::Dir => Err(OutputError::IsDirectory {
                path: out.to_path_buf(),
            }),
            Kind::Block => Err(OutputError::BlockDevice {
                path: out.to_path_buf(),
            }),
            Kind::Stream => Ok(Target::Stream),
            Kind::File if !self.force => Err(OutputError::Exists {
                path: out.to_path_buf(),
            }),
            Kind::File => Ok(Target::File { path }),
        }
    }

    fn input_matching(&self, out: &Path, meta: Option<&std::fs::Metadata>) -> Option<Input> {
        let canonical = canonical_even_if_missing(out);
        let id = meta.map(file_id);
        let matches = |i: &&Input| {
            (i.canonical.is_some() && i.canonical == canonical)
                || (i.id.is_some() && i.id == id)
                || (i.canonical.is_none() && absolute(&i.given) == absolute(out))
        };
        if let Some(i) = self.inputs.iter().find(matches) {
            return Some(i.clone());
        }
        let guarded = GUARDED.lock().unwrap_or_else(|e| e.into_inner());
        guarded.iter().map(|(_, i)| i).find(matches).cloned()
    }
}

impl Input {
    fn of(p: &Path) -> Input {
        let meta = std::fs::metadata(p).ok();
        Input {
            given: p.to_path_buf(),
            canonical: std::fs::canonicalize(p).ok(),
            id: meta.as_ref().map(file_id),
        }
    }
}

/// Inputs every policy of the process refuses to write onto, with the guard that put them
/// there.
static GUARDED: Mutex<Vec<(u64, Input)>> = Mutex::new(Vec::new());

/// While it lives, no [`OutputPolicy`] of this process writes onto the files it was made
/// with ([`guard_inputs`]).
#[must_use = "the inputs are guarded only while the guard lives"]
pub struct InputGuard {
    id: u64,
}

/// Registers `paths` as inputs of every output policy of the process until the returned
/// guard is dropped: for a command whose outputs are written by parts that each make their
/// own policy, so a user's file cannot be replaced by any of them.
pub fn guard_inputs<'a>(paths: impl IntoIterator<Item = &'a Path>) -> InputGuard {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let id = NEXT.fetch_add(1, Ordering::Relaxed);
    let mut guarded = GUARDED.lock().unwrap_or_else(|e| e.into_inner());
    guarded.extend(paths.into_iter().map(|p| (id, Input::of(p))));
    InputGuard { id }
}

impl Drop for InputGuard {
    fn drop(&mut self) {
        let mut guarded = GUARDED.lock().unwrap_or_else(|e| e.into_inner());
        guarded.retain(|(id, _)| *id != self.id);
    }
}

/// What stands at the path of a file a command owns and reads back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Owned {
    /// Nothing: the command may create it.
    Absent,
    /// A regular file, or a symbolic link to one.
    File,
}

/// Checks the path of a file the command owns (a journal it appends to, a record it
/// re-reads) as an input is checked, before anything opens it: only nothing or a regular
/// file (through links) will do. A FIFO would block the open for ever, a device never
/// ends, a directory is no file, and a dangling link would make the program create a file
/// wherever it points (or report an empty file that is not there).
pub fn owned_file(path: &Path) -> Result<Owned, OutputError> {
    match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Owned::Absent),
        Err(source) => {
            return Err(OutputError::Io {
                path: path.to_path_buf(),
                action: "inspect",
                source,
            })
        }
        Ok(_) => {}
    }
    let target = follow_links(path)?;
    let meta = match std::fs::metadata(&target) {
        Ok(m) => m,
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            return Err(OutputError::DanglingLink {
                path: path.to_path_buf(),
                target,
            })
        }
        Err(source) => {
            return Err(OutputError::Io {
                path: path.to_path_buf(),
                action: "inspect",
                source,
            })
        }
    };
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    let what = if t.is_file() {
        return Ok(Owned::File);
    } else if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a named pipe (FIFO)"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    };
    Err(OutputError::NotAFile {
        path: path.to_path_buf(),
        what,
    })
}

/// How long a FIFO output may wait for its reader: one started with the command (`cat
/// pipe &`) has opened it long before; one that never comes is an error, not a command
/// waiting in `open` for ever.
pub const FIFO_READER_WAIT: std::time::Duration = std::time::Duration::from_secs(3);

/// Opens a device or FIFO for writing. A FIFO's blocking open waits for a reader for
/// ever; opened without waiting, one that has none fails (ENXIO), which is tried again
/// for [`FIFO_READER_WAIT`]. The writes then block as a pipe's do.
fn open_stream(out: &Path) -> io::Result<File> {
    use std::os::unix::fs::OpenOptionsExt;
    use std::os::unix::io::AsRawFd;
    let start = std::time::Instant::now();
    let file = loop {
        match OpenOptions::new()
            .write(true)
            .custom_flags(libc::O_NONBLOCK)
            .open(out)
        {
            Err(e)
                if e.raw_os_error() == Some(libc::ENXIO) && start.elapsed() < FIFO_READER_WAIT =>
            {
                std::thread::sleep(std::time::Duration::from_millis(20))
            }
            r => break r?,
        }
    };
    // SAFETY: fcntl on a descriptor this function owns, with integer arguments only.
    unsafe {
        let fd = file.as_raw_fd();
        let flags = libc::fcntl(fd, libc::F_GETFL);
        if flags < 0 || libc::fcntl(fd, libc::F_SETFL, flags & !libc::O_NONBLOCK) < 0 {
            return Err(io::Error::last_os_error());
        }
    }
    Ok(file)
}

enum Kind {
    File,
    Dir,
    Block,
    Stream,
}

fn kind_of(meta: &std::fs::Metadata) -> Kind {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_dir() {
        Kind::Dir
    } else if t.is_block_device() {
        Kind::Block
    } else if t.is_char_device() || t.is_fifo() || t.is_socket() {
        Kind::Stream
    } else {
        Kind::File
    }
}

fn file_id(meta: &std::fs::Metadata) -> (u64, u64) {
    use std::os::unix::fs::MetadataExt;
    (meta.dev(), meta.ino())
}

fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

fn absolute(p: &Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}

/// The canonical path of `p`, or of its directory joined with its name when `p` does not
/// exist yet.
fn canonical_even_if_missing(p: &Path) -> Option<PathBuf> {
    std::fs::canonicalize(p).ok().or_else(|| {
        let name = p.file_name()?;
        Some(std::fs::canonicalize(parent_dir(p)).ok()?.join(name))
    })
}

/// Follows symlinks from `out` to a path that is not a link (it may not exist: a dangling
/// link names the file to create).
fn follow_links(out: &Path) -> Result<PathBuf, OutputError> {
    // The kernel's own limit on links followed in one lookup.
    const MAX_LINKS: usize = 40;
    let mut path = out.to_path_buf();
    for _ in 0..MAX_LINKS {
        match std::fs::symlink_metadata(&path) {
            Ok(m) if m.file_type().is_symlink() => {
                let to = std::fs::read_link(&path).map_err(|source| OutputError::Io {
                    path: out.to_path_buf(),
                    action: "read the symbolic link",
                    source,
                })?;
                path = if to.is_absolute() {
                    to
                } else {
                    parent_dir(&path).join(to)
                };
            }
            _ => return Ok(path),
        }
    }
    Err(OutputError::SymlinkLoop {
        path: out.to_path_buf(),
    })
}

/// A temporary sibling that is removed unless it was renamed into place.
struct TempFile {
    path: PathBuf,
    armed: bool,
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if self.armed {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

fn write_atomically(
    target: &Path,
    f: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<(), OutputError> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let dir = parent_dir(target);
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let io_err = |action| {
        move |source| OutputError::Io {
            path: target.to_path_buf(),
            action,
            source,
        }
    };
    // Hidden, and unique per process and call, so concurrent writers never share one.
    let (file, mut temp) = loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let path = dir.join(format!(".{name}.{}-{n}.tmp", std::process::id()));
        match OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(file) => break (file, TempFile { path, armed: true }),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(io_err("create a temporary file beside it")(e)),
        }
    };
    // Keep a replaced file's permissions (a profile made read-only for others stays so).
    if let Ok(old) = std::fs::metadata(target) {
        file.set_permissions(old.permissions())
            .map_err(io_err("copy permissions"))?;
    }
    let mut w = BufWriter::new(file);
    f(&mut w).map_err(io_err("write"))?;
    let file = w
        .into_inner()
        .map_err(|e| io_err("write")(e.into_error()))?;
    file.sync_all().map_err(io_err("sync"))?;
    drop(file);
    std::fs::rename(&temp.path, target).map_err(io_err("rename into place"))?;
    temp.armed = false;
    // The rename is durable once the directory is synced; a filesystem that cannot sync a
    // directory still has the file, so this is best effort.
    if let Ok(d) = File::open(&dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

#[cfg(test)]
mod tests;
