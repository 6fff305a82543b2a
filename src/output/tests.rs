use super::*;

/// A fresh directory per test, removed at the end.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Self {
        let dir =
            std::env::temp_dir().join(format!("metamer-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }
    fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
    /// Every file in the directory, sorted: what a failed write must leave unchanged.
    fn listing(&self) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(&self.0)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[test]
fn writes_a_new_file_and_leaves_no_temporary() {
    let s = Scratch::new("new");
    let out = s.path("a.json");
    OutputPolicy::new(false).write(&out, b"hello").unwrap();
    assert_eq!(std::fs::read(&out).unwrap(), b"hello");
    assert_eq!(s.listing(), ["a.json"]);
}

#[test]
fn refuses_an_existing_file_unless_forced() {
    let s = Scratch::new("exists");
    let out = s.path("a.json");
    std::fs::write(&out, "old").unwrap();
    let e = OutputPolicy::new(false).write(&out, b"new").unwrap_err();
    assert!(e.needs_force(), "{e}");
    assert!(e.to_string().contains("a.json"), "{e}");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "old");
    OutputPolicy::new(true).write(&out, b"new").unwrap();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "new");
    assert_eq!(s.listing(), ["a.json"]);
}

#[test]
fn refuses_an_input_by_any_name_even_when_forced() {
    let s = Scratch::new("input");
    let input = s.path("m.csv");
    std::fs::write(&input, "data").unwrap();
    std::fs::create_dir(s.path("sub")).unwrap();
    std::os::unix::fs::symlink(&input, s.path("link.csv")).unwrap();
    std::fs::hard_link(&input, s.path("hard.csv")).unwrap();
    let mut p = OutputPolicy::new(true);
    p.input(&input);
    for out in [
        input.clone(),
        s.path("sub/../m.csv"),
        s.path("./m.csv"),
        s.path("link.csv"),
        s.path("hard.csv"),
    ] {
        let e = p.write(&out, b"x").unwrap_err();
        match &e {
            OutputError::IsInput { output, input: i } => {
                assert_eq!(output, &out);
                assert_eq!(i, &input);
            }
            other => panic!("{out:?}: {other}"),
        }
        let msg = e.to_string();
        assert!(msg.contains(&*out.to_string_lossy()), "{msg}");
        assert!(msg.contains(&*input.to_string_lossy()), "{msg}");
    }
    assert_eq!(std::fs::read_to_string(&input).unwrap(), "data");
}

#[test]
fn an_input_that_does_not_exist_yet_is_still_protected() {
    let s = Scratch::new("missing-input");
    let mut p = OutputPolicy::new(true);
    p.input(&s.path("later.csv"));
    assert!(matches!(
        p.check(&s.path("later.csv")),
        Err(OutputError::IsInput { .. })
    ));
    p.check(&s.path("other.csv")).unwrap();
}

#[test]
fn follows_a_symlink_and_keeps_it() {
    let s = Scratch::new("symlink");
    std::fs::create_dir(s.path("data")).unwrap();
    let real = s.path("data/profile.json");
    std::fs::write(&real, "old").unwrap();
    let link = s.path("out.json");
    std::os::unix::fs::symlink("data/profile.json", &link).unwrap();
    OutputPolicy::new(true).write(&link, b"new").unwrap();
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(std::fs::read_to_string(&real).unwrap(), "new");
    assert_eq!(s.listing(), ["data", "out.json"]);
    assert_eq!(
        std::fs::read_dir(s.path("data")).unwrap().count(),
        1,
        "no temporary beside the real file"
    );
    // An existing file behind a link still needs force.
    let e = OutputPolicy::new(false).write(&link, b"x").unwrap_err();
    assert!(e.needs_force(), "{e}");
}

#[test]
fn a_dangling_symlink_names_the_file_to_create() {
    let s = Scratch::new("dangling");
    let link = s.path("out.json");
    std::os::unix::fs::symlink("made.json", &link).unwrap();
    OutputPolicy::new(false).write(&link, b"made").unwrap();
    assert_eq!(
        std::fs::read_to_string(s.path("made.json")).unwrap(),
        "made"
    );
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
}

#[test]
fn a_symlink_loop_is_an_error_not_a_hang() {
    let s = Scratch::new("loop");
    std::os::unix::fs::symlink("b", s.path("a")).unwrap();
    std::os::unix::fs::symlink("a", s.path("b")).unwrap();
    let e = OutputPolicy::new(true)
        .write(&s.path("a"), b"x")
        .unwrap_err();
    assert!(matches!(e, OutputError::SymlinkLoop { .. }), "{e}");
}

#[test]
fn a_character_device_is_written_in_place_and_survives() {
    // /dev/null is a character device on every Unix: a rename-style write would replace it
    // by a regular file (as root) or fail (as a user).
    let null = Path::new("/dev/null");
    OutputPolicy::new(false).write(null, b"discarded").unwrap();
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::metadata(null)
        .unwrap()
        .file_type()
        .is_char_device());
}

#[test]
fn a_full_device_reports_the_error() {
    // /dev/full answers every write with ENOSPC: the error must surface, not be swallowed.
    let e = OutputPolicy::new(false)
        .write(Path::new("/dev/full"), &[0u8; 100_000])
        .unwrap_err();
    match e {
        OutputError::Io { source, .. } => {
            assert_eq!(source.raw_os_error(), Some(libc::ENOSPC), "{source}")
        }
        other => panic!("{other}"),
    }
}

#[test]
fn a_fifo_is_written_in_place() {
    let s = Scratch::new("fifo");
    let fifo = s.path("pipe");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path; mkfifo only creates a node.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read(&fifo).unwrap())
    };
    OutputPolicy::new(false).write(&fifo, b"through").unwrap();
    assert_eq!(reader.join().unwrap(), b"through");
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
}

#[test]
fn a_directory_or_missing_directory_is_refused_clearly() {
    let s = Scratch::new("dirs");
    let e = OutputPolicy::new(true).check(&s.0).unwrap_err();
    assert!(matches!(e, OutputError::IsDirectory { .. }), "{e}");
    let e = OutputPolicy::new(true)
        .check(&s.path("nope/a.json"))
        .unwrap_err();
    assert!(matches!(e, OutputError::NoDirectory { .. }), "{e}");
    assert!(e.to_string().contains("nope"), "{e}");
}

#[test]
fn a_failing_writer_leaves_the_old_file_and_no_temporary() {
    let s = Scratch::new("fail");
    let out = s.path("image.png");
    std::fs::write(&out, "the old image").unwrap();
    // Enough bytes that some reach the temporary file before the failure, as on a disk
    // that fills up halfway.
    let e = OutputPolicy::new(true)
        .write_with(&out, |w| {
            w.write_all(&[7u8; 100_000])?;
            Err(io::Error::from_raw_os_error(libc::ENOSPC))
        })
        .unwrap_err();
    assert!(matches!(e, OutputError::Io { .. }), "{e}");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "the old image");
    assert_eq!(s.listing(), ["image.png"]);
}

#[test]
fn replacing_keeps_the_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let s = Scratch::new("perm");
    let out = s.path("p.json");
    std::fs::write(&out, "old").unwrap();
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o640)).unwrap();
    OutputPolicy::new(true).write(&out, b"new").unwrap();
    let mode = std::fs::metadata(&out).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o640);
}

#[test]
fn dir_creates_or_accepts_and_refuses_a_file() {
    let s = Scratch::new("outdir");
    let d = s.path("a/b");
    OutputPolicy::new(false).dir(&d).unwrap();
    assert!(d.is_dir());
    OutputPolicy::new(false).dir(&d).unwrap();
    std::fs::write(s.path("f"), "x").unwrap();
    let e = OutputPolicy::new(false).dir(&s.path("f")).unwrap_err();
    assert!(matches!(e, OutputError::NotADirectory { .. }), "{e}");
}

/// A real full disk: a 64 KiB tmpfs, where the write fails with ENOSPC part-way. Mounting
/// needs root; elsewhere the injected failure above covers the same path.
#[test]
fn a_full_disk_leaves_nothing_behind() {
    // SAFETY: geteuid has no preconditions.
    if unsafe { libc::geteuid() } != 0 {
        return;
    }
    let s = Scratch::new("tmpfs");
    let mnt = s.path("mnt");
    std::fs::create_dir(&mnt).unwrap();
    let ok = std::process::Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=64k", "tmpfs"])
        .arg(&mnt)
        .status()
        .map(|st| st.success())
        .unwrap_or(false);
    if !ok {
        return;
    }
    let out = mnt.join("big.bin");
    std::fs::write(&out, "old").unwrap();
    let r = OutputPolicy::new(true).write(&out, &vec![1u8; 1 << 20]);
    let left: Vec<_> = std::fs::read_dir(&mnt)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    let old = std::fs::read_to_string(&out);
    let _ = std::process::Command::new("umount").arg(&mnt).status();
    let e = r.unwrap_err();
    match &e {
        OutputError::Io { source, .. } => {
            assert_eq!(source.raw_os_error(), Some(libc::ENOSPC), "{e}")
        }
        other => panic!("{other}"),
    }
    assert_eq!(left, ["big.bin"]);
    assert_eq!(old.unwrap(), "old");
}

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(path.as_os_str().as_encoded_bytes()).unwrap();
    // SAFETY: a NUL-terminated path and a mode.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0);
}

/// A FIFO that nothing reads made `open` wait for ever: it is an error once the reader
/// has had its time; a reader that comes late within it gets the bytes.
#[test]
fn a_fifo_without_a_reader_is_an_error_and_a_late_reader_gets_the_bytes() {
    let s = Scratch::new("fifo-reader");
    let fifo = s.path("out.json");
    mkfifo(&fifo);
    let start = std::time::Instant::now();
    let e = OutputPolicy::new(false).write(&fifo, b"x").unwrap_err();
    let took = start.elapsed();
    assert!(matches!(e, OutputError::NoReader { .. }), "{e}");
    assert!(e.to_string().contains("that nothing is reading"), "{e}");
    assert!(
        took >= FIFO_READER_WAIT && took < FIFO_READER_WAIT * 3,
        "{took:?}"
    );
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            std::thread::sleep(std::time::Duration::from_millis(300));
            std::fs::read(&fifo).unwrap()
        })
    };
    OutputPolicy::new(false).write(&fifo, b"hello").unwrap();
    assert_eq!(reader.join().unwrap(), b"hello");
}

/// What may stand where a command keeps a file it reads back: nothing or a regular file
/// (through a link); each other kind is named.
#[test]
fn an_owned_file_must_be_absent_or_a_regular_file() {
    let s = Scratch::new("owned");
    assert_eq!(owned_file(&s.path("none")).unwrap(), Owned::Absent);
    std::fs::write(s.path("file"), "x").unwrap();
    assert_eq!(owned_file(&s.path("file")).unwrap(), Owned::File);
    std::os::unix::fs::symlink(s.path("file"), s.path("link")).unwrap();
    assert_eq!(owned_file(&s.path("link")).unwrap(), Owned::File);
    mkfifo(&s.path("fifo"));
    std::fs::create_dir(s.path("dir")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", s.path("zero")).unwrap();
    std::os::unix::fs::symlink(s.path("gone"), s.path("dangling")).unwrap();
    for (name, words) in [
        (
            "fifo",
            "is a named pipe (FIFO), not a file this program wrote",
        ),
        ("dir", "is a directory"),
        ("zero", "is a character device"),
        ("dangling", "is a symbolic link to"),
    ] {
        let e = owned_file(&s.path(name)).unwrap_err().to_string();
        assert!(e.contains(words) && e.contains(name), "{name}: {e}");
    }
}

/// Inputs guarded for the process are refused by a policy that never registered them,
/// until the guard is dropped.
#[test]
fn guarded_inputs_are_refused_by_every_policy_while_the_guard_lives() {
    let s = Scratch::new("guard");
    let given = s.path("spots.csv");
    std::fs::write(&given, "given").unwrap();
    let guard = guard_inputs([given.as_path()]);
    let e = OutputPolicy::new(true).write(&given, b"x").unwrap_err();
    assert!(matches!(e, OutputError::IsInput { .. }), "{e}");
    assert_eq!(std::fs::read_to_string(&given).unwrap(), "given");
    drop(guard);
    OutputPolicy::new(true).write(&given, b"x").unwrap();
    assert_eq!(std::fs::read_to_string(&given).unwrap(), "x");
}
