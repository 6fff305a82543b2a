//! Replays every CS-100A transcript through the real driver, one test per file (generated
//! by `build.rs`). Each transcript's header carries `expect`: the steps to run and what the
//! user must see — readings (xyY, XYZ, flags) or the error message (a substring of it).
//! After the steps the whole transcript must have been played.

use std::path::Path;

use metamer_drivers::cs100a::Cs100a;
use metamer_drivers::link::replay::ReplaySerial;
use metamer_drivers::link::LineSettings;
use metamer_drivers::{Instrument, MeasureMode, Request};
use serde_json::Value;

include!(concat!(env!("OUT_DIR"), "/cs100a_transcript_tests.rs"));

fn replay_transcript(path: &str) {
    let link = ReplaySerial::open(Path::new(path)).unwrap_or_else(|e| panic!("{e}"));
    let header = link.transcript().header.clone();
    assert_eq!(header.instrument, "cs100a", "{path}");
    assert_eq!(header.transport, "serial", "{path}");
    assert!(
        header.origin == "recorded"
            || header.origin == "synthesized from the protocol documentation",
        "{path}: origin {:?}",
        header.origin
    );
    assert_eq!(
        link.transcript().line_settings(),
        Some(LineSettings::CS100A),
        "{path}"
    );
    let steps = header
        .expect
        .as_ref()
        .and_then(Value::as_array)
        .unwrap_or_else(|| panic!("{path}: the header needs \"expect\": [steps]"))
        .clone();
    assert!(!steps.is_empty(), "{path}: no steps");
    let mut meter = Cs100a::new(link);
    for (i, step) in steps.iter().enumerate() {
        let at = format!("{path} step {i} {step}");
        if let Some(outcome) = step.get("connect") {
            let r = meter.connect();
            match outcome.as_str() {
                Some("ok") => r.unwrap_or_else(|e| panic!("{at}: {e}")),
                _ => check_error(r.err(), step, &at),
            }
        } else if let Some(speed) = step.get("measure").and_then(Value::as_str) {
            if speed != "fast" && speed != "slow" {
                panic!("{at}: unknown speed {speed}");
            }
            meter.set_option("speed", speed).unwrap();
            let request = Request {
                mode: MeasureMode::Emissive,
            };
            let r = meter.measure(&request);
            if step.get("error").is_some() {
                check_error(r.err(), step, &at);
                continue;
            }
            let reading = r.unwrap_or_else(|e| panic!("{at}: {e}"));
            check_triple(&reading.xyy, &step["xyY"], 1e-9, &at);
            if let Some(xyz) = step.get("XYZ") {
                // The expected XYZ were computed by hand (Python) from the Yxy in the
                // transcript and rounded to 6 decimals.
                check_triple(&reading.xyz.to_array(), xyz, 1e-5, &at);
            }
            let flags: Vec<&str> = reading.flags.iter().map(|f| f.name()).collect();
            let want: Vec<&str> = step["flags"]
                .as_array()
                .unwrap_or_else(|| panic!("{at}: needs flags"))
                .iter()
                .map(|f| f.as_str().unwrap())
                .collect();
            assert_eq!(flags, want, "{at}");
            assert_eq!(reading.instrument, "cs100a");
            let t = if speed == "fast" { 0.1 } else { 0.4 };
            assert_eq!(reading.integration_s, Some(t), "{at}");
        } else {
            panic!("{at}: a step is {{\"connect\":…}} or {{\"measure\":\"fast\"|\"slow\",…}}");
        }
    }
    meter
        .link()
        .finish()
        .unwrap_or_else(|e| panic!("{path}: {e}"));
}

fn check_error(e: Option<metamer_drivers::DriverError>, step: &Value, at: &str) {
    let want = step["error"].as_str().expect("error is a string");
    let e = e.unwrap_or_else(|| panic!("{at}: succeeded, expected an error"));
    let message = e.to_string();
    assert!(
        message.contains(want),
        "{at}:\n  got  {message}\n  want …{want}…"
    );
}

fn check_triple(got: &[f64; 3], want: &Value, tol: f64, at: &str) {
    let want = want
        .as_array()
        .unwrap_or_else(|| panic!("{at}: needs a triple"));
    for (g, w) in got.iter().zip(want) {
        match w.as_f64() {
            Some(w) => assert!((g - w).abs() <= tol, "{at}: {got:?} vs {want:?}"),
            None => assert!(
                g.is_nan(),
                "{at}: {got:?} vs {want:?} (null = not measured)"
            ),
        }
    }
}
