//! What the operator sees: `metamer measure-box` driven in a real terminal (tmux) with a
//! replayed i1Pro (a transcript recorded from the simulated one) and a CS-100A answering
//! on a pseudo-terminal, keys sent as an operator would press them. Checked on the screen:
//! the calibration said as done, once; each placement asked for once with its number of
//! readings and where the tile is; a line after each reading with its place in the
//! placement and the session; a reading the meter cannot have repeated flagged and read
//! again when the operator presses Enter; `q` stops with exit 0 and the resume hint.
//! Needs tmux (Debian: `apt-get install tmux`, done by `.ci/run`).

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use metamer_drivers::cs100a::emulator::{Cs100aEmulator, EmulatorConfig};
use metamer_drivers::cs100a::pty::PtyEmulator;
use metamer_drivers::{View, World};

use crate::support::fresh_dir;
use crate::support::oracle::TMUX;

const METAMER: &str = env!("CARGO_BIN_EXE_metamer");

/// 100 cd/m² at the chromaticity of D65, and 3 % more at one chosen reading: the meter
/// bumped between two readings of a placement.
struct Light {
    views: AtomicUsize,
    bumped: usize,
}

impl World for Light {
    fn view(&self) -> View {
        let n = self.views.fetch_add(1, Ordering::SeqCst) + 1;
        let k = if n == self.bumped { 1.03 } else { 1.0 };
        View::from([95.047 * k, 100.0 * k, 108.883 * k])
    }
}

/// A tmux server of the test's own (its socket in the test's directory).
struct Tmux {
    socket: PathBuf,
}

impl Tmux {
    fn run(&self, args: &[&str]) -> Output {
        Command::new("tmux")
            .arg("-S")
            .arg(&self.socket)
            .args(["-f", "/dev/null"])
            .args(args)
            .stdin(Stdio::null())
            .output()
            .expect("tmux runs (Debian: apt-get install tmux)")
    }

    /// Everything the pane showed, wrapped lines joined.
    fn screen(&self) -> String {
        String::from_utf8_lossy(
            &self
                .run(&["capture-pane", "-p", "-J", "-S", "-", "-t", "op"])
                .stdout,
        )
        .into_owned()
    }

    /// Waits until the screen holds `needle` `times` times.
    fn wait_for(&self, needle: &str, times: usize) -> String {
        let start = Instant::now();
        loop {
            let screen = self.screen();
            if screen.matches(needle).count() >= times {
                return screen;
            }
            assert!(
                start.elapsed() < Duration::from_secs(30),
                "waited 30 s for {times} × {needle:?}; the screen:\n{screen}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    fn keys(&self, keys: &[&str]) {
        let mut args = vec!["send-keys", "-t", "op"];
        args.extend(keys);
        assert!(self.run(&args).status.success());
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = self.run(&["kill-server"]);
    }
}

fn quoted(p: &Path) -> String {
    format!("'{}'", p.display())
}

/// The test's own directory, empty; None (the test skipped with the reason) where tmux,
/// which drives its terminal, is missing.
fn scratch(tag: &str) -> Option<PathBuf> {
    TMUX.find()?;
    Some(fresh_dir(tag))
}

/// `count` emissive readings of the simulated i1Pro, recorded to `dir/i1pro.jsonl` for
/// replaying through the real driver.
fn record_i1pro(dir: &Path, count: usize) -> PathBuf {
    let transcript = dir.join("i1pro.jsonl");
    let recorded = Command::new(METAMER)
        .args(["spot", "--instrument", "sim:i1pro?time_scale=0", "--count"])
        .arg(count.to_string())
        .arg("--record")
        .arg(&transcript)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert!(recorded.status.success(), "{recorded:?}");
    transcript
}

/// The CS-100A emulator on a pseudo-terminal, seeing `light`, at a hundredth of its pace.
fn pty_meter(light: Arc<Light>) -> PtyEmulator {
    let config = EmulatorConfig {
        seed: 1,
        time_scale: 0.01,
        noise: false,
    };
    PtyEmulator::start(Cs100aEmulator::new(light, config)).unwrap()
}

/// A 200×60 tmux session `op` running `script`, on a server of the test's own in `dir`.
fn tmux_running(dir: &Path, script: &str) -> Tmux {
    let tmux = Tmux {
        socket: dir.join("tmux.sock"),
    };
    let started = tmux.run(&[
        "new-session",
        "-d",
        "-s",
        "op",
        "-x",
        "200",
        "-y",
        "60",
        script,
    ]);
    assert!(started.status.success(), "{started:?}");
    tmux
}

#[test]
fn an_operator_is_asked_once_per_placement_and_sees_every_reading() {
    let Some(dir) = scratch("tmux") else {
        return;
    };

    // The i1Pro: six emissive readings of the simulated one, recorded, then replayed
    // through the real driver (a transcript is not a live instrument: no --unattended).
    let transcript = record_i1pro(&dir, 6);
    // The CS-100A: the emulator on a pseudo-terminal, its 5th reading of a bumped meter.
    let light = Arc::new(Light {
        views: AtomicUsize::new(0),
        bumped: 5,
    });
    let meter = pty_meter(light.clone());

    let plan = dir.join("plan.json");
    std::fs::write(
        &plan,
        r#"{"repeats": 3, "patches": [1, 2], "falloff_angles_deg": [-20, 0, 20],
            "geometry": {"rows": 1, "cols": 2}}"#,
    )
    .unwrap();
    let out = dir.join("out");
    let command = |stage: &str| {
        format!(
            "{} measure-box -o {} --plan {} --spectral replay:{} --spot cs100a:{} --stage {stage}",
            quoted(Path::new(METAMER)),
            quoted(&out),
            quoted(&plan),
            quoted(&transcript),
            meter.path()
        )
    };
    let script = format!(
        "{}; echo EXIT1=$?; {}; echo EXIT2=$?; {}; echo EXIT3=$?; sleep 600",
        command("tiles"),
        command("spots"),
        command("falloff")
    );
    let tmux = tmux_running(&dir, &script);

    // The tiles: the calibration, then each tile once with its count.
    tmux.wait_for(
        "spectral instrument (i1pro), emissive calibration: place the instrument on its white calibration tile; press Enter when done (q to stop)",
        1,
    );
    tmux.keys(&["Enter"]);
    let first = "place the i1Pro on tile row 0, column 0 of the light on the left wall (the only row, column nearest the open front) — 3 readings; press Enter when done (q to stop)";
    tmux.wait_for(first, 1);
    tmux.keys(&["Enter"]);
    let second = "place the i1Pro on tile row 0, column 1 of the light on the left wall (the only row, column nearest the back) — 3 readings; press Enter when done (q to stop)";
    tmux.wait_for(second, 1);
    tmux.keys(&["Enter"]);
    tmux.wait_for("EXIT1=0", 1);

    // The spots: patch 2's second reading is 3 % off its first.
    let patch = |n: usize, name: &str| {
        format!("aim the spot meter from the viewpoint at ColorChecker patch {n} ({name}) on the right wall — 3 readings; press Enter when done (q to stop)")
    };
    tmux.wait_for(&patch(1, "dark skin"), 1);
    tmux.keys(&["Enter"]);
    tmux.wait_for(&patch(2, "light skin"), 1);
    tmux.keys(&["Enter"]);
    let doubt = "reading 2/3 (spot 2 #2) differs: re-aim and press Enter to read it again, k then Enter to keep it (q to stop)";
    tmux.wait_for(doubt, 1);
    tmux.keys(&["Enter"]);
    tmux.wait_for("EXIT2=0", 1);

    // The fall-off: the operator stops at the first request.
    tmux.wait_for("from -20° in the horizontal plane (towards the open front) — 1 reading; press Enter when done (q to stop)", 1);
    tmux.keys(&["q", "Enter"]);
    let screen = tmux.wait_for("EXIT3=", 1);

    if std::env::var_os("SHOW_SCREEN").is_some() {
        eprintln!("{screen}");
    }
    let count = |s: &str| screen.matches(s).count();
    // Asked once per placement, every reading shown.
    for prompt in [
        first,
        second,
        &patch(1, "dark skin"),
        &patch(2, "light skin"),
    ] {
        assert_eq!(count(prompt), 1, "{prompt}\n{screen}");
    }
    for k in 1..=3 {
        assert_eq!(
            count(&format!("  reading {k}/3 · stage 1/4 tiles · Y ")),
            2,
            "{screen}"
        );
    }
    assert_eq!(count("stage 1/4 tiles: 6 readings at 2 placements"), 1);
    assert_eq!(count("stage 4/4 spots: 6 readings at 2 placements"), 1);
    assert_eq!(
        count("reading 1/3 · stage 4/4 spots · Y 100.0 cd/m² · xy 0.3127 0.3290"),
        2,
        "{screen}"
    );
    // The bumped reading, flagged and set aside; then read again.
    assert_eq!(
        count(
            "  reading 2/3 · stage 4/4 spots · Y 103.0 cd/m² · xy 0.3127 0.3290 · differs: Y 3.00 % above the reading before it; the instrument repeats within ±0.2 % in Y and ±0.001 in x, y"
        ),
        1,
        "{screen}"
    );
    assert_eq!(
        count("  set aside: Y 103.0 cd/m² · xy 0.3127 0.3290; reading it again"),
        1
    );
    assert_eq!(
        count("reading 2/3 · stage 4/4 spots · Y 100.0 cd/m² · xy 0.3127 0.3290"),
        2,
        "{screen}"
    );
    // The calibration said as done, once, not as a new request.
    assert_eq!(
        count("calibrated the spectral instrument (i1pro) for emissive readings on its white calibration tile"),
        1
    );
    assert_eq!(count("calibrated the spectral instrument for emissive:"), 0);
    // `q`: stopped, how to go on, exit 0; nothing measured.
    assert!(
        screen.contains(
            "stopped at your request: stage falloff: none of its 6 readings taken yet: continue with --resume\nEXIT3=0"
        ),
        "{screen}"
    );
    assert_eq!(
        light.views.load(Ordering::SeqCst),
        7,
        "6 spot readings and the one set aside"
    );

    // The journal holds the reading taken again, not the one set aside.
    let spots = std::fs::read_to_string(out.join("spots.jsonl")).unwrap();
    let ys: Vec<f64> = spots
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|v| v["type"] == "entry")
        .map(|v| v["reading"]["xyz"][1].as_f64().unwrap())
        .collect();
    assert_eq!(ys, [100.0; 6]);
    drop(tmux);
    drop(meter);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `experiment --unattended` at a terminal, on instruments that are not simulated (a
/// replayed i1Pro, a CS-100A on a pseudo-terminal): the box stage asks nobody to place,
/// aim or calibrate anything, as `measure-box --unattended` does, instead of waiting for
/// an Enter that nobody will press. The transcript holds only emissive readings, so the
/// session runs the tiles and the fall-off and stops at the materials, where the driver
/// asks the replay for a reflective calibration it does not hold.
#[test]
fn the_experiment_unattended_at_a_terminal_asks_nobody() {
    let Some(dir) = scratch("tmux-unattended") else {
        return;
    };
    let transcript = record_i1pro(&dir, 2);
    let meter = pty_meter(Arc::new(Light {
        views: AtomicUsize::new(0),
        bumped: 0,
    }));
    let plan = dir.join("plan.json");
    std::fs::write(
        &plan,
        r#"{"repeats": 1, "falloff_angles_deg": [-20, 0, 20], "geometry": {"rows": 1, "cols": 2}}"#,
    )
    .unwrap();
    let out = dir.join("out");
    let script = format!(
        "{} experiment -o {} --plan {} --spectral replay:{} --spot cs100a:{} --stage box --unattended; echo EXIT=$?; sleep 600",
        quoted(Path::new(METAMER)),
        quoted(&out),
        quoted(&plan),
        quoted(&transcript),
        meter.path()
    );
    let tmux = tmux_running(&dir, &script);
    let screen = tmux.wait_for("EXIT=", 1);
    assert_eq!(screen.matches("press Enter").count(), 0, "{screen}");
    assert!(
        screen.contains("stage materials") && screen.contains("EXIT=1"),
        "{screen}"
    );
    let entries = |stage: &str| {
        std::fs::read_to_string(out.join("box").join(format!("{stage}.jsonl")))
            .unwrap()
            .lines()
            .filter(|l| l.starts_with(r#"{"type":"entry""#))
            .count()
    };
    assert_eq!((entries("tiles"), entries("falloff")), (2, 6), "{screen}");
    drop(tmux);
    std::fs::remove_dir_all(&dir).unwrap();
}
