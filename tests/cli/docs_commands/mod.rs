//! Every command block of README.md and docs/*.md, run as written, so the documents cannot
//! drift from the program. A fenced block tagged `sh` is a list of commands: each line (with
//! its `\` continuations, `#` comments removed) runs through `sh -c` in a scratch folder of
//! the block's own, where `data/`, `docs/`, `tests/` and `protocols/` are the repository's,
//! `metamer` (and `cargo run --release --`) is the built binary and
//! `METAMER_SIM_TIME_SCALE=0`. A command fails the test when it exits non-zero, and a figure
//! the prose quotes from a block's output fails it when the output does not print it.
//!
//! What a line may say that a shell would not run, and how it is read:
//! - `[...]` is optional: left out (each `--flag` in it must be in the command's `--help`);
//! - `a|b|c` (no spaces) is a choice: the first is taken;
//! - a real instrument (`cs100a:PORT`, `i1pro[:SERIAL]` after `--instrument`, `--spectral`
//!   or `--spot`) becomes the simulated one at `time_scale=0`, a `window[:N]` display
//!   (`--display`) becomes `virtual:ips-lcd`;
//! - `metamer lab -o lab-out` is the shared lab run: made once per test process and shared
//!   by every block that copies from it, since it takes a minute and a half.
//!
//! Marks, each an HTML comment on its own line just above the block (blank lines allowed):
//! - `<!-- doc-test: skip: WHY -->` — the block is not run (hardware, root, a long run);
//! - ``<!-- doc-test: skip `PREFIX`: WHY -->`` — its commands that begin with PREFIX are not
//!   (`PREFIX$`: the command that is exactly PREFIX);
//! - `<!-- doc-test: with NAME=VALUE … -->` — a placeholder's value (whole words only);
//! - `<!-- doc-test: copy PATH=FROM -->` — the scratch folder gets FROM (a path in the shared
//!   lab run `lab-out/…`, or the repository's) as PATH before the block runs;
//! - `<!-- doc-test: folder NAME -->` — blocks naming the same folder share it, in order,
//!   so one's output is the next one's input;
//! - `<!-- doc-test: name NAME -->` — the block's output (stdout and stderr) can be quoted:
//!   a number followed by `<!-- doc-figure: NAME -->` in the prose must be printed by it.
//!
//! Commands that fail for a reason another change is fixing are listed in
//! [`EXPECTED_FAILURES`]; such a command passing fails the test, so the list only shrinks.
#![cfg(unix)]

use std::collections::{BTreeMap, HashMap};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

use crate::support::{fresh_dir, root};

mod markdown;
use markdown::{contains_number, parse, runnable, skips, subcommand};

/// (document, the command as the document writes it — its beginning —, why it fails for
/// now). The lead empties this list as the fixes land.
const EXPECTED_FAILURES: &[(&str, &str, &str)] = &[];

/// The shared lab run, as the README writes it (`cargo run --release --` read as `metamer`).
const LAB_COMMAND: &str = "metamer lab -o lab-out";

/// A command that runs longer than this is killed and reported.
const TIMEOUT: Duration = Duration::from_secs(600);

/// Every document the test runs; [`every_document_is_run`] checks that none is missing.
const DOCUMENTS: &[&str] = &[
    "README.md",
    "docs/architecture.md",
    "docs/benchmarks.md",
    "docs/contributing.md",
    "docs/formats.md",
    "docs/guide.md",
    "docs/instruments.md",
    "docs/renderers.md",
    "docs/validation-box.md",
];

/// What a run of a command printed.
#[derive(Clone, Debug)]
struct Ran {
    ok: bool,
    status: String,
    stdout: String,
    stderr: String,
    seconds: f64,
}

/// A folder with `metamer` in it, linked to the built binary, for PATH.
fn bin_dir() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| {
        let dir = fresh_dir("docs-bin");
        std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_metamer"), dir.join("metamer")).unwrap();
        dir
    })
}

/// Runs `command` through `sh -c` in `dir`, its output in files (no pipe to fill), killed
/// with its process group after [`TIMEOUT`].
fn run_shell(command: &str, dir: &Path, log: &str) -> Ran {
    let path = std::env::var_os("PATH").unwrap_or_default();
    let mut paths = vec![bin_dir().to_path_buf()];
    paths.extend(std::env::split_paths(&path));
    let out = dir.join(format!(".{log}.stdout"));
    let err = dir.join(format!(".{log}.stderr"));
    let start = Instant::now();
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(command)
        .current_dir(dir)
        .env("PATH", std::env::join_paths(paths).unwrap())
        .env("METAMER_SIM_TIME_SCALE", "0")
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap())
        .process_group(0)
        .spawn()
        .expect("sh runs");
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s.to_string();
        }
        if start.elapsed() > TIMEOUT {
            // SAFETY: kills the process group this test started for the command.
            unsafe { libc::killpg(child.id() as i32, libc::SIGKILL) };
            let _ = child.wait();
            break format!("killed after {} s", TIMEOUT.as_secs());
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let read =
        |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap_or_default()).into_owned();
    Ran {
        ok: status == "exit status: 0",
        status,
        stdout: read(&out),
        stderr: read(&err),
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// The shared lab run: its folder (holding `lab-out/`) and what it printed.
fn lab() -> &'static Result<(PathBuf, Ran), String> {
    static LAB: OnceLock<Result<(PathBuf, Ran), String>> = OnceLock::new();
    LAB.get_or_init(|| {
        let dir = fresh_dir("docs-lab");
        let ran = run_shell(LAB_COMMAND, &dir, "lab");
        eprintln!("the shared lab run: {:.1} s", ran.seconds);
        if ran.ok {
            Ok((dir, ran))
        } else {
            Err(format!(
                "the shared lab run `{LAB_COMMAND}` {}: {}",
                ran.status,
                tail(&ran.stderr)
            ))
        }
    })
}

/// The last lines of a command's error output, for a failure message.
fn tail(text: &str) -> String {
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let from = lines.len().saturating_sub(6);
    lines[from..].join("\n      ")
}

/// `from` copied to `to`: a file, or a folder with everything in it.
fn copy(from: &Path, to: &Path) -> std::io::Result<()> {
    if from.is_dir() {
        std::fs::create_dir_all(to)?;
        for entry in std::fs::read_dir(from)? {
            let entry = entry?;
            copy(&entry.path(), &to.join(entry.file_name()))?;
        }
        Ok(())
    } else {
        if let Some(parent) = to.parent() {
            std::fs::create_dir_all(parent)?;
        }
        std::fs::copy(from, to).map(|_| ())
    }
}

/// `metamer SUB --help`, once per subcommand.
fn help(sub: &[String]) -> String {
    static HELP: OnceLock<Mutex<HashMap<Vec<String>, String>>> = OnceLock::new();
    let mut cache = HELP.get_or_init(Default::default).lock().unwrap();
    cache
        .entry(sub.to_vec())
        .or_insert_with(|| {
            let o = Command::new(env!("CARGO_BIN_EXE_metamer"))
                .args(sub)
                .arg("--help")
                .output()
                .unwrap();
            String::from_utf8_lossy(&o.stdout).into_owned()
        })
        .clone()
}

/// Runs every `sh` block of `doc` and checks its figures; returns the failures, one
/// message each, naming the file, line and command.
fn run_document(doc: &str) -> Vec<String> {
    let text = std::fs::read_to_string(root().join(doc)).unwrap();
    let (blocks, figures) = match parse(&text) {
        Ok(parsed) => parsed,
        Err(e) => return vec![format!("{doc}: {e}")],
    };
    let stem = doc.trim_end_matches(".md").replace('/', "-");
    let mut failures = Vec::new();
    let mut folders: BTreeMap<String, PathBuf> = BTreeMap::new();
    let mut outputs: HashMap<String, String> = HashMap::new();
    for block in &blocks {
        let at = format!("{doc}:{}", block.fence);
        if let Some(why) = &block.marks.skip {
            eprintln!("{at}: skipped: {why}");
            continue;
        }
        let dir = match &block.marks.folder {
            Some(name) => folders
                .entry(name.clone())
                .or_insert_with(|| scratch(&format!("{stem}-{name}")))
                .clone(),
            None => scratch(&format!("{stem}-{}", block.fence)),
        };
        let mut output = String::new();
        let mut prepared = true;
        for (path, from) in &block.marks.copy {
            let source = if let Some(rest) = from.strip_prefix("lab-out/") {
                match lab() {
                    Ok((lab_dir, _)) => lab_dir.join("lab-out").join(rest),
                    Err(e) => {
                        failures.push(format!("{at}: copy {path}={from}: {e}"));
                        prepared = false;
                        continue;
                    }
                }
            } else {
                root().join(from)
            };
            if let Err(e) = copy(&source, &dir.join(path)) {
                failures.push(format!(
                    "{at}: copy {path}={from}: {}: {e}",
                    source.display()
                ));
                prepared = false;
            }
        }
        if !prepared {
            continue;
        }
        for (k, line) in block.lines.iter().enumerate() {
            let where_ = format!("{doc}:{}", line.number);
            if let Some((_, why)) = block
                .marks
                .skip_prefixes
                .iter()
                .find(|(prefix, _)| skips(prefix, &line.text))
            {
                eprintln!("{where_}: skipped `{}`: {why}", line.text);
                continue;
            }
            let r = runnable(&line.text, &block.marks.with);
            if !r.command.starts_with("metamer ") && r.command != "metamer" {
                failures.push(format!(
                    "{where_}: `{}` runs another program than metamer, which this test does \
                     not run: mark its block `<!-- doc-test: skip: WHY -->`",
                    line.text
                ));
                continue;
            }
            let sub = subcommand(&r.command);
            let help_text = help(&sub);
            for flag in &r.optional_flags {
                let name = flag.split('=').next().unwrap_or(flag);
                if !help_text.contains(name) {
                    failures.push(format!(
                        "{where_}: `{}` names {name}, which `metamer {} --help` does not list",
                        line.text,
                        sub.join(" ")
                    ));
                }
            }
            let ran = if r.command == LAB_COMMAND {
                match lab() {
                    Ok((lab_dir, ran)) => {
                        let link = dir.join("lab-out");
                        if !link.exists() {
                            std::os::unix::fs::symlink(lab_dir.join("lab-out"), link).unwrap();
                        }
                        ran.clone()
                    }
                    Err(e) => {
                        failures.push(format!("{where_}: {e}"));
                        continue;
                    }
                }
            } else {
                run_shell(&r.command, &dir, &format!("{}-{k}", line.number))
            };
            eprintln!(
                "{where_}: {:.1} s {} `{}`",
                ran.seconds,
                if ran.ok { "ok" } else { "FAILED" },
                r.command
            );
            let expected = EXPECTED_FAILURES
                .iter()
                .find(|(d, prefix, _)| *d == doc && line.text.starts_with(prefix));
            match (ran.ok, expected) {
                (true, None) => {}
                (false, Some((_, _, why))) => {
                    eprintln!("{where_}: fails as expected ({why}): {}", tail(&ran.stderr))
                }
                (true, Some((_, prefix, _))) => failures.push(format!(
                    "{where_}: `{}` now runs: remove (\"{doc}\", \"{prefix}\") from \
                     EXPECTED_FAILURES in tests/cli/docs_commands.rs",
                    line.text
                )),
                (false, None) => failures.push(format!(
                    "{where_}: `{}` (run as `{}` in {}) {}:\n      {}",
                    line.text,
                    r.command,
                    dir.display(),
                    ran.status,
                    tail(&format!("{}\n{}", ran.stdout, ran.stderr))
                )),
            }
            output.push_str(&ran.stdout);
            output.push_str(&ran.stderr);
        }
        if let Some(name) = &block.marks.name {
            outputs.insert(name.clone(), output);
        }
    }
    for figure in &figures {
        let at = format!("{doc}:{}", figure.number);
        match outputs.get(&figure.block) {
            None => failures.push(format!(
                "{at}: the figure {} quotes block `{}`, which is not a named block that ran",
                figure.value, figure.block
            )),
            Some(out) if !contains_number(out, &figure.value) => failures.push(format!(
                "{at}: the figure {} is not in what block `{}` printed:\n      {}",
                figure.value,
                figure.block,
                tail(out)
            )),
            Some(_) => {}
        }
    }
    failures
}

#[track_caller]
fn scratch(tag: &str) -> PathBuf {
    let dir = fresh_dir(tag);
    for shared in ["data", "docs", "tests", "protocols"] {
        std::os::unix::fs::symlink(root().join(shared), dir.join(shared)).unwrap();
    }
    dir
}

#[track_caller]
fn check(doc: &str) {
    let failures = run_document(doc);
    assert!(
        failures.is_empty(),
        "{} of {doc}'s commands or figures differ from what the program does:\n  {}",
        failures.len(),
        failures.join("\n  ")
    );
}

#[test]
fn every_document_is_run() {
    let mut found = vec!["README.md".to_string()];
    for entry in std::fs::read_dir(root().join("docs")).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        if name.ends_with(".md") {
            found.push(format!("docs/{name}"));
        }
    }
    found.sort();
    let mut listed: Vec<String> = DOCUMENTS.iter().map(|d| d.to_string()).collect();
    listed.sort();
    assert_eq!(
        found, listed,
        "DOCUMENTS in tests/cli/docs_commands.rs lists every document"
    );
}

#[test]
fn readme_commands_run_as_written() {
    check("README.md");
}

#[test]
fn guide_commands_run_as_written() {
    check("docs/guide.md");
}

#[test]
fn renderers_commands_run_as_written() {
    check("docs/renderers.md");
}

#[test]
fn the_other_documents_commands_run_as_written() {
    let mut failures = Vec::new();
    for doc in DOCUMENTS {
        if !["README.md", "docs/guide.md", "docs/renderers.md"].contains(doc) {
            failures.extend(run_document(doc));
        }
    }
    assert!(failures.is_empty(), "\n  {}", failures.join("\n  "));
}
