//! `metamer experiment` on the simulated monitor and meter, with the box's readings given:
//! every stage's files, re-use of unchanged stages, re-running exactly what depends on a
//! changed option, and a killed measuring stage resumed with nothing lost.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use metamer::experiment::readings::{write_readings, PatchReading};
use metamer::experiment::validate::ValidationResult;
use metamer::render::radiosity::{render_spots_radiosity, RadiosityOptions};
use metamer::render::Scene;

use crate::support::unused_dir;

/// The validation box the experiment tests run on.
pub(crate) const SCENE: &str = "data/scenes/validation-box.json";

/// The box's spot readings: the deterministic render of the scene, as a box measured
/// without meter noise would read.
pub(crate) fn box_spots(dir: &Path) -> PathBuf {
    let scene = Scene::load(Path::new(SCENE)).unwrap();
    let r = render_spots_radiosity(&scene, &RadiosityOptions::default(), &|_| {}).unwrap();
    let stats: Vec<(usize, PatchReading)> = r
        .patches
        .iter()
        .map(|p| (p.patch, PatchReading::of(&[p.xyz])))
        .collect();
    let f = dir.join("box-spots.csv");
    write_readings(&f, &stats).unwrap();
    f
}

fn command(out: &Path, spots: &Path, extra: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_metamer"));
    c.args(["experiment", "-o"])
        .arg(out)
        .args(["--box-scene", SCENE, "--box-spots"])
        .arg(spots)
        .args(extra);
    c
}

fn run(out: &Path, spots: &Path, extra: &[&str]) -> Output {
    let o = command(out, spots, extra).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

/// Stage name → "ran" or "re-used", from the summary table.
fn stages(o: &Output) -> Vec<(String, String)> {
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .filter_map(|l| {
            let mut f = l.split_whitespace();
            let (s, how) = (f.next()?, f.next()?);
            matches!(how, "ran" | "re-used").then(|| (s.to_string(), how.to_string()))
        })
        .collect()
}

fn how(o: &Output, stage: &str) -> String {
    stages(o)
        .into_iter()
        .find(|(s, _)| s == stage)
        .map(|(_, h)| h)
        .unwrap_or_default()
}

#[test]
fn stages_run_once_and_rerun_only_downstream_of_a_change() {
    let dir = unused_dir("reuse");
    std::fs::create_dir_all(&dir).unwrap();
    let spots = box_spots(&dir);
    let out = dir.join("exp");
    let first = run(&out, &spots, &[]);
    // The box was measured elsewhere: said so, with its readings' file, not "re-used".
    let said = String::from_utf8_lossy(&first.stdout);
    let box_line = said.lines().find(|l| l.starts_with("box ")).unwrap_or("");
    assert!(
        box_line.contains("given") && box_line.contains("box-spots.csv"),
        "{said}"
    );
    let told = String::from_utf8_lossy(&first.stderr);
    assert!(
        told.contains("box: given, measured earlier or elsewhere"),
        "{told}"
    );
    for s in [
        "simulation",
        "display",
        "reproduction",
        "display-spots",
        "validation",
    ] {
        assert_eq!(how(&first, s), "ran", "{s}");
    }
    let v: ValidationResult = serde_json::from_str(
        &std::fs::read_to_string(out.join("validation/comparisons.json")).unwrap(),
    )
    .unwrap();
    // Box and simulation are the same deterministic render here.
    assert!(
        v.simulation_vs_box.max_de76.value < 1e-9,
        "{:?}",
        v.simulation_vs_box.max_de76
    );
    // The lut model reproduces every colour it can show to within the JND.
    for p in &v.display_vs_simulation.patches {
        if !v.out_of_gamut_patches.contains(&p.patch) {
            assert!(p.de76 < 2.3, "patch {}: ΔE*ab {}", p.patch, p.de76);
        }
    }
    // The CIELAB white is the display's measured white.
    let profile: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("display/profile.json")).unwrap())
            .unwrap();
    assert_eq!(profile["white_xyz"][1].as_f64().unwrap(), v.white[1]);

    let second = run(&out, &spots, &[]);
    assert!(
        stages(&second).iter().all(|(_, h)| h == "re-used"),
        "{:?}",
        stages(&second)
    );

    // A stage record is trusted only as far as it vouches, and read only when it is a
    // small regular file: a link to /dev/zero, a 6 GB sparse file or a FIFO is not read
    // (it once was read whole, or waited for a writer), and one that leaves its product out
    // (`"outputs": {}`) does not let an edited product pass as the stage's work. Each
    // re-runs the stage, at once, and restores what it writes.
    let record = out.join("validation/stage.json");
    let comparisons = out.join("validation/comparisons.json");
    let good = std::fs::read(&comparisons).unwrap();
    let vouched = std::fs::read_to_string(&record).unwrap();
    let mut empty: serde_json::Value = serde_json::from_str(&vouched).unwrap();
    empty["outputs"] = serde_json::json!({});
    type Damage<'a> = (&'a str, Box<dyn Fn() + 'a>);
    let damages: [Damage; 4] = [
        (
            "a link to /dev/zero",
            Box::new(|| std::os::unix::fs::symlink("/dev/zero", &record).unwrap()),
        ),
        (
            "a 6 GB sparse file",
            Box::new(|| {
                std::fs::File::create(&record)
                    .unwrap()
                    .set_len(6 << 30)
                    .unwrap()
            }),
        ),
        (
            "a FIFO",
            Box::new(|| {
                let c = std::ffi::CString::new(record.as_os_str().as_encoded_bytes()).unwrap();
                // SAFETY: a NUL-terminated path and a mode.
                assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0);
            }),
        ),
        (
            "outputs {} and an edited product",
            Box::new(|| {
                std::fs::write(&record, empty.to_string()).unwrap();
                std::fs::write(&comparisons, b"{\"edited\": true}").unwrap();
            }),
        ),
    ];
    for (what, damage) in damages {
        std::fs::remove_file(&record).unwrap();
        damage();
        let start = Instant::now();
        let again = run(&out, &spots, &[]);
        assert!(start.elapsed() < Duration::from_secs(60), "{what}");
        assert_eq!(how(&again, "validation"), "ran", "{what}");
        assert_eq!(how(&again, "display-spots"), "re-used", "{what}");
        assert!(
            std::fs::symlink_metadata(&record)
                .unwrap()
                .file_type()
                .is_file(),
            "{what}"
        );
        assert!(
            std::fs::metadata(&record).unwrap().len() < 1 << 20,
            "{what}"
        );
        assert_eq!(std::fs::read(&comparisons).unwrap(), good, "{what}");
    }

    // More repeats on the display: only the display readings and what follows them.
    let third = run(&out, &spots, &["--repeats", "2"]);
    for (s, expect) in [
        ("simulation", "re-used"),
        ("display", "re-used"),
        ("reproduction", "re-used"),
        ("display-spots", "ran"),
        ("validation", "ran"),
    ] {
        assert_eq!(how(&third, s), expect, "{s}");
    }
    // The readings of the earlier configuration are kept, not deleted.
    assert!(out.join("display-spots.old-1/journal.jsonl").exists());

    // Another gamut mapping: reproduction onwards, not the display.
    let fourth = run(&out, &spots, &["--repeats", "2", "--gamut", "clip"]);
    assert_eq!(how(&fourth, "display"), "re-used");
    assert_eq!(how(&fourth, "reproduction"), "ran");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_killed_display_characterization_resumes() {
    let dir = unused_dir("killed");
    std::fs::create_dir_all(&dir).unwrap();
    let spots = box_spots(&dir);
    let out = dir.join("exp");
    // ≈ 10 ms a reading: slow enough to be killed in the display stage.
    let slow = ["--spot", "sim:cs100a?time_scale=0.1"];
    let mut child = command(&out, &spots, &slow)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let log = out.join("display/log.jsonl");
    let start = Instant::now();
    while std::fs::read_to_string(&log).map_or(0, |t| t.lines().count()) < 11 {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no readings arrive"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let journalled: Vec<String> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    let before = journalled.len();

    // Without --resume the journal is not touched.
    let o = command(&out, &spots, &slow).output().unwrap();
    assert!(!o.status.success());
    assert_eq!(
        std::fs::read_to_string(&log).unwrap().lines().count(),
        before
    );

    let o = run(&out, &spots, &[&slow[..], &["--resume"]].concat());
    assert_eq!(how(&o, "simulation"), "re-used");
    assert_eq!(how(&o, "display"), "ran");
    let after: Vec<String> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    // Every whole line journalled before the kill is still there, first in the file (the
    // last one may have been torn by the kill and set aside).
    let whole = before - 1;
    assert_eq!(&after[..whole], &journalled[..whole]);
    assert!(after.len() > before);
    assert!(out.join("validation/comparisons.json").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
