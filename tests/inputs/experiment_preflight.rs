//! `metamer experiment`'s inputs that can be known before the first reading, refused before
//! it: another renderer's image that is missing, of another aspect ratio than the camera or
//! where the simulation stage writes its own copy; a real screen with no X display or before
//! a simulated meter; a rig half simulated. Each refusal must come at once, with no journal
//! and no stage directory written (each used to come after the box had been measured).

use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};

use crate::support::{fresh_dir, metamer_command, root, stderr, unused_dir};

/// The simulated box, measured once per target, nobody at the rig.
const SIM_BOX: [&str; 5] = [
    "--spectral",
    "sim:i1pro?time_scale=0",
    "--box-repeats",
    "1",
    "--unattended",
];

/// Every file under `dir`, if it exists.
fn files_under(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    entries
        .flatten()
        .flat_map(|e| {
            let p = e.path();
            if p.is_dir() {
                files_under(&p)
            } else {
                vec![p]
            }
        })
        .collect()
}

/// Runs `experiment -o out args` (without `DISPLAY` when `no_display`) and checks that it
/// was refused within seconds, saying `needle`, and that `out` holds nothing but `kept`.
fn refused_at_once(out: &Path, args: &[&str], no_display: bool, needle: &str, kept: &[PathBuf]) {
    let mut command = metamer_command();
    command
        .current_dir(root())
        .env("METAMER_SIM_TIME_SCALE", "0")
        .args(["experiment", "-o"])
        .arg(out)
        .args(args);
    if no_display {
        command.env_remove("DISPLAY");
    }
    let start = Instant::now();
    let result: Output = command.output().unwrap();
    let took = start.elapsed();
    let err = stderr(&result);
    assert!(!result.status.success(), "{args:?} ran: {err}");
    assert!(err.contains(needle), "{args:?}: {err}");
    // Measuring the simulated box alone takes longer; the checks take a fraction of it.
    assert!(took < Duration::from_secs(10), "{args:?} took {took:?}");
    assert_eq!(
        files_under(out),
        kept,
        "{args:?}: written before the refusal"
    );
}

/// A PFM image `width`×`height` of a uniform grey (absolute cd/m²).
fn pfm(file: &Path, width: usize, height: usize) {
    let mut bytes = format!("PF\n{width} {height}\n-1.0\n").into_bytes();
    for _ in 0..width * height * 3 {
        bytes.extend(10.0f32.to_le_bytes());
    }
    std::fs::write(file, bytes).unwrap();
}

#[test]
fn a_missing_or_misshapen_simulation_image_is_refused_before_the_box_is_measured() {
    let dir = fresh_dir("image");
    let out = dir.join("exp");
    let missing = dir.join("missing.pfm");
    let args = |image: &Path| {
        let mut a: Vec<String> = SIM_BOX.iter().map(|s| s.to_string()).collect();
        a.extend(["--simulation-image".into(), image.display().to_string()]);
        a
    };
    let run = |image: &Path, needle: &str| {
        let a = args(image);
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        refused_at_once(&out, &a, false, needle, &[]);
    };
    run(&missing, "missing.pfm");
    // The measured scene's camera is square (1014²): a 4×2 image is of another one.
    let wide = dir.join("wide.pfm");
    pfm(&wide, 4, 2);
    run(&wide, "4×2");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The image the stage would write its own copy over is refused, and left as it was.
#[test]
fn a_simulation_image_in_the_stage_directory_is_refused_and_kept() {
    let dir = fresh_dir("in-stage");
    let out = dir.join("exp");
    let stage = out.join("simulation");
    std::fs::create_dir_all(&stage).unwrap();
    let image = stage.join("image.exr");
    std::fs::write(&image, b"another renderer's image").unwrap();
    let mut args = SIM_BOX.to_vec();
    let shown = image.display().to_string();
    args.extend(["--simulation-image", &shown]);
    refused_at_once(
        &out,
        &args,
        false,
        "lies in the simulation stage's directory",
        std::slice::from_ref(&image),
    );
    assert_eq!(std::fs::read(&image).unwrap(), b"another renderer's image");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A real monitor needs an X display, and a real meter before it; both are known before
/// the box is measured.
#[test]
fn a_real_screen_that_cannot_be_used_is_refused_before_the_box_is_measured() {
    let out = unused_dir("screen");
    let meter = "replay:protocols/cs100a/transcripts/normal_session.jsonl";
    // Replayed instruments: a real (not simulated) rig that needs nobody at it.
    let replayed = [
        "--spectral",
        "replay:protocols/i1pro/transcripts/open_emissive.jsonl",
        "--spot",
        meter,
        "--display",
        "window:0",
    ];
    refused_at_once(&out, &replayed, true, "DISPLAY is not set", &[]);
    let mut simulated_meter = SIM_BOX.to_vec();
    simulated_meter.extend(["--display", "window:0"]);
    refused_at_once(
        &out,
        &simulated_meter,
        false,
        "cannot see the real screen window:0",
        &[],
    );
    // Half a simulated rig: the simulated spectrometer sees only the simulated box.
    let mixed = ["--spectral", "sim:i1pro", "--spot", meter];
    refused_at_once(&out, &mixed, false, "both must be simulated", &[]);
}
