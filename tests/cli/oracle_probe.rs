//! The oracle probe (`support::oracle`) every test that runs another program calls: it must
//! find a program only where it and its imports work, say why otherwise, skip when not
//! required and fail when `METAMER_ORACLES=required`. Each case builds the missing piece
//! itself — an empty PATH, a PYTHONPATH whose module shadows one the probe imports, a
//! program that exits non-zero — so none depends on what this machine has installed.
#![cfg(unix)]

use std::ffi::OsStr;
use std::os::unix::fs::PermissionsExt;
use std::path::Path;

use crate::support::fresh_dir;
use crate::support::oracle::{Oracle, MITSUBA_NUMPY};

/// An executable shell script `name` in `dir` that prints `err` on stderr and exits `code`.
fn script(dir: &Path, name: &str, err: &str, code: i32) {
    let path = dir.join(name);
    std::fs::write(&path, format!("#!/bin/sh\necho '{err}' >&2\nexit {code}\n")).unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
}

const FAKE: Oracle = Oracle {
    name: "the fake oracle",
    programs: &["metamer-fake-oracle"],
    probe: &["--probe"],
    install: "nothing to install",
};

#[test]
fn a_program_off_path_is_missing_with_its_name() {
    let empty = fresh_dir("empty-path");
    let why = MITSUBA_NUMPY
        .probe(&[("PATH", empty.as_os_str())])
        .unwrap_err();
    assert_eq!(why, "`python3` is not on PATH");
    // Not required: skipped (None); required: a failure naming the oracle, why and how to
    // install it.
    assert_eq!(MITSUBA_NUMPY.decide(Err(why.clone()), false), Ok(None));
    assert_eq!(
        MITSUBA_NUMPY.decide(Err(why), true).unwrap_err(),
        "METAMER_ORACLES=required but Mitsuba 3 with numpy is missing: `python3` is not on \
         PATH (install: python3 -m pip install mitsuba==3.9.1 numpy; .ci/run installs it)"
    );
}

#[test]
fn a_program_that_fails_its_probe_is_missing_with_its_last_error_line() {
    let dir = fresh_dir("fake-oracle");
    script(
        &dir,
        "metamer-fake-oracle",
        "fake: the library it needs is gone",
        3,
    );
    let why = FAKE.probe(&[("PATH", dir.as_os_str())]).unwrap_err();
    let exe = dir.join("metamer-fake-oracle");
    assert_eq!(
        why,
        format!(
            "`{} --probe` failed (exit status: 3): fake: the library it needs is gone",
            exe.display()
        )
    );
    // The same program passing its probe is found, at its full path.
    script(&dir, "metamer-fake-oracle", "", 0);
    assert_eq!(FAKE.probe(&[("PATH", dir.as_os_str())]), Ok(exe.clone()));
    assert_eq!(FAKE.decide(Ok(exe.clone()), true), Ok(Some(exe)));
}

#[test]
fn a_python_whose_import_is_hidden_is_missing_with_the_import_error() {
    // python3 itself must be there for this case; where it is not, the probe's reason
    // says so and the case above covers it.
    let Ok(python) = (Oracle {
        name: "python3",
        programs: &["python3"],
        probe: &["-c", "import json"],
        install: "apt-get install python3",
    })
    .probe(&[]) else {
        eprintln!("skipped: no python3 on PATH");
        return;
    };
    // A module of the same name earlier on sys.path hides the installed one, as a missing
    // package would.
    let shadow = fresh_dir("hidden-numpy");
    std::fs::write(
        shadow.join("numpy.py"),
        "raise ImportError('numpy hidden by the oracle test')\n",
    )
    .unwrap();
    let why = MITSUBA_NUMPY
        .probe(&[("PYTHONPATH", shadow.as_os_str())])
        .unwrap_err();
    assert!(
        why.starts_with(&format!("`{} -c ", python.display()))
            && why.ends_with("ImportError: numpy hidden by the oracle test"),
        "{why}"
    );
    // A variable given empty is removed from the child's environment, not set empty.
    let json = Oracle {
        name: "python3 json",
        programs: &["python3"],
        probe: &["-c", "import os, sys; sys.exit('PYTHONPATH' in os.environ)"],
        install: "",
    };
    assert!(json
        .probe(&[("PYTHONPATH", OsStr::new(""))])
        .is_ok_and(|p| p == python));
}
