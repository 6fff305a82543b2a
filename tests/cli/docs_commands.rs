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

/// One line of a block, continuations joined, its comment removed.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    /// 1-based line in the document where the command starts.
    pub number: usize,
    pub text: String,
}

/// The marks above a block.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Marks {
    pub skip: Option<String>,
    pub skip_prefixes: Vec<(String, String)>,
    pub with: Vec<(String, String)>,
    pub copy: Vec<(String, String)>,
    pub folder: Option<String>,
    pub name: Option<String>,
}

/// A fenced `sh` block.
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    /// 1-based line of its opening fence.
    pub fence: usize,
    pub marks: Marks,
    pub lines: Vec<Line>,
}

/// A figure the prose quotes from a named block's output.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    pub number: usize,
    pub value: String,
    pub block: String,
}

/// The `sh` blocks and quoted figures of a document; errors name the line.
pub fn parse(text: &str) -> Result<(Vec<Block>, Vec<Figure>), String> {
    let mut blocks = Vec::new();
    let mut figures = Vec::new();
    let mut marks = Marks::default();
    let lines: Vec<&str> = text.lines().collect();
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let trimmed = line.trim();
        if let Some(mark) = trimmed
            .strip_prefix("<!-- doc-test:")
            .and_then(|m| m.strip_suffix("-->"))
        {
            parse_mark(mark.trim(), &mut marks).map_err(|e| format!("line {}: {e}", i + 1))?;
            i += 1;
            continue;
        }
        for (at, _) in line.match_indices("<!-- doc-figure:") {
            let rest = &line[at + "<!-- doc-figure:".len()..];
            let block = rest
                .split("-->")
                .next()
                .map(str::trim)
                .filter(|b| !b.is_empty() && rest.contains("-->"))
                .ok_or_else(|| format!("line {}: a doc-figure mark names no block", i + 1))?;
            let value = last_number(&line[..at])
                .ok_or_else(|| format!("line {}: no number before the doc-figure mark", i + 1))?;
            figures.push(Figure {
                number: i + 1,
                value,
                block: block.to_string(),
            });
        }
        if let Some(lang) = trimmed.strip_prefix("```") {
            let fence = i + 1;
            let mut body = Vec::new();
            i += 1;
            while i < lines.len() && !lines[i].trim_start().starts_with("```") {
                body.push((i + 1, lines[i]));
                i += 1;
            }
            if lang.trim() == "sh" {
                blocks.push(Block {
                    fence,
                    marks: std::mem::take(&mut marks),
                    lines: join_lines(&body),
                });
            } else if marks != Marks::default() {
                return Err(format!(
                    "line {fence}: doc-test marks on a block that is not `sh`"
                ));
            }
            marks = Marks::default();
        } else if !trimmed.is_empty() && marks != Marks::default() {
            return Err(format!(
                "line {}: doc-test marks must stand just above a ```sh block",
                i + 1
            ));
        }
        i += 1;
    }
    Ok((blocks, figures))
}

fn parse_mark(mark: &str, marks: &mut Marks) -> Result<(), String> {
    let pair = |s: &str| {
        s.split_once('=')
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .filter(|(a, b)| !a.is_empty() && !b.is_empty())
            .ok_or_else(|| format!("`{s}`: expected NAME=VALUE"))
    };
    if let Some(rest) = mark.strip_prefix("skip") {
        let rest = rest.trim_start();
        if let Some(why) = rest.strip_prefix(':') {
            let why = why.trim();
            if why.is_empty() {
                return Err("skip: say why".into());
            }
            marks.skip = Some(why.to_string());
            return Ok(());
        }
        let quoted = rest
            .strip_prefix('`')
            .and_then(|r| r.split_once('`'))
            .ok_or("expected `skip: WHY` or ``skip `PREFIX`: WHY``")?;
        let why = quoted.1.trim_start().strip_prefix(':').map(str::trim);
        match why {
            Some(why) if !why.is_empty() => {
                marks
                    .skip_prefixes
                    .push((quoted.0.to_string(), why.to_string()));
                Ok(())
            }
            _ => Err(format!("skip `{}`: say why", quoted.0)),
        }
    } else if let Some(rest) = mark.strip_prefix("with ") {
        for word in rest.split_whitespace() {
            marks.with.push(pair(word)?);
        }
        Ok(())
    } else if let Some(rest) = mark.strip_prefix("copy ") {
        for word in rest.split_whitespace() {
            marks.copy.push(pair(word)?);
        }
        Ok(())
    } else if let Some(rest) = mark.strip_prefix("folder ") {
        marks.folder = Some(rest.trim().to_string());
        Ok(())
    } else if let Some(rest) = mark.strip_prefix("name ") {
        marks.name = Some(rest.trim().to_string());
        Ok(())
    } else {
        Err(format!(
            "unknown doc-test mark `{mark}` (skip, with, copy, folder, name)"
        ))
    }
}

/// The last number in `text` (digits with an optional sign and decimal point).
fn last_number(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut end = bytes.len();
    while end > 0 && !bytes[end - 1].is_ascii_digit() {
        end -= 1;
    }
    if end == 0 {
        return None;
    }
    let mut start = end;
    while start > 0 && (bytes[start - 1].is_ascii_digit() || bytes[start - 1] == b'.') {
        start -= 1;
    }
    if start > 0 && bytes[start - 1] == b'-' {
        start -= 1;
    }
    Some(text[start..end].trim_start_matches('.').to_string())
}

/// Whether a skip mark's `prefix` names `command`: its beginning, or with a final `$`
/// the whole of it.
fn skips(prefix: &str, command: &str) -> bool {
    match prefix.strip_suffix('$') {
        Some(whole) => command == whole,
        None => command.starts_with(prefix),
    }
}

/// Joins continuation lines and drops comments and blank lines.
fn join_lines(body: &[(usize, &str)]) -> Vec<Line> {
    let mut out: Vec<Line> = Vec::new();
    let mut open: Option<Line> = None;
    for &(number, raw) in body {
        let text = strip_comment(raw);
        let (text, continues) = match text.trim_end().strip_suffix('\\') {
            Some(t) => (t.to_string(), true),
            None => (text.trim_end().to_string(), false),
        };
        let line = match open.take() {
            Some(mut l) => {
                l.text.push(' ');
                l.text.push_str(text.trim());
                l
            }
            None => Line {
                number,
                text: text.trim().to_string(),
            },
        };
        if continues {
            open = Some(line);
        } else if !line.text.is_empty() {
            out.push(line);
        }
    }
    out.extend(open.filter(|l| !l.text.is_empty()));
    out
}

/// `line` without a shell comment (a `#` that starts a word outside quotes).
fn strip_comment(line: &str) -> String {
    let mut quote = None;
    let mut prev = ' ';
    for (i, c) in line.char_indices() {
        match (quote, c) {
            (None, '\'' | '"') => quote = Some(c),
            (Some(q), c) if c == q => quote = None,
            (None, '#') if prev.is_whitespace() => return line[..i].to_string(),
            _ => {}
        }
        prev = c;
    }
    line.to_string()
}

/// A command made runnable, and the flags its optional parts name.
#[derive(Debug, PartialEq)]
pub struct Runnable {
    pub command: String,
    pub optional_flags: Vec<String>,
}

/// Reads a documented command as the module's header says.
pub fn runnable(text: &str, with: &[(String, String)]) -> Runnable {
    let mut optional_flags = Vec::new();
    // Optional groups, nested or not, each starting a word.
    let mut kept = String::new();
    let mut depth = 0usize;
    let mut group = String::new();
    let mut prev = ' ';
    for c in text.chars() {
        if c == '[' && (depth > 0 || prev.is_whitespace()) {
            depth += 1;
        } else if c == ']' && depth > 0 {
            depth -= 1;
            if depth == 0 {
                optional_flags.extend(
                    group
                        .split(|c: char| c.is_whitespace() || c == '[' || c == ']')
                        .filter(|w| w.starts_with("--"))
                        .map(str::to_string),
                );
                group.clear();
            }
        } else if depth > 0 {
            group.push(c);
        } else {
            kept.push(c);
        }
        prev = c;
    }
    let mut words: Vec<String> = kept.split_whitespace().map(str::to_string).collect();
    if words.len() >= 4 && words[..4] == ["cargo", "run", "--release", "--"] {
        words.splice(..4, ["metamer".to_string()]);
    }
    let simulated = |model: &str| format!("'sim:{model}?time_scale=0'");
    for i in 0..words.len() {
        let w = &words[i];
        if w.contains('|') && w != "|" && w != "||" && !w.starts_with('\'') && !w.starts_with('"') {
            words[i] = w.split('|').next().unwrap_or_default().to_string();
        }
        if let Some((_, value)) = with.iter().find(|(name, _)| *name == words[i]) {
            words[i] = value.clone();
        }
        let flag = if i > 0 { words[i - 1].as_str() } else { "" };
        let w = words[i].as_str();
        let replaced = match flag {
            "--instrument" | "--spectral" | "--spot" if w.starts_with("cs100a") => {
                Some(simulated("cs100a"))
            }
            "--instrument" | "--spectral" | "--spot" if w == "i1pro" || w.starts_with("i1pro:") => {
                Some(simulated("i1pro"))
            }
            "--display" if w == "window" || w.starts_with("window:") => {
                Some("virtual:ips-lcd".to_string())
            }
            _ => None,
        };
        if let Some(r) = replaced {
            words[i] = r;
        }
    }
    Runnable {
        command: words.join(" "),
        optional_flags,
    }
}

/// The subcommand words of a `metamer` command: those after `metamer` up to the first
/// that is not a plain lower-case word.
fn subcommand(command: &str) -> Vec<String> {
    command
        .split_whitespace()
        .skip(1)
        .take_while(|w| {
            !w.is_empty()
                && w.chars().all(|c| c.is_ascii_lowercase() || c == '-')
                && !w.starts_with('-')
        })
        .map(str::to_string)
        .collect()
}

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

/// Whether `text` holds `number` as a whole number: not part of a longer one.
fn contains_number(text: &str, number: &str) -> bool {
    text.match_indices(number).any(|(i, _)| {
        let mut before = text[..i].chars().rev();
        let mut after = text[i + number.len()..].chars();
        let digit = |c: Option<char>| c.is_some_and(|c| c.is_ascii_digit());
        let (b1, b2) = (before.next(), before.next());
        let (a1, a2) = (after.next(), after.next());
        let longer_before = digit(b1) || (b1 == Some('.') && digit(b2));
        let longer_after = digit(a1) || (a1 == Some('.') && digit(a2));
        !longer_before && !longer_after
    })
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

#[test]
fn a_documented_command_is_read_as_its_header_says() {
    let with = [(
        "FILE.ti3".to_string(),
        "tests/data/dispread_cal.ti3".to_string(),
    )];
    assert_eq!(
        runnable(
            "metamer fit --measurements FILE.ti3|FILE.csv --model plcc|lut [--folds 5] \
             -o P.json [--icc OUT.icc [--icc-version 4|2.4]] [--force]",
            &with
        ),
        Runnable {
            command:
                "metamer fit --measurements tests/data/dispread_cal.ti3 --model plcc -o P.json"
                    .into(),
            optional_flags: vec![
                "--folds".into(),
                "--icc".into(),
                "--icc-version".into(),
                "--force".into()
            ],
        }
    );
    assert_eq!(
        runnable(
            "cargo run --release -- experiment -o exp/ --spectral i1pro --spot cs100a:/dev/ttyUSB0 --display window:1",
            &[]
        )
        .command,
        "metamer experiment -o exp/ --spectral 'sim:i1pro?time_scale=0' --spot \
         'sim:cs100a?time_scale=0' --display virtual:ips-lcd"
    );
    // Simulated specs and redirections are left as written.
    assert_eq!(
        runnable(
            "metamer spot --instrument 'sim:i1pro?time_scale=0' --json > a.json",
            &[]
        )
        .command,
        "metamer spot --instrument 'sim:i1pro?time_scale=0' --json > a.json"
    );
    assert_eq!(
        subcommand("metamer render spots-from-image image.exr"),
        ["render", "spots-from-image"]
    );
}

#[test]
fn marks_blocks_and_figures_are_read_from_the_markdown() {
    let doc = "text\n\
               <!-- doc-test: skip `metamer b`: it needs hardware -->\n\
               <!-- doc-test: with X=1 Y=2 -->\n\
               \n\
               ```sh\n\
               metamer a --x \\\n    --y   # a comment\n\
               metamer b\n\
               ```\n\
               It prints 0.25 <!-- doc-figure: a --> and -3 in all.<!-- doc-figure: a -->\n\
               ```json\n\
               {}\n\
               ```\n";
    let (blocks, figures) = parse(doc).unwrap();
    assert_eq!(blocks.len(), 1);
    assert_eq!(blocks[0].fence, 5);
    assert_eq!(
        blocks[0].lines,
        [
            Line {
                number: 6,
                text: "metamer a --x --y".into()
            },
            Line {
                number: 8,
                text: "metamer b".into()
            }
        ]
    );
    assert_eq!(
        blocks[0].marks.skip_prefixes,
        [("metamer b".to_string(), "it needs hardware".to_string())]
    );
    assert_eq!(blocks[0].marks.with.len(), 2);
    assert_eq!(
        figures
            .iter()
            .map(|f| (f.number, f.value.as_str()))
            .collect::<Vec<_>>(),
        [(10, "0.25"), (10, "-3")]
    );
    assert!(parse("<!-- doc-test: skip: -->\n```sh\nx\n```\n")
        .unwrap_err()
        .contains("say why"));
    assert!(parse("<!-- doc-test: skip: why -->\ntext\n```sh\nx\n```\n")
        .unwrap_err()
        .starts_with("line 2: doc-test marks must stand just above"));
    assert!(skips("metamer b", "metamer b --json"));
    assert!(skips("metamer b$", "metamer b"));
    assert!(!skips("metamer b$", "metamer b --json"));
    assert!(contains_number("mean 0.25, max 0.84.", "0.25"));
    assert!(contains_number("mean 0.25, max 0.84.", "0.84"));
    assert!(!contains_number("mean 0.253", "0.25"));
    assert!(!contains_number("mean 10.25", "0.25"));
}
