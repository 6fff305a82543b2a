//! `metamer spot` end to end: the simulated meter, replayed transcripts, recording, and the
//! message a user sees for every error path.

use std::path::Path;
use std::process::{Command, Output};

use serde_json::Value;

use crate::support::{fresh_dir, stderr};

fn metamer(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        // Tests run the emulator at a hundredth of the meter's pace.
        .env("METAMER_SIM_TIME_SCALE", "0.01")
        .output()
        .expect("the metamer binary runs")
}

fn transcript(name: &str) -> String {
    format!("replay:protocols/cs100a/transcripts/{name}.jsonl")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn json_lines(o: &Output) -> Vec<Value> {
    stdout(o)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect()
}

fn write_transcript(dir: &Path, name: &str, events: &[&str]) -> String {
    let mut text = String::from(
        r#"{"format":"metamer-transcript/1","instrument":"cs100a","transport":"serial","settings":{"baud":4800,"data_bits":7,"parity":"even","stop_bits":2},"origin":"synthesized from the protocol documentation","description":"spot CLI test"}"#,
    );
    text.push('\n');
    for e in [
        r#"{"dir":"host","data":"MDS,04\r\n"}"#,
        r#"{"dir":"device","data":"OK00\r\n"}"#,
        r#"{"dir":"host","data":"MDS,06\r\n"}"#,
        r#"{"dir":"device","data":"OK00\r\n"}"#,
    ]
    .iter()
    .chain(events)
    {
        text.push_str(e);
        text.push('\n');
    }
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    format!("replay:{}", path.display())
}

#[test]
fn sim_json_reads_the_default_light() {
    let o = metamer(&[
        "spot",
        "--instrument",
        "sim:cs100a",
        "--json",
        "--count",
        "3",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let lines = json_lines(&o);
    assert_eq!(lines.len(), 3);
    assert!(stdout(&o).starts_with(r#"{"XYZ":["#), "{}", stdout(&o));
    for v in &lines {
        // Default light: 100 cd/m² at LED-RGB1's chromaticity (0.45576, 0.42110); the
        // emulator's noise is ±0.2 % / ±0.001 at 2σ, bounds here are 5σ plus rounding.
        let xyy: Vec<f64> = v["xyY"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert!((xyy[2] - 100.0).abs() < 0.55, "{v}");
        assert!((xyy[0] - 0.45576).abs() < 0.0026, "{v}");
        assert!((xyy[1] - 0.42110).abs() < 0.0026, "{v}");
        let xyz: Vec<f64> = v["XYZ"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        // X = xY/y, Z = (1−x−y)Y/y.
        assert!((xyz[0] - xyy[0] * xyy[2] / xyy[1]).abs() < 1e-9);
        assert!((xyz[2] - (1.0 - xyy[0] - xyy[1]) * xyy[2] / xyy[1]).abs() < 1e-9);
        assert_eq!(v["flags"], serde_json::json!([]));
        assert_eq!(v["instrument"], "cs100a");
    }
    // Noise: three readings are not all equal.
    assert!(lines[0] != lines[1] || lines[1] != lines[2]);
}

#[test]
fn sim_human_output_and_spec_options() {
    let o = metamer(&[
        "spot",
        "--instrument",
        "sim:cs100a?time_scale=0&noise=off",
        "--speed",
        "slow",
        // A real meter's port, and stdin is not a terminal: nobody to ask, by choice.
        "--unattended",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert_eq!(
        out,
        "cs100a on sim:cs100a\n#1  Y 100.00 cd/m²  x 0.4558  y 0.4211  XYZ 108.24 100.00 29.233\n",
        "{out}"
    );
}

#[test]
fn replay_prints_the_transcripts_readings() {
    let o = metamer(&[
        "spot",
        "--instrument",
        &transcript("normal_session"),
        "--count",
        "3",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let lines = json_lines(&o);
    assert_eq!(lines[0]["xyY"], serde_json::json!([0.3127, 0.329, 123.4]));
    assert_eq!(lines[2]["xyY"], serde_json::json!([0.2851, 0.3004, 0.523]));
    let x = lines[0]["XYZ"][0].as_f64().unwrap();
    assert!((x - 117.286261).abs() < 1e-5, "{x}");

    let o = metamer(&[
        "spot",
        "--instrument",
        &transcript("low_light_ok13"),
        "--json",
    ]);
    assert_eq!(json_lines(&o)[0]["flags"], serde_json::json!(["low_light"]));
    let o = metamer(&[
        "spot",
        "--instrument",
        &transcript("chromaticity_over_ok11"),
    ]);
    assert!(
        stdout(&o).contains("x —  y —") && stdout(&o).contains("[chromaticity over range]"),
        "{}",
        stdout(&o)
    );
}

#[test]
fn an_error_reading_exits_1_with_the_meaning() {
    let dir = fresh_dir("er10");
    let spec = write_transcript(
        &dir,
        "er10.jsonl",
        &[
            r#"{"dir":"host","data":"MES\r\n"}"#,
            r#"{"dir":"device","data":"ER10\r\n"}"#,
        ],
    );
    let o = metamer(&["spot", "--instrument", &spec]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains(
            "answered 'MES' with ER10: luminance and chromaticity over the measuring range"
        ),
        "{}",
        stderr(&o)
    );
    // Readings before the error are printed; the error still exits 1.
    let spec = write_transcript(
        &dir,
        "ok_then_er30.jsonl",
        &[
            r#"{"dir":"host","data":"MES\r\n"}"#,
            r#"{"dir":"device","data":"OK00,  12.34, .3127, .3290\r\n"}"#,
            r#"{"dir":"host","data":"MES\r\n"}"#,
            r#"{"dir":"device","data":"ER30\r\n"}"#,
        ],
    );
    let o = metamer(&["spot", "--instrument", &spec, "--count", "2", "--json"]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(json_lines(&o).len(), 1);
    assert!(
        stderr(&o).contains("ER30: battery exhausted"),
        "{}",
        stderr(&o)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn device_faults_are_explained() {
    let cases = [
        ("silent_meter", "Switch the meter off, then hold F while switching it on"),
        ("garbage", "which is not a valid reply: byte 0 is 0xF3, not plain ASCII: a parity or framing error"),
        ("disconnect_mid_reply", "disconnected during 'MES' (received \"OK00,  12\"); reconnect the cable"),
        ("partial_reply_timeout", "stopped in the middle of its reply to 'MES'"),
        ("mode_rejected_er00", "ER00: command error: unknown command or parameter out of range"),
    ];
    for (name, message) in cases {
        let o = metamer(&["spot", "--instrument", &transcript(name)]);
        assert_eq!(o.status.code(), Some(1), "{name}");
        assert!(stderr(&o).contains(message), "{name}: {}", stderr(&o));
    }
}

#[test]
fn bad_specs_and_arguments() {
    let o = metamer(&["spot", "--instrument", "sim:i1d3"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).starts_with(
            "error: instrument 'sim:i1d3': the X-Rite i1Display Pro is not supported: metamer \
             has no codec for its HID protocol; known: cs100a:PORT"
        ),
        "{}",
        stderr(&o)
    );
    let o = metamer(&["spot", "--instrument", "sim:cs100a?time_scale=fast"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("time_scale=\"fast\" is not a number"),
        "{}",
        stderr(&o)
    );
    let o = metamer(&["spot", "--instrument", "sim:cs100a", "--count", "0"]);
    assert_eq!(o.status.code(), Some(2));
    let o = metamer(&[
        "spot",
        "--instrument",
        "cs100a:/dev/metamer-missing",
        "--unattended",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("serial port /dev/metamer-missing does not exist"),
        "{}",
        stderr(&o)
    );
    let o = metamer(&["spot", "--instrument", "replay:no/such/file.jsonl"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("cannot open no/such/file.jsonl"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn a_recorded_sim_session_replays_identically() {
    let dir = fresh_dir("record");
    let file = dir.join("session.jsonl");
    let f = file.to_str().unwrap();
    let live = metamer(&[
        "spot",
        "--instrument",
        "sim:cs100a",
        "--count",
        "2",
        "--json",
        "--record",
        f,
    ]);
    assert!(live.status.success(), "{}", stderr(&live));
    let replayed = metamer(&[
        "spot",
        "--instrument",
        &format!("replay:{f}"),
        "--count",
        "2",
        "--json",
    ]);
    assert!(replayed.status.success(), "{}", stderr(&replayed));
    assert_eq!(stdout(&live), stdout(&replayed));
    // A recording is never overwritten.
    let again = metamer(&["spot", "--instrument", "sim:cs100a", "--record", f]);
    assert_eq!(again.status.code(), Some(2));
    assert!(
        stderr(&again).contains("never overwritten"),
        "{}",
        stderr(&again)
    );
    // Replaying with a different speed than recorded names the line and the bytes.
    let wrong = metamer(&[
        "spot",
        "--instrument",
        &format!("replay:{f}"),
        "--speed",
        "slow",
    ]);
    assert_eq!(wrong.status.code(), Some(1));
    assert!(
        stderr(&wrong).contains("line 4: expected the host to send \"MDS,06\\r\\n\", but the driver wrote \"MDS,07\\r\\n\""),
        "{}",
        stderr(&wrong)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The real-meter path end to end: `cs100a:PORT` through the `serialport` backend, with the
/// emulator answering on a pseudo-terminal.
#[cfg(unix)]
#[test]
fn a_meter_on_a_serial_port() {
    use std::sync::Arc;

    use metamer_drivers::cs100a::emulator::{Cs100aEmulator, EmulatorConfig};
    use metamer_drivers::cs100a::pty::PtyEmulator;
    use metamer_drivers::SharedWorld;

    // A display's blue primary: x = 0.15, y = 0.06, Y = 7.22 cd/m².
    let (x, y, lum) = (0.15, 0.06, 7.22);
    let light = SharedWorld::new([x / y * lum, lum, (1.0 - x - y) / y * lum]);
    let config = EmulatorConfig {
        seed: 11,
        time_scale: 0.01,
        noise: false,
    };
    let emu = PtyEmulator::start(Cs100aEmulator::new(Arc::new(light), config)).unwrap();
    let spec = format!("cs100a:{}", emu.path());
    let o = metamer(&[
        "spot",
        "--instrument",
        &spec,
        "--json",
        "--count",
        "2",
        "--speed",
        "slow",
        // A real meter's port, and stdin is not a terminal: nobody to ask, by choice.
        "--unattended",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for v in json_lines(&o) {
        assert_eq!(v["xyY"], serde_json::json!([0.15, 0.06, 7.22]), "{v}");
    }
}

/// A simulated i1Pro that keeps (a part of) the real one's pace says so first, and its
/// dark calibration (20 s at the real pace, 6 s here) shows it is alive every 5 s while
/// stderr is no terminal.
#[test]
fn a_paced_simulation_says_so_first_and_a_long_wait_shows_progress() {
    let o = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args([
            "spot",
            "--instrument",
            "sim:i1pro?time_scale=0.3",
            "--count",
            "1",
        ])
        .env_remove("METAMER_SIM_TIME_SCALE")
        .output()
        .unwrap();
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert_eq!(
        err.lines().next(),
        Some(
            "note: the simulated instruments (sim:i1pro?time_scale=0.3) run at 0.3 times their \
             real pace; `?time_scale=0` in a spec (or METAMER_SIM_TIME_SCALE=0) makes them \
             answer at once"
        ),
        "{err}"
    );
    assert!(
        err.lines()
            .any(|l| l == "  … the i1pro calibrates for emissive readings: 5 s so far"),
        "{err}"
    );
}
