//! The experiment killed with SIGKILL once in each of its six stages, resumed each time,
//! ends with exactly the comparisons of an uninterrupted run, and every reading journalled
//! before a kill is still in its journal afterwards.
//!
//! The simulated instruments draw their noise from (seed, reading index) and the stages'
//! outputs are written whole or not at all, so an interruption anywhere may cost time but
//! never changes a number: the uninterrupted run computed here is the independent value.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use crate::support::{json, unused_dir};

const STAGES: [&str; 6] = [
    "box",
    "simulation",
    "display",
    "reproduction",
    "display-spots",
    "validation",
];

/// A small lab at a fiftieth of the instruments' real pace: slow enough for a kill to land
/// among the readings of a measuring stage, quick enough for a test.
fn lab(dir: &Path, resume: bool) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_metamer"));
    c.args(["lab", "-o"])
        .arg(dir)
        .args([
            "--target-de",
            "0.5",
            "--repeats",
            "1",
            "--box-repeats",
            "1",
            "--image-size",
            "96",
            "--time-scale",
            "0.02",
        ])
        .env_remove("METAMER_SIM_TIME_SCALE")
        .stdin(Stdio::null());
    if resume {
        c.arg("--resume");
    }
    c
}

/// Every line of every journal a stage keeps (the box keeps one per measuring stage).
fn journal_lines(stage_dir: &Path) -> Vec<(PathBuf, Vec<String>)> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(stage_dir) else {
        return out;
    };
    let mut paths: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "jsonl"))
        .collect();
    paths.sort();
    for p in paths {
        let text = std::fs::read_to_string(&p).unwrap_or_default();
        out.push((p, text.lines().map(String::from).collect()));
    }
    out
}

fn line_count(stage_dir: &Path) -> usize {
    journal_lines(stage_dir).iter().map(|(_, l)| l.len()).sum()
}

/// Waits until the child says it runs `stage` and, for a measuring stage, has journalled a
/// few more readings.
fn wait_inside(lines: &mpsc::Receiver<String>, dir: &Path, stage: &str) {
    let start = Instant::now();
    let limit = Duration::from_secs(240);
    let wanted = format!("{stage}: running");
    loop {
        match lines.recv_timeout(Duration::from_millis(50)) {
            Ok(l) if l.trim() == wanted => break,
            Ok(_) => {}
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                panic!("the lab ended before the {stage} stage ran")
            }
        }
        assert!(start.elapsed() < limit, "the {stage} stage never started");
    }
    let stage_dir = dir.join(stage);
    if matches!(stage, "box" | "display" | "display-spots") {
        let at = line_count(&stage_dir);
        while line_count(&stage_dir) < at + 4 {
            assert!(
                start.elapsed() < limit,
                "the {stage} stage journals nothing"
            );
            std::thread::sleep(Duration::from_millis(2));
        }
    }
}

/// Kills the child inside `stage` ([`wait_inside`]). Returns whether the stage was still
/// unfinished.
fn kill_in(child: &mut Child, lines: &mpsc::Receiver<String>, dir: &Path, stage: &str) -> bool {
    wait_inside(lines, dir, stage);
    child.kill().unwrap();
    child.wait().unwrap();
    !dir.join(stage).join("stage.json").exists()
}

fn spawn(dir: &Path, resume: bool) -> (Child, mpsc::Receiver<String>) {
    let mut child = lab(dir, resume)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        // The progress bar writes carriage returns: split on them too.
        let mut r = BufReader::new(stderr);
        let mut buf = Vec::new();
        while r.read_until(b'\n', &mut buf).is_ok_and(|n| n > 0) {
            for part in String::from_utf8_lossy(&buf).split('\r') {
                let _ = tx.send(part.to_string());
            }
            buf.clear();
        }
    });
    (child, rx)
}

#[test]
fn killed_in_every_stage_and_resumed_it_ends_as_an_uninterrupted_run() {
    let root = unused_dir("chain");
    let whole = root.join("whole");
    let o = lab(&whole, false).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let killed = root.join("killed");
    let mut landed = Vec::new();
    for (i, stage) in STAGES.iter().enumerate() {
        let before: Vec<_> = STAGES
            .iter()
            .flat_map(|s| journal_lines(&killed.join(s)))
            .collect();
        let (mut child, lines) = spawn(&killed, i > 0);
        landed.push((stage, kill_in(&mut child, &lines, &killed, stage)));
        // Nothing journalled before this run was lost or changed by it: each journal that
        // was there still begins with its whole lines (a torn last line is set aside).
        for (path, old) in before {
            let now = std::fs::read_to_string(&path).unwrap_or_default();
            let now: Vec<&str> = now.lines().collect();
            let whole_lines = old.len().saturating_sub(1);
            assert!(now.len() >= whole_lines, "{} lost lines", path.display());
            for (a, b) in old[..whole_lines].iter().zip(&now) {
                assert_eq!(a, b, "{} changed", path.display());
            }
        }
    }
    eprintln!("where each kill landed (stage, before the stage finished): {landed:?}");
    // The measuring stages are slow enough that each kill lands inside them; the quick
    // stages may finish before the signal arrives, and then the kill lands in the next.
    for (stage, inside) in &landed {
        if matches!(**stage, "box" | "display" | "display-spots") {
            assert!(inside, "the kill missed the {stage} stage");
        }
    }
    assert!(
        landed.iter().filter(|(_, inside)| *inside).count() >= 4,
        "{landed:?}"
    );

    let o = lab(&killed, true).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let a = json(&whole.join("validation/comparisons.json"));
    let b = json(&killed.join("validation/comparisons.json"));
    assert_eq!(a, b, "the resumed run's comparisons differ");
    // The readings themselves, not only their summary: the measured scene's spot readings
    // and the display's.
    for f in [
        "box/spots.csv",
        "display-spots/spots.csv",
        "simulation/spots.csv",
    ] {
        assert_eq!(
            std::fs::read_to_string(whole.join(f)).unwrap(),
            std::fs::read_to_string(killed.join(f)).unwrap(),
            "{f} differs"
        );
    }
    std::fs::remove_dir_all(&root).unwrap();
}

/// Ctrl-C in the display stage stops it before its next reading, as in the box and
/// display-spots stages: the display's profile is not written, the readings taken are in
/// its journal, and the message says which stage stopped and how to go on. (Were the
/// stage deaf to the first Ctrl-C, it would finish and the next measuring stage would be
/// the one that stops.)
#[test]
fn ctrl_c_in_the_display_stage_stops_that_stage() {
    let dir = unused_dir("sigint-display");
    let (mut child, lines) = spawn(&dir, false);
    wait_inside(&lines, &dir, "display");
    let stage_dir = dir.join("display");
    // SAFETY: sending a signal to our own child process.
    assert_eq!(
        unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) },
        0
    );
    let said: Vec<String> = lines.iter().collect();
    let status = child.wait().unwrap();
    let said = said.join("\n");
    assert!(!status.success(), "{said}");
    assert!(
        said.contains("the display stage stopped with") && said.contains("resume"),
        "{said}"
    );
    assert!(!stage_dir.join("profile.json").exists());
    assert!(line_count(&stage_dir) >= 4);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Ctrl-C while the simulation renders stops the render at its next check, names the
/// simulation stage, and leaves the stage unrecorded so the next run renders it again
/// (the flag used to wait for the render's end and then stop the display stage, which was
/// blamed).
#[test]
fn ctrl_c_during_the_render_stops_it_and_names_the_simulation_stage() {
    let out = unused_dir("ctrl-c-render");
    let given = crate::support::test_data("report/experiment/box");
    // A target no render reaches within its 600 s limit.
    let mut child = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(["experiment", "-o"])
        .arg(&out)
        .arg("--box-scene")
        .arg(crate::support::scenes_dir().join("validation-box.json"))
        .arg("--box-spots")
        .arg(given.join("spots.csv"))
        .args(["--target-de", "0.00001", "--image-size", "0"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (tx, lines) = mpsc::channel();
    let err = BufReader::new(child.stderr.take().unwrap());
    std::thread::spawn(move || {
        for line in err.lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let start = Instant::now();
    let mut seen = Vec::new();
    while !seen
        .iter()
        .any(|l: &String| l.contains("simulation: running"))
    {
        let line = lines
            .recv_timeout(Duration::from_secs(60))
            .unwrap_or_else(|_| panic!("the simulation never started: {seen:?}"));
        seen.push(line);
    }
    // Well into the render.
    std::thread::sleep(Duration::from_secs(2));
    let sent = Instant::now();
    // SAFETY: kill with a child's pid and a signal number.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        assert!(
            sent.elapsed() < Duration::from_secs(30),
            "still rendering 30 s after Ctrl-C"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    let stopped_in = sent.elapsed();
    seen.extend(lines.try_iter());
    let err = seen.join("\n");
    assert_eq!(status.code(), Some(1), "{err}");
    assert!(err.contains("interrupted in the simulation stage"), "{err}");
    // The budget before the first stage names the display's stages; none of them began,
    // and none is blamed.
    assert!(!err.contains("display: running"), "{err}");
    assert!(!err.contains("in the display"), "{err}");
    assert!(!out.join("simulation/stage.json").exists());
    assert!(!out.join("display").exists());
    eprintln!(
        "stopped {:.2} s after Ctrl-C ({:.1} s in all)",
        stopped_in.as_secs_f64(),
        start.elapsed().as_secs_f64()
    );
    std::fs::remove_dir_all(&out).ok();
}
