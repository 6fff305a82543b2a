//! `metamer simulate cs100a --pty` talked to by a client that is not metamer's own driver:
//! pyserial (tests/pyserial_client.py), run by the first Python found that has it.
#![cfg(unix)]

use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::support::oracle::PYSERIAL;

const SCRIPT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/pyserial_client.py");

/// Starts the command and returns it with the device path from its first line.
fn start(args: &[&str]) -> (Child, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(["simulate", "cs100a", "--pty"])
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starting metamer");
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    if line.is_empty() {
        let _ = child.wait();
        let mut err = String::new();
        child
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut err)
            .unwrap();
        panic!("metamer simulate printed no device path; stderr: {err}");
    }
    let path = line.trim_end().to_string();
    assert!(Path::new(&path).exists(), "{path:?} is not a device");
    (child, path)
}

/// Sends `signal` and returns the exit code, failing if the command does not stop.
fn stop(mut child: Child, signal: i32) -> Option<i32> {
    // SAFETY: kill with the id of a child this test started and has not yet reaped.
    let rc = unsafe { libc::kill(child.id() as libc::pid_t, signal) };
    assert_eq!(rc, 0, "kill: {}", std::io::Error::last_os_error());
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status.code();
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("metamer simulate did not stop within 10 s of signal {signal}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn client(python: &Path, path: &str, xyz: [f64; 3], tolerances: &[&str]) -> String {
    let out = Command::new(python)
        .arg(SCRIPT)
        .arg(path)
        .args(xyz.map(|v| v.to_string()))
        .args(tolerances)
        .output()
        .expect("running the pyserial client");
    assert!(
        out.status.success(),
        "pyserial client failed: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// A display's blue primary, x = 0.15, y = 0.06 at Y = 7.22 cd/m², read without noise:
/// the client gets exactly those numbers; SIGTERM ends the command with exit 0.
#[test]
fn pyserial_reads_the_light_given_and_sigterm_stops_cleanly() {
    let Some(python) = PYSERIAL.find() else {
        return;
    };
    let (x, y, lum) = (0.15, 0.06, 7.22);
    let xyz = [x / y * lum, lum, (1.0 - x - y) / y * lum];
    let arg = format!("{},{},{}", xyz[0], xyz[1], xyz[2]);
    let (child, path) = start(&["--noise", "off", "--time-scale", "0.01", "--xyz", &arg]);
    let reading = client(&python, &path, xyz, &[]);
    assert_eq!(reading.trim(), "Y 7.22 x 0.1500 y 0.0600");
    // A second client on the same device: the meter keeps serving after the first closed.
    client(&python, &path, xyz, &[]);
    assert_eq!(stop(child, libc::SIGTERM), Some(0));
}

/// With noise on, a reading stays within 4σ of the meter's repeatability (σ = 0.1 % of Y,
/// 0.0005 in x and y); Ctrl-C (SIGINT) ends the command with exit 0.
#[test]
fn noisy_readings_stay_within_the_repeatability_and_sigint_stops_cleanly() {
    let Some(python) = PYSERIAL.find() else {
        return;
    };
    let xyz = [41.2, 35.0, 5.5];
    let arg = "41.2,35,5.5";
    let (child, path) = start(&["--seed", "7", "--time-scale", "0", "--xyz", arg]);
    client(&python, &path, xyz, &["0.004", "0.0021"]);
    assert_eq!(stop(child, libc::SIGINT), Some(0));
}

#[test]
fn bad_arguments_are_usage_errors() {
    for args in [
        vec!["simulate", "cs100a"],
        vec!["simulate", "cs100a", "--pty", "--xyz", "1,-2,3"],
        vec!["simulate", "cs100a", "--pty", "--time-scale=-1"],
        vec!["simulate", "cs100a", "--pty", "--noise", "maybe"],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_metamer"))
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(
            out.stdout.is_empty(),
            "{args:?}: no device path on an error"
        );
    }
}
