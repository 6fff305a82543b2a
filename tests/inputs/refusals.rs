//! Options that cannot work are refused before the work: each command below is given one,
//! and must say what is wrong (naming the option or the path) and exit within four seconds —
//! long before the work it would otherwise have started (renders, characterizations and
//! sessions take tens of seconds to minutes).

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use crate::support::fresh_dir;

const FAST: Duration = Duration::from_secs(4);

/// A regular file where a command needs its output directory.
fn a_file(dir: &Path) -> String {
    let f = dir.join("not-a-directory");
    std::fs::write(&f, "a file").unwrap();
    f.display().to_string()
}

/// Runs metamer with `args`; returns (exit code, stdout, stderr) after checking it was fast.
fn refused(args: &[&str]) -> (Option<i32>, String, String) {
    // The first start of the large binary reads it from disk, which on a loaded machine took
    // over two seconds by itself: start it once untimed so that only the refusal is timed.
    let _ = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .arg("--version")
        .output();
    let start = Instant::now();
    let o = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let took = start.elapsed();
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    );
    assert!(!o.status.success(), "{args:?} succeeded: {out}");
    assert!(took < FAST, "{args:?} took {took:?} to refuse: {err}");
    (o.status.code(), out, err)
}

#[test]
fn budget_with_no_trials_is_refused() {
    let d = fresh_dir("budget");
    let out = d.join("b").display().to_string();
    let (code, _, err) = refused(&["budget", "--trials", "0", "-o", &out]);
    assert_eq!(code, Some(2));
    assert!(err.contains("--trials must be at least 1"), "{err}");
    assert!(!d.join("b").exists(), "nothing is created");
}

/// The reproduction stage's gamut mapping is read with the command line, before the box is
/// measured, not after the box, the simulation and the display have run.
#[test]
fn experiment_with_an_unknown_gamut_mapping_is_refused_before_any_stage() {
    let d = fresh_dir("gamut");
    let out = d.join("ex").display().to_string();
    let (code, _, err) = refused(&[
        "experiment",
        "-o",
        &out,
        "--spectral",
        "sim:i1pro?time_scale=0",
        "--gamut",
        "nearest",
    ]);
    assert_eq!(code, Some(2));
    assert!(
        err.contains("--gamut")
            && err.contains("unknown gamut mapping 'nearest' (known: nearest-lab, clip)"),
        "{err}"
    );
    assert!(!d.join("ex").exists(), "nothing is created");
}

#[test]
fn render_spots_with_no_time_is_refused() {
    let (code, _, err) = refused(&["render", "spots", "--max-seconds", "0"]);
    assert_eq!(code, Some(2));
    assert!(err.contains("--max-seconds must be > 0"), "{err}");
}

#[test]
fn render_convergence_with_no_or_endless_time_is_refused_before_the_reference_run() {
    for seconds in ["0", "1e308", "NaN"] {
        let d = fresh_dir(&format!("conv-{seconds}"));
        let out = d.join("c").display().to_string();
        let (code, _, err) = refused(&["render", "convergence", "-o", &out, "--seconds", seconds]);
        assert_eq!(code, Some(2), "{seconds}: {err}");
        assert!(
            err.contains("--seconds: the time budget per strategy must be more than 0 s"),
            "{seconds}: {err}"
        );
        assert!(
            !d.join("c").exists(),
            "{seconds}: no output directory is made"
        );
    }
    let d = fresh_dir("conv-target");
    let out = d.join("c").display().to_string();
    let (_, _, err) = refused(&["render", "convergence", "-o", &out, "--reference-de", "0"]);
    assert!(err.contains("the ΔE*ab target must be > 0, got 0"), "{err}");
    let d = fresh_dir("conv-dir");
    let file = a_file(&d);
    let (_, _, err) = refused(&["render", "convergence", "-o", &file, "--seconds", "1"]);
    assert!(
        err.contains(&format!("cannot use {file} as an output directory")),
        "{err}"
    );
}

#[test]
fn reproduce_with_bits_and_xyz_is_refused() {
    let d = fresh_dir("bits");
    let out = d.join("drive.csv").display().to_string();
    let (code, _, err) = refused(&[
        "reproduce",
        "--profile",
        "no-such-profile.json",
        "--xyz",
        "no-such-targets.csv",
        "--bits",
        "16",
        "-o",
        &out,
    ]);
    assert_eq!(code, Some(2));
    assert!(
        err.contains("--bits sets the PNG depth of --image"),
        "{err}"
    );
}

/// Every command that writes into a directory refuses a file given as `-o`, naming it.
#[test]
fn an_output_directory_that_is_a_file_is_refused_by_every_command() {
    let d = fresh_dir("dirs");
    let file = a_file(&d);
    let sim = ["sim:i1pro?time_scale=0", "sim:cs100a?time_scale=0"];
    let cases: Vec<Vec<&str>> = vec![
        vec!["lab", "-o", &file],
        vec![
            "experiment",
            "-o",
            &file,
            "--spectral",
            sim[0],
            "--spot",
            sim[1],
            "--display",
            "virtual:ips-lcd",
        ],
        vec![
            "measure-box",
            "-o",
            &file,
            "--spectral",
            sim[0],
            "--spot",
            sim[1],
        ],
        vec![
            "characterize",
            "-o",
            &file,
            "--display",
            "virtual:ips-lcd",
            "--instrument",
            sim[1],
        ],
        vec!["budget", "-o", &file],
    ];
    for args in cases {
        let (_, _, err) = refused(&args);
        assert!(err.contains(file.as_str()), "{args:?}: {err}");
        assert!(
            err.contains("not a directory") || err.contains("is a file"),
            "{args:?}: {err}"
        );
        assert!(!err.contains("os error"), "{args:?}: {err}");
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "a file");
}

/// A colorimeter has no spectrum to write: refused before the first reading is taken.
#[test]
fn spot_spectrum_on_a_colorimeter_is_refused_before_measuring() {
    let d = fresh_dir("spot");
    let csv = d.join("s.csv");
    let (code, out, err) = refused(&[
        "spot",
        "--instrument",
        "sim:cs100a",
        "--count",
        "3",
        "--spectrum",
        &csv.display().to_string(),
    ]);
    assert_eq!(code, Some(2));
    assert!(
        err.contains("--spectrum: the cs100a measures no spectrum"),
        "{err}"
    );
    assert!(!out.contains("#1"), "a reading was taken first: {out}");
    assert!(!csv.exists());
}

/// The simulated meter served on a pseudo-terminal took `--time-scale 1e308` (a reading
/// would never end); the bound is that of every simulated instrument.
#[test]
fn simulate_refuses_a_time_scale_beyond_the_simulated_instruments_bound() {
    for scale in ["1e308", "1000.5", "-1", "NaN"] {
        let option = format!("--time-scale={scale}");
        let (code, _, err) = refused(&["simulate", "cs100a", "--pty", &option]);
        assert_eq!(code, Some(2), "{scale}: {err}");
        assert!(
            err.contains("--time-scale") && err.contains("is not a number from 0 to 1000"),
            "{scale}: {err}"
        );
    }
}

/// Once a client had asked for a reading, Ctrl-C printed "stopped by signal 2" and the
/// process never exited (the emulator slept through the reading's delay, and the main
/// thread waited for it). At 1000 times the real pace a reading takes minutes: the process
/// must still end at once.
#[test]
fn simulate_ends_at_ctrl_c_while_a_slow_reading_is_under_way() {
    use std::io::{BufRead, BufReader, Write};
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(["simulate", "cs100a", "--pty", "--time-scale", "1000"])
        .args(["--noise", "off"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut device = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut device)
        .unwrap();
    let mut port = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(device.trim())
        .unwrap();
    port.write_all(b"MES\r\n").unwrap();
    // The emulator takes the command and starts its minutes-long delay.
    std::thread::sleep(Duration::from_millis(500));
    // SAFETY: kill with a child's pid and a signal number.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > Duration::from_secs(5) {
            let _ = child.kill();
            panic!("still running 5 s after Ctrl-C");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    assert!(status.success(), "{status}");
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    assert!(err.contains("stopped by signal 2"), "{err}");
}

/// A real instrument with nobody at it: every guided command, its stdin not a terminal and
/// without `--unattended`, refuses before any reading, naming `--unattended`. The meter is a
/// live CS-100A emulator on a pseudo-terminal that counts what it is asked to measure:
/// nothing, until `--unattended` says the rig may measure alone.
#[cfg(unix)]
#[test]
fn a_real_instrument_with_nobody_at_it_is_refused_before_any_reading() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Arc;

    use metamer_drivers::cs100a::emulator::{Cs100aEmulator, EmulatorConfig};
    use metamer_drivers::cs100a::pty::PtyEmulator;
    use metamer_drivers::{View, World};

    struct Counted(AtomicUsize);
    impl World for Counted {
        fn view(&self) -> View {
            self.0.fetch_add(1, Ordering::SeqCst);
            View::from([95.047, 100.0, 108.883])
        }
    }
    let seen = Arc::new(Counted(AtomicUsize::new(0)));
    let config = EmulatorConfig {
        seed: 1,
        time_scale: 0.0,
        noise: false,
    };
    let emu = PtyEmulator::start(Cs100aEmulator::new(seen.clone(), config)).unwrap();
    let meter = format!("cs100a:{}", emu.path());
    let d = fresh_dir("unattended");
    let out = d.join("out").display().to_string();
    let box_plan = d.join("plan.json");
    std::fs::write(&box_plan, r#"{"patches": [1]}"#).unwrap();
    let box_plan = box_plan.display().to_string();
    let sessions: [&[&str]; 5] = [
        &[
            "measure-box",
            "-o",
            &out,
            "--plan",
            &box_plan,
            "--spectral",
            "i1pro",
            "--spot",
            &meter,
        ],
        &[
            "measure-box",
            "-o",
            &out,
            "--spectral",
            "replay:x.jsonl",
            "--spot",
            &meter,
            "--stage",
            "spots",
        ],
        &[
            "characterize",
            "--display",
            "virtual",
            "--instrument",
            &meter,
            "-o",
            &out,
        ],
        &["spot", "--instrument", &meter, "--count", "3"],
        // Not simulated, as the meter is not: a simulated spectral instrument beside a real
        // meter is refused as a mixed rig first.
        &[
            "experiment",
            "-o",
            &out,
            "--spectral",
            "i1pro",
            "--spot",
            &meter,
        ],
    ];
    for args in sessions {
        let (code, _, err) = refused(args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(
            err.contains(&format!(
                "{meter} is a real instrument and stdin is not a terminal"
            )) || err.contains("i1pro is a real instrument and stdin is not a terminal"),
            "{args:?}: {err}"
        );
        assert!(
            err.contains("add --unattended") && err.contains("nothing was measured"),
            "{args:?}: {err}"
        );
        assert!(!d.join("out").exists(), "{args:?} wrote {out}");
    }
    assert_eq!(
        seen.0.load(Ordering::SeqCst),
        0,
        "the meter was asked to measure"
    );
    // Said unattended, the same meter measures: the refusal above was not a dead port.
    let o = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args([
            "spot",
            "--instrument",
            &meter,
            "--count",
            "2",
            "--unattended",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(seen.0.load(Ordering::SeqCst), 2);
    std::fs::remove_dir_all(&d).unwrap();
}

/// Forgetting `--spot` on a real rig: the experiment's spot meter defaults to the simulated
/// CS-100A, and the refusal names that default and how to name the real meter, before any
/// stage.
#[test]
fn a_real_spectral_instrument_with_the_default_spot_meter_is_refused_naming_the_default() {
    let dir = fresh_dir("mixed-rig");
    let out = dir.join("out").display().to_string();
    let (code, _, err) = refused(&[
        "experiment",
        "-o",
        &out,
        "--spectral",
        "i1pro",
        "--unattended",
    ]);
    assert_eq!(code, Some(2));
    assert_eq!(
        err,
        "error: --spectral i1pro is real and --spot sim:cs100a?time_scale=0 (the default when \
         --spot is not given) is simulated: both must be simulated (sim:…) or neither, as a \
         simulated instrument sees only the simulated box; a real Konica Minolta CS-100A is \
         named cs100a:PORT\n"
    );
    // A spot meter given by hand is not called a default.
    let (code, _, err) = refused(&[
        "experiment",
        "-o",
        &out,
        "--spectral",
        "i1pro",
        "--spot",
        "sim:cs100a",
        "--unattended",
    ]);
    assert_eq!(code, Some(2));
    assert!(
        err.starts_with("error: --spectral i1pro is real and --spot sim:cs100a is simulated: "),
        "{err}"
    );
    assert!(!dir.join("out").join("box").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
