//! Other programs the tests compare metamer with (oracles: ArgyllCMS, LittleCMS,
//! colour-science, Mitsuba 3, Chromium, …) and the programs some tests drive (Xvfb, tmux,
//! pyserial). Every such test asks [`Oracle::find`] first: it probes the program *and what
//! it needs* (a Python module's imports, not only `python3`) and, where anything is
//! missing, the test is skipped with the reason and the install command, unless
//! `METAMER_ORACLES=required` (CI sets it after installing them all), when it fails with
//! that reason. A missing oracle is never taken for a wrong answer, nor the reverse.

use std::collections::HashMap;
use std::ffi::{OsStr, OsString};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::{Mutex, OnceLock};

/// An external program a test needs, and how to tell that it works here.
#[derive(Debug)]
pub struct Oracle {
    /// What it is, in the skip message: "Mitsuba 3 with numpy".
    pub name: &'static str,
    /// Programs to try in order, by name on PATH or by absolute path; the first that is
    /// there and passes the probe is the one the test runs.
    pub programs: &'static [&'static str],
    /// Arguments that make the program exit 0 only when it and everything the test uses
    /// of it work (for Python, the imports); empty when being on PATH is enough.
    pub probe: &'static [&'static str],
    /// How to install it (what `.ci/run` does).
    pub install: &'static str,
}

/// Mitsuba 3's Python module, in the variant the export tests render with.
pub const MITSUBA: Oracle = Oracle {
    name: "Mitsuba 3",
    programs: &["python3"],
    probe: &[
        "-c",
        "import mitsuba as mi; mi.set_variant('scalar_spectral')",
    ],
    install: "python3 -m pip install mitsuba==3.9.1",
};

/// Mitsuba 3 and numpy, for a script that reads the rendered pixels as an array.
pub const MITSUBA_NUMPY: Oracle = Oracle {
    name: "Mitsuba 3 with numpy",
    programs: &["python3"],
    probe: &[
        "-c",
        "import numpy; import mitsuba as mi; mi.set_variant('scalar_spectral')",
    ],
    install: "python3 -m pip install mitsuba==3.9.1 numpy",
};

/// Blender 4.2 as a Python module, with Cycles (the export's script renders on the CPU).
pub const BLENDER: Oracle = Oracle {
    name: "Blender (bpy) with Cycles",
    programs: &["python3"],
    probe: &[
        "-c",
        "import bpy; assert 'cycles' in bpy.context.preferences.addons or bpy.ops.preferences.addon_enable(module='cycles')",
    ],
    install: "python3 -m pip install bpy==4.2.23",
};

/// colour-science, with the modules its comparison script imports.
pub const COLOUR_SCIENCE: Oracle = Oracle {
    name: "colour-science",
    programs: &["python3"],
    probe: &["-c", "import json, warnings; import colour"],
    install: "python3 -m pip install colour-science==0.4.7",
};

/// A Python with pyserial. Debian's python3-serial installs into the system Python, which
/// need not be the first `python3` on PATH (pyenv, virtual environments).
pub const PYSERIAL: Oracle = Oracle {
    name: "pyserial",
    programs: &["python3", "/usr/bin/python3"],
    probe: &["-c", "import serial"],
    install: "apt-get install python3-serial",
};

/// LittleCMS's `transicc`.
pub const TRANSICC: Oracle = Oracle {
    name: "LittleCMS transicc",
    programs: &["transicc"],
    probe: &[],
    install: "apt-get install liblcms2-utils",
};

/// ArgyllCMS's `iccdump`.
pub const ICCDUMP: Oracle = Oracle {
    name: "ArgyllCMS iccdump",
    programs: &["iccdump"],
    probe: &[],
    install: "apt-get install argyll",
};

/// ArgyllCMS's `xicclu`.
pub const XICCLU: Oracle = Oracle {
    name: "ArgyllCMS xicclu",
    programs: &["xicclu"],
    probe: &[],
    install: "apt-get install argyll",
};

/// ArgyllCMS's `colprof`.
pub const COLPROF: Oracle = Oracle {
    name: "ArgyllCMS colprof",
    programs: &["colprof"],
    probe: &[],
    install: "apt-get install argyll",
};

/// Headless Chromium, under any of its usual names.
pub const CHROMIUM: Oracle = Oracle {
    name: "Chromium",
    programs: &["chromium", "chromium-browser", "google-chrome"],
    probe: &[],
    install: "apt-get install chromium",
};

/// poppler's `pdfinfo`.
pub const PDFINFO: Oracle = Oracle {
    name: "poppler pdfinfo",
    programs: &["pdfinfo"],
    probe: &[],
    install: "apt-get install poppler-utils",
};

/// poppler's `pdftotext`.
pub const PDFTOTEXT: Oracle = Oracle {
    name: "poppler pdftotext",
    programs: &["pdftotext"],
    probe: &[],
    install: "apt-get install poppler-utils",
};

/// poppler's `pdftoppm`.
pub const PDFTOPPM: Oracle = Oracle {
    name: "poppler pdftoppm",
    programs: &["pdftoppm"],
    probe: &[],
    install: "apt-get install poppler-utils",
};

/// tmux, to drive a session as an operator at a terminal.
pub const TMUX: Oracle = Oracle {
    name: "tmux",
    programs: &["tmux"],
    probe: &["-V"],
    install: "apt-get install tmux",
};

/// The X virtual framebuffer, for the full-screen window.
pub const XVFB: Oracle = Oracle {
    name: "Xvfb",
    programs: &["Xvfb"],
    probe: &[],
    install: "apt-get install xvfb xauth",
};

/// True when `METAMER_ORACLES=required`: a missing oracle then fails its test.
pub fn required() -> bool {
    std::env::var("METAMER_ORACLES").as_deref() == Ok("required")
}

impl Oracle {
    /// The program to run, once per process probed. None, after printing "skipped: …" with
    /// the reason, when it or something it needs is missing; a panic with that reason
    /// instead when `METAMER_ORACLES=required`.
    #[track_caller]
    pub fn find(&self) -> Option<PathBuf> {
        static FOUND: OnceLock<Mutex<HashMap<&'static str, Result<PathBuf, String>>>> =
            OnceLock::new();
        let found = {
            let mut cache = FOUND.get_or_init(Default::default).lock().unwrap();
            cache
                .entry(self.name)
                .or_insert_with(|| self.probe(&[]))
                .clone()
        };
        self.decide(found, required())
            .unwrap_or_else(|message| panic!("{message}"))
    }

    /// Probes the oracle with `env` added to this process's environment (a variable set to
    /// an empty value is removed): the first program of [`Oracle::programs`] that is on the
    /// PATH the child would see and passes the probe, or why none does.
    pub fn probe(&self, env: &[(&str, &OsStr)]) -> Result<PathBuf, String> {
        let path = env
            .iter()
            .find(|(k, _)| *k == "PATH")
            .map(|(_, v)| v.to_os_string())
            .or_else(|| std::env::var_os("PATH"))
            .unwrap_or_default();
        let mut reasons = Vec::new();
        for program in self.programs {
            let Some(exe) = locate(program, &path) else {
                reasons.push(format!("`{program}` is not on PATH"));
                continue;
            };
            if self.probe.is_empty() {
                return Ok(exe);
            }
            let mut command = Command::new(&exe);
            command
                .args(self.probe)
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::piped());
            for (k, v) in env {
                if v.is_empty() {
                    command.env_remove(k);
                } else {
                    command.env(k, v);
                }
            }
            match command.output() {
                Ok(o) if o.status.success() => return Ok(exe),
                Ok(o) => {
                    let err = String::from_utf8_lossy(&o.stderr);
                    let last = err.lines().rev().find(|l| !l.trim().is_empty());
                    reasons.push(format!(
                        "`{} {}` failed ({}): {}",
                        exe.display(),
                        shell_words(self.probe),
                        o.status,
                        last.unwrap_or("no message")
                    ));
                }
                Err(e) => reasons.push(format!("`{}` does not run: {e}", exe.display())),
            }
        }
        Err(reasons.join("; "))
    }

    /// What [`Oracle::find`] does with a probe's result: the program, a skip (None, with
    /// the reason printed), or, when the oracle is required, the failure's message.
    pub fn decide(
        &self,
        probed: Result<PathBuf, String>,
        required: bool,
    ) -> Result<Option<PathBuf>, String> {
        match probed {
            Ok(exe) => Ok(Some(exe)),
            Err(why) => {
                let message = format!(
                    "{} is missing: {why} (install: {}; .ci/run installs it)",
                    self.name, self.install
                );
                if required {
                    return Err(format!("METAMER_ORACLES=required but {message}"));
                }
                eprintln!("skipped: {message}");
                Ok(None)
            }
        }
    }
}

/// `program` as a file: itself when it is a path, else the first match on `path`.
fn locate(program: &str, path: &OsString) -> Option<PathBuf> {
    if program.contains('/') {
        return Path::new(program).is_file().then(|| PathBuf::from(program));
    }
    std::env::split_paths(path)
        .map(|d| d.join(program))
        .find(|p| p.is_file())
}

fn shell_words(args: &[&str]) -> String {
    args.iter()
        .map(|a| {
            if a.contains('\'') {
                format!("\"{a}\"")
            } else if a.contains(' ') || a.contains(';') {
                format!("'{a}'")
            } else {
                a.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}
