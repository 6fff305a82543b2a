//! `metamer characterize` end to end on the simulated monitor and meter: the files it
//! writes, verification against an analytic case, resuming after an interruption (a stop
//! on purpose and a killed process), and the messages of its error paths.

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use metamer::display::{read_measurements, Profile};
use serde_json::Value;

use crate::support::{text, unused_dir};

fn command(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_metamer"));
    c.arg("characterize")
        .args(args)
        .env_remove("METAMER_SIM_TIME_SCALE");
    c
}

fn metamer(args: &[&str]) -> Output {
    command(args).output().expect("the metamer binary runs")
}

fn summary(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// (index, rgb) of every reading entry of a journal, in file order.
fn logged(dir: &Path) -> Vec<(u64, Vec<u64>)> {
    let log = std::fs::read_to_string(dir.join("log.jsonl")).unwrap();
    let mut lines = log.lines();
    let header: Value = serde_json::from_str(lines.next().unwrap()).unwrap();
    assert_eq!(header["type"], "header");
    lines
        .map(|l| serde_json::from_str::<Value>(l).unwrap())
        .filter(|v| v["type"] == "entry")
        .map(|v| {
            let rgb = v["data"]["rgb"]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| c.as_u64().unwrap())
                .collect();
            (v["index"].as_u64().unwrap(), rgb)
        })
        .collect()
}

/// Every reading's XYZ by plan index.
fn readings(dir: &Path) -> Vec<(u64, Value)> {
    let log = std::fs::read_to_string(dir.join("log.jsonl")).unwrap();
    let mut v: Vec<(u64, Value)> = log
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).unwrap())
        .filter(|v| v["type"] == "entry")
        .map(|v| (v["index"].as_u64().unwrap(), v["reading"]["xyz"].clone()))
        .collect();
    v.sort_by_key(|e| e.0);
    v
}

const IPS: &[&str] = &[
    "--display",
    "virtual:ips-lcd",
    "--instrument",
    "sim:cs100a?time_scale=0",
];

#[test]
fn writes_profile_ti3_log_report_and_summary() {
    let dir = unused_dir("files");
    let o = metamer(&[IPS, &["-o", dir.to_str().unwrap()]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(
        out.contains("measured 86 readings of virtual:ips-lcd with cs100a"),
        "{out}"
    );
    assert!(
        out.contains("verification on 48 held-out patches: ΔE00 mean "),
        "{out}"
    );
    assert!(out.contains("verdict: "), "{out}");

    let profile = Profile::load(&dir.join("profile.json")).unwrap();
    // The .ti3 holds every raw reading and reads back through the .ti3 reader, white
    // normalised to Y = 100 as ArgyllCMS writes it.
    let ti3 = read_measurements(&dir.join("readings.ti3")).unwrap();
    assert_eq!(ti3.len(), 86);
    let log = logged(&dir);
    assert_eq!(log.len(), 86);
    for (patch, (_, rgb)) in ti3.iter().zip(&log) {
        let drive: Vec<u64> = patch
            .rgb
            .iter()
            .map(|d| (d * 255.0).round() as u64)
            .collect();
        assert_eq!(&drive, rgb);
    }
    let s = summary(&dir);
    assert_eq!(s["model"], "plcc");
    assert_eq!(s["readings"], 86);
    assert_eq!(s["fit_patches"], 33);
    let v = &s["verification"];
    assert_eq!(v["patches"].as_array().unwrap().len(), 48);
    let (mean, p95, max) = (
        v["mean"].as_f64().unwrap(),
        v["p95"].as_f64().unwrap(),
        v["max"].as_f64().unwrap(),
    );
    assert!(mean <= p95 && p95 <= max, "{mean} {p95} {max}");
    // The verification's predictions are the saved profile's.
    let first = &v["patches"][0];
    let rgb: Vec<f64> = first["rgb8"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_f64().unwrap() / 255.0)
        .collect();
    let predicted = profile.forward([rgb[0], rgb[1], rgb[2]]);
    for (k, p) in predicted.iter().enumerate() {
        assert!((p - first["predicted_xyz"][k].as_f64().unwrap()).abs() < 1e-9);
    }
    let svg = std::fs::read_to_string(dir.join("report.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("ΔE00 of the 48 verification patches"));
    // A finished directory is never overwritten.
    let o = metamer(&[IPS, &["-o", dir.to_str().unwrap()]].concat());
    assert_eq!(o.status.code(), Some(1));
    let err = text(&o.stderr);
    assert!(
        err.contains("log.jsonl exists with 86 reading(s)") && err.contains("--resume"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_exact_model_verifies_to_the_meter_resolution_and_a_faulty_display_does_not() {
    // ideal-crt is PLCC with power-law TRCs exactly; without noise, what is left is the
    // CS-100A's 4-decimal chromaticity, far below 0.1 ΔE00.
    let dir = unused_dir("exact");
    let o = metamer(&[
        "--display",
        "virtual:ideal-crt",
        "--instrument",
        "sim:cs100a?time_scale=0&noise=off",
        "--model",
        "plcc-gamma",
        "-o",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let max = summary(&dir)["verification"]["max"].as_f64().unwrap();
    assert!(max < 0.1, "ideal-crt with plcc-gamma: max ΔE00 {max}");
    std::fs::remove_dir_all(&dir).unwrap();
    // The LCD's drift and crosstalk are beyond PLCC: the held-out patches show it.
    let dir = unused_dir("faulty");
    let o = metamer(&[
        "--display",
        "virtual:wide-gamut-ccfl",
        "--instrument",
        "sim:cs100a?time_scale=0&noise=off",
        "-o",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let s = summary(&dir);
    let mean = s["verification"]["mean"].as_f64().unwrap();
    assert!(mean > 1.0, "wide-gamut-ccfl with plcc: mean ΔE00 {mean}");
    assert!(!s["failures"].as_array().unwrap().is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_lut_gets_a_grid_of_the_ramp_levels() {
    // --ramp-steps 3: levels 0, 128, 255; the 3³ grid adds the 18 combinations that black,
    // the primaries, white and the four ramps' 128 do not already hold: 9 + 18 fit patches.
    let dir = unused_dir("lut");
    let o = metamer(
        &[
            IPS,
            &[
                "--model",
                "lut",
                "--ramp-steps",
                "3",
                "-o",
                dir.to_str().unwrap(),
            ],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let s = summary(&dir);
    assert_eq!(
        (s["model"].as_str(), s["fit_patches"].as_u64()),
        (Some("lut"), Some(27))
    );
    // The 3³ grid holds the ramps; 48 verification patches; black, primaries, white twice.
    assert_eq!(s["readings"], 27 + 48 + 5);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_stopped_session_resumes_and_measures_only_what_is_missing() {
    let dir = unused_dir("stop");
    let d = dir.to_str().unwrap();
    let args = [IPS, &["--repeats", "2", "-o", d]].concat();
    let o = metamer(&[args.as_slice(), &["--stop-after", "30"]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stdout)
        .contains("stopped with 132 of 162 readings still to take; continue with --resume"));
    assert_eq!(logged(&dir).len(), 30);
    // Another plan is refused and the log left as it is.
    let before = std::fs::read(dir.join("log.jsonl")).unwrap();
    let o = metamer(&[IPS, &["--repeats", "3", "-o", d, "--resume"]].concat());
    assert_eq!(o.status.code(), Some(1));
    let err = text(&o.stderr);
    assert!(
        err.contains("was written by another session: its --repeats is 2, this one's is 3"),
        "{err}"
    );
    assert_eq!(std::fs::read(dir.join("log.jsonl")).unwrap(), before);

    let o = metamer(&[args.as_slice(), &["--resume"]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("resuming: 30 of 162 readings"),
        "{}",
        text(&o.stderr)
    );
    let log = logged(&dir);
    let mut indices: Vec<u64> = log.iter().map(|r| r.0).collect();
    indices.sort_unstable();
    assert_eq!(indices, (0..162).collect::<Vec<_>>());
    assert_eq!(summary(&dir)["readings"], 162);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_killed_session_resumes_to_the_same_patches_as_an_uninterrupted_one() {
    let whole = unused_dir("uninterrupted");
    let o = metamer(&[IPS, &["-o", whole.to_str().unwrap()]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));

    // At a tenth of the meter's pace a reading takes ≈ 10 ms: kill it mid-session.
    let dir = unused_dir("killed");
    let d = dir.to_str().unwrap();
    let slow = [
        "--display",
        "virtual:ips-lcd",
        "--instrument",
        "sim:cs100a?time_scale=0.1",
        "-o",
        d,
    ];
    let mut child = command(&slow)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        let n = std::fs::read_to_string(dir.join("log.jsonl")).map_or(0, |t| t.lines().count());
        if n >= 11 {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no readings arrive"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let partial = logged(&dir).len();
    assert!(
        (10..86).contains(&partial),
        "{partial} readings before the kill"
    );

    // The simulated meter at another pace is another instrument setting: refused by name.
    let before = std::fs::read(dir.join("log.jsonl")).unwrap();
    let o = metamer(&[IPS, &["-o", d, "--resume"]].concat());
    assert_eq!(o.status.code(), Some(1));
    let err = text(&o.stderr);
    assert!(
        err.contains("time_scale") && err.contains("was 0.1, this session's is 0"),
        "{err}"
    );
    assert_eq!(std::fs::read(dir.join("log.jsonl")).unwrap(), before);

    let o = metamer(&[&slow[..], &["--resume"]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    let mut resumed = logged(&dir);
    resumed.sort();
    let mut straight = logged(&whole);
    straight.sort();
    assert_eq!(
        resumed, straight,
        "each planned patch once, the same as without interruption"
    );
    // And the same numbers: the meter's noise of reading k depends on its seed and k only,
    // not on the process that took it or on the pace.
    assert_eq!(readings(&dir), readings(&whole));
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&whole).unwrap();
}

#[test]
fn ctrl_c_stops_cleanly_and_the_session_resumes() {
    let dir = unused_dir("ctrl-c");
    let d = dir.to_str().unwrap();
    let slow = [
        "--display",
        "virtual:ideal-crt",
        "--instrument",
        "sim:cs100a?time_scale=0.1",
        "-o",
        d,
    ];
    let child = command(&slow)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while std::fs::read_to_string(dir.join("log.jsonl")).map_or(0, |t| t.lines().count()) < 6 {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no readings arrive"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    // SAFETY: sending a signal to our own child process.
    assert_eq!(
        unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) },
        0
    );
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = text(&o.stderr);
    assert!(
        err.contains("error: interrupted with ") && err.contains("continue with --resume"),
        "{err}"
    );
    let partial = logged(&dir).len();
    assert!(partial < 86, "{partial}");
    let o = metamer(&[&slow[..], &["--resume"]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(logged(&dir).len(), 86);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn usage_and_environment_errors() {
    let dir = unused_dir("usage");
    let d = dir.to_str().unwrap();
    for (args, expect) in [
        (
            vec!["--display", "oled", "--instrument", "sim:cs100a", "-o", d],
            "unknown display 'oled'",
        ),
        (
            vec![
                "--display",
                "virtual",
                "--instrument",
                "sim:cs100a",
                "--model",
                "magic",
                "-o",
                d,
            ],
            "unknown model 'magic'",
        ),
        (
            vec![
                "--display",
                "virtual",
                "--instrument",
                "sim:cs100a",
                "--ramp-steps",
                "1",
                "-o",
                d,
            ],
            "--ramp-steps must be between 2 and 256",
        ),
        (
            vec![
                "--display",
                "virtual",
                "--instrument",
                "sim:cs100a",
                "--repeats",
                "0",
                "-o",
                d,
            ],
            "--repeats must be at least 1",
        ),
        (
            vec!["--display", "virtual", "--instrument", "sim:i1d3", "-o", d],
            "sim:i1d3",
        ),
    ] {
        let o = metamer(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o.stderr));
        assert!(
            text(&o.stderr).contains(expect),
            "{args:?}: {}",
            text(&o.stderr)
        );
    }
    assert!(!dir.exists(), "nothing is written on a usage error");
    // A window needs an X display.
    let o = command(&["--display", "window", "--instrument", "sim:cs100a", "-o", d])
        .env_remove("DISPLAY")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("DISPLAY is not set"),
        "{}",
        text(&o.stderr)
    );
}

#[test]
fn a_log_that_holds_no_session_says_what_to_do_and_resume_sets_it_aside() {
    let dir = unused_dir("broken");
    let d = dir.to_str().unwrap();
    std::fs::create_dir_all(&dir).unwrap();
    // A crash while the header was written leaves a cut-off first line.
    std::fs::write(dir.join("log.jsonl"), r#"{"type":"header","form"#).unwrap();
    let args = [IPS, &["--ramp-steps", "3", "-o", d]].concat();
    let o = metamer(&args);
    assert_eq!(o.status.code(), Some(1));
    let err = text(&o.stderr);
    assert!(
        err.contains("holds no session to continue: its header line was cut off after 22 bytes")
            && err.contains("run with --resume to set it aside"),
        "{err}"
    );
    let o = metamer(&[args.as_slice(), &["--resume"]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("log.jsonl.broken-1"),
        "{}",
        text(&o.stderr)
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("log.jsonl.broken-1")).unwrap(),
        r#"{"type":"header","form"#
    );
    // Black, primaries, white; one level inside each of 4 ramps; 48 held out; the key 5 again.
    assert_eq!(summary(&dir)["readings"], 5 + 4 + 48 + 5);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The adaptive plan's refusals, before anything is measured: a targets file with a row
/// that is no colour names its file and line (exit 1); the flags that do not go together
/// are usage errors (exit 2).
#[test]
fn adaptive_plan_refusals_name_the_file_line_and_flag() {
    let dir = unused_dir("adaptive-refusals");
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("targets.csv");
    std::fs::write(&bad, "X,Y,Z\n10,12,5\n# a comment\n4,-1,3\n").unwrap();
    let out = dir.join("out");
    let (b, d) = (bad.to_str().unwrap(), out.to_str().unwrap());
    let o = metamer(&[IPS, &["--plan", "adaptive", "--targets", b, "-o", d]].concat());
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert!(
        err.contains(&format!("{b}:4: target X=4, Y=-1, Z=3 is no colour")),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    for (args, expect) in [
        (
            vec!["--plan", "adaptive"],
            "--plan adaptive needs --targets",
        ),
        (vec!["--targets", b], "--targets names the colours"),
        (
            vec!["--model", "auto"],
            "--model auto chooses the model between batches",
        ),
        (
            vec!["--plan", "adaptive", "--targets", b, "--stop-de", "0"],
            "--stop-de must be a ΔE*ab above 0",
        ),
        (
            vec!["--plan", "adaptive", "--targets", b, "--grid-steps", "5"],
            "--grid-steps sets the fixed plan's grid",
        ),
    ] {
        let o = metamer(&[IPS, &args, &["-o", d]].concat());
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o.stderr));
        assert!(
            text(&o.stderr).contains(expect),
            "{args:?}: {}",
            text(&o.stderr)
        );
    }
    let good = dir.join("good.csv");
    std::fs::write(&good, "X,Y,Z\n10,12,5\n").unwrap();
    let g = good.to_str().unwrap();
    let o = metamer(
        &[
            IPS,
            &[
                "--plan",
                "adaptive",
                "--targets",
                g,
                "--max-readings",
                "20",
                "-o",
                d,
            ],
        ]
        .concat(),
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr)
            .contains("--max-readings: the cap of 20 readings is below the first pass's"),
        "{}",
        text(&o.stderr)
    );
    assert!(!out.exists(), "nothing is written on a refusal");
    std::fs::remove_dir_all(&dir).unwrap();
}
