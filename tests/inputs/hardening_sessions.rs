//! The files a session owns, checked as inputs are, through the binary: a journal that is
//! a FIFO or a dangling link, two sessions on one journal (a lock, and a journal two
//! sessions wrote at once recovered), a journalled reading whose XYZ no longer follows from
//! its spectrum, plans the fit or the validation cannot use refused before the first
//! reading, and an experiment's given box that a stage would overwrite.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use serde_json::{json, Value};

use crate::support::{fresh_dir, root, stderr};

const SPECTRAL: &str = "sim:i1pro?time_scale=0";
const SPOT: &str = "sim:cs100a?time_scale=0";
const PLAN: &str = r#"{"repeats": 2, "geometry": {"rows": 3, "cols": 3}}"#;

/// `metamer measure-box -o DIR/out --plan DIR/plan.json` on the simulated box.
fn measure_box(dir: &Path, spectral: &str, extra: &[&str]) -> Command {
    let plan = dir.join("plan.json");
    if !plan.exists() {
        std::fs::write(&plan, PLAN).unwrap();
    }
    let mut c = Command::new(env!("CARGO_BIN_EXE_metamer"));
    c.arg("measure-box")
        .arg("-o")
        .arg(dir.join("out"))
        .arg("--plan")
        .arg(&plan)
        .args(["--spectral", spectral, "--spot", SPOT])
        .args(extra)
        .env_remove("METAMER_SIM_TIME_SCALE")
        .stdin(Stdio::null());
    c
}

fn run(dir: &Path, extra: &[&str]) -> (Output, Duration) {
    let start = Instant::now();
    let o = measure_box(dir, SPECTRAL, extra).output().unwrap();
    (o, start.elapsed())
}

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(path.as_os_str().as_encoded_bytes()).unwrap();
    // SAFETY: a NUL-terminated path and a mode.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0);
}

/// A FIFO where a journal should be made the session wait for ever for a writer; a
/// dangling link was reported as an earlier session "with 0 readings" to continue with
/// --resume, which then said the same. Each is now named at once, with or without resume.
#[test]
fn a_journal_that_is_a_fifo_a_dangling_link_or_a_directory_is_named_at_once() {
    let dir = fresh_dir("kinds");
    let out = dir.join("out");
    let journal = out.join("tiles.jsonl");
    let kinds: [(&str, &dyn Fn()); 3] = [
        (
            "is a named pipe (FIFO), not a file this program wrote",
            &|| mkfifo(&journal),
        ),
        ("is a symbolic link to", &|| {
            std::os::unix::fs::symlink(dir.join("elsewhere.jsonl"), &journal).unwrap()
        }),
        ("is a directory", &|| std::fs::create_dir(&journal).unwrap()),
    ];
    for (words, make) in kinds {
        let _ = std::fs::remove_dir_all(&out);
        std::fs::create_dir_all(&out).unwrap();
        make();
        for extra in [&[][..], &["--resume"]] {
            let (o, took) = run(&dir, extra);
            let e = stderr(&o);
            assert_eq!(o.status.code(), Some(1), "{extra:?}: {e}");
            assert!(
                e.contains("tiles.jsonl") && e.contains(words),
                "{extra:?}: {e}"
            );
            assert!(!e.contains("reading(s) of an earlier session"), "{e}");
            assert!(took < Duration::from_secs(20), "{took:?}");
        }
        // Nothing was created where the dangling link points.
        assert!(!dir.join("elsewhere.jsonl").exists());
    }
}

/// Polls until `path` holds at least one whole line (the journal's header).
fn wait_for_header(path: &Path, child: &mut std::process::Child) {
    let deadline = Instant::now() + Duration::from_secs(120);
    while !std::fs::read(path).is_ok_and(|b| b.contains(&b'\n')) {
        if let Ok(Some(status)) = child.try_wait() {
            panic!("the first session ended ({status}) before its journal was written");
        }
        assert!(
            Instant::now() < deadline,
            "no journal at {}",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Three `--resume` at once left a step journalled twice, and every later resume failed.
/// A second session on the journal is refused while the first measures; once the first
/// is killed (SIGKILL: no chance to clean up) the system has released its lock and the
/// session resumes.
#[test]
fn a_second_session_on_a_journal_is_refused_while_the_first_runs() {
    let dir = fresh_dir("lock");
    // The i1Pro at its real pace: several seconds per tile, so the first session is
    // still measuring when the second starts.
    let mut first = measure_box(&dir, "sim:i1pro?time_scale=1", &[])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let journal = dir.join("out/tiles.jsonl");
    wait_for_header(&journal, &mut first);
    for extra in [&["--resume"][..], &[]] {
        let (o, took) = run(&dir, extra);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{extra:?}: {e}");
        assert!(
            e.contains("tiles.jsonl is in use by another session"),
            "{extra:?}: {e}"
        );
        assert!(took < Duration::from_secs(20), "{took:?}");
    }
    first.kill().unwrap();
    first.wait().unwrap();
    let o = measure_box(
        &dir,
        "sim:i1pro?time_scale=1",
        &["--resume", "--stop-after", "1"],
    )
    .output()
    .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
}

/// The tiles journal of a session stopped after `n` readings, as lines.
fn stopped_journal(dir: &Path, n: usize) -> (PathBuf, Vec<String>) {
    let (o, _) = run(dir, &["--stop-after", &n.to_string()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let journal = dir.join("out/tiles.jsonl");
    let lines = std::fs::read_to_string(&journal)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    (journal, lines)
}

fn entries(lines: &[String]) -> Vec<(usize, Value)> {
    lines
        .iter()
        .enumerate()
        .filter_map(|(i, l)| {
            let v: Value = serde_json::from_str(l).ok()?;
            (v["type"] == "entry").then_some((i, v))
        })
        .collect()
}

/// What two sessions writing one journal leave — steps 2 and 3 a second time, read by
/// the other session — is recovered: the first entry of each step kept, the others moved
/// to a side file, said on stderr; the session goes on and the next resume is clean.
#[test]
fn a_journal_with_steps_written_twice_is_recovered_keeping_the_first() {
    let dir = fresh_dir("twice");
    let (journal, mut lines) = stopped_journal(&dir, 4);
    let e = entries(&lines);
    assert_eq!(e.len(), 4);
    let mut second: Vec<String> = Vec::new();
    for (_, v) in &e[2..] {
        let mut v = v.clone();
        v["reading"]["timestamp_s"] = json!(v["reading"]["timestamp_s"].as_f64().unwrap() + 1.0);
        second.push(v.to_string());
    }
    lines.extend(second.iter().cloned());
    std::fs::write(&journal, lines.join("\n") + "\n").unwrap();
    let (o, _) = run(&dir, &["--resume", "--stop-after", "1"]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    let aside = dir.join("out/tiles.duplicates.jsonl");
    assert!(
        err.contains("held 2 reading(s) of steps it already had")
            && err.contains(aside.to_str().unwrap())
            && err.contains("(step 2)")
            && err.contains("(step 3)"),
        "{err}"
    );
    let kept: Vec<String> = std::fs::read_to_string(&aside)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    assert_eq!(kept, second);
    // The journal: the first four entries as they were, then the one new reading.
    let now: Vec<String> = std::fs::read_to_string(&journal)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    assert_eq!(now[..lines.len() - 2], lines[..lines.len() - 2]);
    let steps: Vec<u64> = entries(&now)
        .iter()
        .map(|(_, v)| v["index"].as_u64().unwrap())
        .collect();
    assert_eq!(steps, [0, 1, 2, 3, 4]);
    let (o, _) = run(&dir, &["--resume", "--stop-after", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("steps it already had"));
}

/// A tile's spectrum edited to −1e6 kept its XYZ and was accepted on resume; the XYZ must
/// follow from the spectrum, and the line that breaks it is named, the journal untouched.
#[test]
fn a_reading_whose_xyz_does_not_follow_from_its_spectrum_is_refused_on_resume() {
    let dir = fresh_dir("spectrum");
    let (journal, mut lines) = stopped_journal(&dir, 3);
    let (i, mut v) = entries(&lines)[1].clone();
    let n = v["reading"]["spectrum"]["values"].as_array().unwrap().len();
    v["reading"]["spectrum"]["values"][n / 2] = json!(-1e6);
    lines[i] = v.to_string();
    std::fs::write(&journal, lines.join("\n") + "\n").unwrap();
    let before = std::fs::read(&journal).unwrap();
    let (o, _) = run(&dir, &["--resume"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains(&format!(
            "tiles.jsonl, line {}: step 1 (tile 0,0 #2)",
            i + 1
        )) && e.contains("do not follow from its spectrum"),
        "{e}"
    );
    assert_eq!(std::fs::read(&journal).unwrap(), before);
}

/// Fall-off angles on one side of the normal cannot be fitted: the plan was measured
/// through all four stages and failed at the end. It is refused before the first reading.
#[test]
fn a_plan_the_fall_off_fit_cannot_use_is_refused_before_the_first_reading() {
    let dir = fresh_dir("angles");
    std::fs::write(
        dir.join("plan.json"),
        r#"{"repeats": 1, "falloff_angles_deg": [0, 20, 40, 60]}"#,
    )
    .unwrap();
    let (o, took) = run(&dir, &[]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("falloff_angles_deg: needs an angle on each side of the normal, and has no negative one"),
        "{e}"
    );
    assert!(!dir.join("out").exists(), "nothing was started");
    assert!(took < Duration::from_secs(20));
}

fn experiment(args: &[&str]) -> (Output, Duration) {
    let start = Instant::now();
    let o = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .arg("experiment")
        .args(args)
        .env_remove("METAMER_SIM_TIME_SCALE")
        .stdin(Stdio::null())
        .output()
        .unwrap();
    (o, start.elapsed())
}

/// A plan with patches [1, 2, 3, 19] ran every stage and failed in the validation (the
/// display reads all 24). It is refused before the box is measured, with the reason.
#[test]
fn an_experiment_plan_the_validation_cannot_use_is_refused_before_any_stage() {
    let dir = fresh_dir("patches");
    let plan = dir.join("plan.json");
    std::fs::write(&plan, r#"{"repeats": 1, "patches": [1, 2, 3, 19]}"#).unwrap();
    let ex = dir.join("ex");
    let (o, took) = experiment(&[
        "-o",
        ex.to_str().unwrap(),
        "--spectral",
        SPECTRAL,
        "--plan",
        plan.to_str().unwrap(),
        "--image-size",
        "0",
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("the experiment validates every patch of the chart")
            && e.contains("only [1, 2, 3, 19]"),
        "{e}"
    );
    assert!(!ex.join("box").exists(), "no stage ran");
    assert!(took < Duration::from_secs(30), "{took:?}");
}

/// `--box-spots ex/simulation/spots.csv --stage simulation` overwrote the given box
/// readings with simulated ones and exited 0. The given files are the run's inputs: one
/// inside a stage directory the run writes is refused before any stage, by any name.
#[test]
fn a_given_box_inside_a_stage_the_run_writes_is_refused_and_kept() {
    let dir = fresh_dir("given");
    let ex = dir.join("ex");
    let sim = ex.join("simulation");
    std::fs::create_dir_all(&sim).unwrap();
    let data = root().join("tests/data/report/experiment/box");
    let scene = root().join("data/scenes/validation-box.json");
    let spots = sim.join("spots.csv");
    std::fs::copy(data.join("spots.csv"), &spots).unwrap();
    let before = std::fs::read(&spots).unwrap();
    let link = dir.join("box-spots.csv");
    std::os::unix::fs::symlink(&spots, &link).unwrap();
    for given in [&spots, &link] {
        let (o, took) = experiment(&[
            "-o",
            ex.to_str().unwrap(),
            "--box-scene",
            scene.to_str().unwrap(),
            "--box-spots",
            given.to_str().unwrap(),
            "--stage",
            "simulation",
        ]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{e}");
        assert!(
            e.contains("lie in the simulation stage's directory")
                && e.contains("copy them elsewhere"),
            "{e}"
        );
        assert!(took < Duration::from_secs(30), "{took:?}");
        assert_eq!(std::fs::read(&spots).unwrap(), before);
    }
    assert!(!sim.join("stage.json").exists());
}

/// A given box whose readings hold other patches than its scene failed in the validation
/// after the simulation and the display had run; refused first, naming both files.
#[test]
fn a_given_box_whose_readings_miss_patches_of_its_scene_is_refused_before_any_stage() {
    let dir = fresh_dir("given-patches");
    let data = root().join("tests/data/report/experiment/box");
    let all = std::fs::read_to_string(data.join("spots.csv")).unwrap();
    let few: Vec<&str> = all.lines().take(5).collect();
    let spots = dir.join("few.csv");
    std::fs::write(&spots, few.join("\n") + "\n").unwrap();
    let ex = dir.join("ex");
    let scene = root().join("data/scenes/validation-box.json");
    let (o, _) = experiment(&[
        "-o",
        ex.to_str().unwrap(),
        "--box-scene",
        scene.to_str().unwrap(),
        "--box-spots",
        spots.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("few.csv are of patches [1, 2, 3, 4]") && e.contains("has patches [1, 2, 3"),
        "{e}"
    );
    assert!(!ex.join("simulation").exists(), "no stage ran");
}
