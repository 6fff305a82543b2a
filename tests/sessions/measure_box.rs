//! `metamer measure-box` end to end on the simulated box: the whole session with the
//! simulated i1Pro and CS-100A, recovered spectra and reflectances against the truth within
//! the instruments' noise, the render of the measured scene against the box's spot
//! readings (and the nominal scene's, to show what the measurement changed), a session
//! killed with SIGKILL and resumed, and the plan's and flags' errors.

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use metamer::color::{luminance, Outside, Spectrum, Xyz};
use metamer::light::CGammaTable;
use metamer::measure_box::compare::{compare_readings, render_scene};
use metamer::measure_box::scene::{scene_json, BoxContents};
use metamer::measure_box::simulated_box::SimulatedBox;
use metamer::measure_box::BoxPlan;
use metamer::render::scene::DistributionFile;
use metamer::render::spot::{RenderedReading, Uncertainty};
use metamer::rig::Scenario;
use serde_json::Value;

use crate::support::{fresh_dir, json};

const SPECTRAL: &str = "sim:i1pro?time_scale=0";
const SPOT: &str = "sim:cs100a?time_scale=0";

/// A small plan: 3 × 3 tiles, two readings of each tile and spot.
const PLAN: &str = r#"{"repeats": 2, "geometry": {"rows": 3, "cols": 3}}"#;

fn command(dir: &Path, extra: &[&str]) -> Command {
    let plan = dir.join("plan.json");
    std::fs::write(&plan, PLAN).unwrap();
    let out = dir.join("out");
    let mut c = Command::new(env!("CARGO_BIN_EXE_metamer"));
    c.arg("measure-box")
        .args([
            "-o",
            out.to_str().unwrap(),
            "--plan",
            plan.to_str().unwrap(),
        ])
        .args(extra)
        .env_remove("METAMER_SIM_TIME_SCALE")
        .stdin(Stdio::null());
    c
}

fn run(dir: &Path, extra: &[&str]) -> Output {
    let o = command(dir, extra).output().unwrap();
    assert!(
        o.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn spectrum(v: &Value) -> Spectrum {
    let f = |k: &str| -> Vec<f64> {
        v[k].as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    Spectrum::new(f("nm"), f("values")).unwrap()
}

/// The truth as a noiseless i1Pro reports it: every spectrum at the instrument's 36 bands
/// (380–730 nm, 10 nm), what the measured scene can at best be.
fn band_limited(truth: &SimulatedBox, plan: &BoxPlan) -> Value {
    let bands = |s: &Spectrum, outside| {
        let nm: Vec<f64> = (0..36).map(|i| 380.0 + 10.0 * f64::from(i)).collect();
        let v = nm.iter().map(|&l| s.value_at(l)).collect();
        Spectrum::new(nm, v).unwrap().with_outside(outside)
    };
    scene_json(
        "band-limited truth",
        "",
        &plan.geometry,
        &BoxContents {
            wall: bands(&truth.wall, Outside::HoldEnds),
            patches: truth
                .patches
                .iter()
                .map(|p| bands(p, Outside::HoldEnds))
                .collect(),
            tiles: truth
                .tiles
                .iter()
                .map(|t| bands(t, Outside::Zero))
                .collect(),
            distribution: DistributionFile::CGamma {
                table: truth.table.clone(),
            },
            provenance: None,
        },
    )
}

#[test]
fn a_simulated_session_recovers_the_truth_and_its_scene_renders_the_box() {
    let dir = fresh_dir("e2e");
    let o = run(
        &dir,
        &["--spectral", SPECTRAL, "--spot", SPOT, "--seed", "7"],
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    let out = dir.join("out");
    let summary = json(&out.join("summary.json"));
    let scene = json(&out.join("scene.json"));
    let plan: BoxPlan = serde_json::from_str(PLAN).unwrap();
    let truth = SimulatedBox::new(&plan, 7, Scenario::DisplayWhite).unwrap();

    // Tiles: the mean of n = 2 readings with 0.1 % (1σ) noise each, within 4σ/√2, plus the
    // i1Pro's 1e-4 conversion error (its emulator's noiseless accuracy).
    for (i, t) in summary["tiles"].as_array().unwrap().iter().enumerate() {
        let y = t["stats"]["xyz"][1].as_f64().unwrap();
        let want = luminance(&truth.tiles[i]);
        let tol = 4.0 * 0.001 / 2f64.sqrt() + 1e-4;
        assert!((y / want - 1.0).abs() < tol, "tile {i}: {y} vs {want}");
    }
    // Reflectances: one reading, 0.002 absolute per band (1σ): within 4σ at every band.
    let surfaces = scene["surfaces"].as_array().unwrap();
    for s in surfaces {
        let Some(k) = s["patch"].as_u64() else {
            continue;
        };
        let measured = spectrum(&s["reflectance"]);
        let want = &truth.patches[k as usize - 1];
        for (&nm, &v) in measured.wavelengths_nm().iter().zip(measured.values()) {
            assert!(
                (v - want.value_at(nm)).abs() < 4.0 * 0.002,
                "patch {k} at {nm} nm: {v} vs {}",
                want.value_at(nm)
            );
        }
    }
    let wall = spectrum(&surfaces[0]["reflectance"]);
    assert!((wall.value_at(550.0) - truth.wall.value_at(550.0)).abs() < 0.008);
    // One emitter, its 9 tiles each with its own spectrum, the fitted C-γ table.
    let emitters = scene["emitters"].as_array().unwrap();
    assert_eq!(emitters.len(), 1);
    assert_eq!(emitters[0]["tiles"].as_array().unwrap().len(), 9);
    assert_eq!(emitters[0]["distribution"]["kind"], "c_gamma");
    let table: CGammaTable =
        serde_json::from_value(emitters[0]["distribution"]["table"].clone()).unwrap();
    // Fall-off: in each measured half-plane the fitted table is the truth's cos power
    // within the meter's noise (0.1 % of each reading, relative to a 0.07 %-noisy normal)
    // plus the fit's own misfit: 0.01 is many σ.
    for (c, m) in [(0.0, 0.9), (90.0, 1.4), (180.0, 0.6), (270.0, 1.1)] {
        for g in [20.0, 40.0, 60.0] {
            let want = f64::cos(f64::to_radians(g)).powf(m);
            let got = table.at(c, g);
            assert!((got - want).abs() < 0.01, "C {c} γ {g}: {got} vs {want}");
        }
    }
    // light.json is the fit that made it; the chart and the photometric files are written.
    let light = json(&out.join("light.json"));
    assert_eq!(light["table"], emitters[0]["distribution"]["table"]);
    assert!(std::fs::read_to_string(out.join("light.svg"))
        .unwrap()
        .contains("<svg"));
    assert!(std::fs::read_to_string(out.join("light.ies"))
        .unwrap()
        .starts_with("IES:LM-63"));
    assert!(
        std::fs::read_to_string(out.join("light.ldt"))
            .unwrap()
            .lines()
            .count()
            > 20
    );
    // The scene carries its provenance: every journal hashed.
    assert_eq!(scene["provenance"]["journals"].as_array().unwrap().len(), 4);

    // The measured scene rendered against the box's spot readings. What it can differ by:
    // (a) the instrument's bands (the i1Pro sees 36 bands of 10 nm from 380 to 730 nm),
    // computed from the truth alone as the ΔE*ab between the truth's render and the render
    // of the truth at those bands; (b) the noise: spots 0.1 % of Y /√2, tiles 0.1 % /√2,
    // reflectance 0.002 absolute (at most 0.002 in Y/Y_white), as σ of L* and taken for
    // each of L*, a*, b* (√3), 4σ; (c) the render's own bound.
    let white = {
        let w = &summary["render"]["comparison"]["white"];
        Xyz::from([0, 1, 2].map(|i| w[i].as_f64().unwrap()))
    };
    let box_xyz: Vec<(usize, Xyz)> = summary["spot_xyz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let xyz = &p[1];
            (
                p[0].as_u64().unwrap() as usize,
                Xyz::from([0, 1, 2].map(|i| xyz[i].as_f64().unwrap())),
            )
        })
        .collect();
    let truth_xyz: Vec<(usize, Xyz)> = truth
        .spots()
        .unwrap()
        .iter()
        .enumerate()
        .map(|(i, &x)| (i + 1, x))
        .collect();
    let (limited, _, _) = render_scene(&band_limited(&truth, &plan)).unwrap();
    let (sys, _) = compare_readings(&truth_xyz, &limited, white, "band-limited").unwrap();
    let measured = &summary["render"]["comparison"]["patches"];
    let bounds = &summary["render"]["render_bound"];
    for (i, p) in measured.as_array().unwrap().iter().enumerate() {
        let de = p["de76"].as_f64().unwrap();
        let t = box_xyz[i].1.y / white[1];
        let rel = ((0.001f64 / 2f64.sqrt()).powi(2) * 2.0 + (0.002 / t).powi(2)).sqrt();
        let sigma_l = 116.0 / 3.0 * t.powf(1.0 / 3.0) * rel;
        let tol = sys.patches[i].de76 + 4.0 * 3f64.sqrt() * sigma_l + bounds[i].as_f64().unwrap();
        assert!(de < tol, "patch {}: ΔE*ab {de} > {tol}", i + 1);
    }
    let c = &summary["render"]["comparison"];
    println!(
        "measured scene vs box: ΔE*ab mean {:.3} max {:.3}; band-limited truth vs truth: mean {:.3} max {:.3}",
        c["mean_de76"], c["max_de76"], sys.mean_de76, sys.max_de76
    );
    assert!(
        stdout.contains("measured scene rendered vs box spots"),
        "{stdout}"
    );

    // The nominal scene (data/ spectra and gains, the nominal LDC).
    let nominal = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args([
            "render",
            "spots",
            "data/scenes/validation-box-ldc.json",
            "--json",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(
        nominal.status.success(),
        "{}",
        String::from_utf8_lossy(&nominal.stderr)
    );
    let n: Value = serde_json::from_slice(&nominal.stdout).unwrap();
    let nominal_xyz: Vec<RenderedReading> = n["patches"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let x = &p["XYZ"];
            RenderedReading::new(
                p["patch"].as_u64().unwrap() as usize,
                Xyz::from([0, 1, 2].map(|i| x[i].as_f64().unwrap())),
                white,
                Uncertainty::Bound {
                    de: 0.0,
                    regular: None,
                },
            )
        })
        .collect();
    let (nom, _) = compare_readings(&box_xyz, &nominal_xyz, white, "nominal scene").unwrap();
    println!(
        "nominal scene vs box: ΔE*ab mean {:.3} max {:.3}",
        nom.mean_de76, nom.max_de76
    );
    // The truth differs from the nominal data on purpose; measuring it must pay off.
    assert!(nom.mean_de76 > 3.0 * c["mean_de76"].as_f64().unwrap());

    // Provenance: every journal hashed, instruments named.
    let p = &summary["provenance"];
    assert_eq!(p["journals"].as_array().unwrap().len(), 4);
    assert_eq!(p["instruments"]["spectral"]["info"]["model"], "i1pro");
    assert_eq!(p["instruments"]["spot"]["info"]["model"], "cs100a");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Entry lines of a journal.
fn entries(path: &Path) -> Vec<String> {
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .lines()
        .filter(|l| l.starts_with("{\"type\":\"entry\""))
        .map(str::to_string)
        .collect()
}

/// `--box-plan adaptive` gives the plan the adaptive rule (the plan file names none): the
/// fall-off stage alone reads the first pass, 0°, ±40° and ±80° in the horizontal plane
/// and ±40° and ±80° in the vertical (the normal once), 9 of the fixed plan's 18, and the
/// journal's plan carries the default rule; without the flag the stage reads all 18.
#[test]
fn box_plan_adaptive_reads_the_first_pass() {
    let plan_of = |journal: &Path| -> Value {
        let text = std::fs::read_to_string(journal).unwrap();
        let header: Value = serde_json::from_str(text.lines().next().unwrap()).unwrap();
        serde_json::from_str(header["options"]["plan"].as_str().unwrap()).unwrap()
    };
    let angles = |journal: &Path| -> Vec<(String, f64)> {
        entries(journal)
            .iter()
            .map(|l| {
                let v: Value = serde_json::from_str(l).unwrap();
                let d = &v["data"];
                (
                    d["plane"].as_str().unwrap().to_string(),
                    d["angle_deg"].as_f64().unwrap(),
                )
            })
            .collect()
    };
    let flags = ["--spectral", SPECTRAL, "--spot", SPOT, "--stage", "falloff"];
    let adaptive = fresh_dir("box-plan-adaptive");
    let o = run(
        &adaptive,
        &[&flags[..], &["--box-plan", "adaptive"]].concat(),
    );
    let journal = adaptive.join("out/falloff.jsonl");
    assert_eq!(plan_of(&journal)["adaptive"]["max_falloff"], 12);
    let first = angles(&journal);
    let h = |a: f64| ("horizontal".to_string(), a);
    let v = |a: f64| ("vertical".to_string(), a);
    assert_eq!(
        first,
        [
            h(-80.0),
            h(-40.0),
            h(0.0),
            h(40.0),
            h(80.0),
            v(-80.0),
            v(-40.0),
            v(40.0),
            v(80.0)
        ],
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let fixed = fresh_dir("box-plan-fixed");
    run(&fixed, &flags);
    let journal = fixed.join("out/falloff.jsonl");
    assert!(plan_of(&journal)["adaptive"].is_null());
    assert_eq!(angles(&journal).len(), 18);
    for d in [adaptive, fixed] {
        std::fs::remove_dir_all(&d).unwrap();
    }
}

#[test]
fn a_session_killed_mid_stage_resumes_to_the_same_scene() {
    let quiet = [
        "--spectral",
        "sim:i1pro?time_scale=0&noise=off",
        "--spot",
        "sim:cs100a?time_scale=0&noise=off",
    ];
    let whole = fresh_dir("whole");
    run(&whole, &quiet);

    // At a twentieth of the i1Pro's pace a tile reading takes tens of milliseconds.
    let dir = fresh_dir("killed");
    let slow = [
        "--spectral",
        "sim:i1pro?time_scale=0.05&noise=off",
        "--spot",
        "sim:cs100a?time_scale=0&noise=off",
    ];
    let mut child = command(&dir, &slow)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let tiles = dir.join("out/tiles.jsonl");
    let start = Instant::now();
    while entries(&tiles).len() < 4 {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no readings arrive"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let before = entries(&tiles);
    assert!(
        before.len() < 18,
        "{} of 18 tile readings before the kill",
        before.len()
    );
    assert!(!dir.join("out/scene.json").exists());

    // Without --resume the journal is refused, not overwritten.
    let o = command(&dir, &quiet).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("continue it with --resume"), "{e}");

    // A resume must use the instruments the journal was started with (pace included).
    run(&dir, &[&slow[..], &["--resume"]].concat());
    let after = entries(&tiles);
    assert_eq!(after.len(), 18);
    assert_eq!(
        &after[..before.len()],
        &before[..],
        "readings before the kill are kept"
    );
    // Noise is off: the same readings, so the same scene; only the provenance (journal
    // paths and hashes, date, the instruments' pace) tells the two sessions apart.
    let scene = |d: &Path| {
        let mut v = json(&d.join("out/scene.json"));
        assert!(v["provenance"]["journals"].is_array());
        v.as_object_mut().unwrap().remove("provenance");
        v
    };
    assert_eq!(scene(&whole), scene(&dir));
    std::fs::remove_dir_all(&whole).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_flags_and_plans_are_usage_errors() {
    let dir = fresh_dir("usage");
    let o = command(
        &dir,
        &["--spectral", SPECTRAL, "--spot", "cs100a:/dev/null"],
    )
    .output()
    .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        String::from_utf8_lossy(&o.stderr),
        format!(
            "error: --spectral {SPECTRAL} is simulated and --spot cs100a:/dev/null is real: both \
             must be simulated (sim:…) or neither, as a simulated instrument sees only the \
             simulated box\n"
        )
    );
    let o = command(
        &dir,
        &["--spectral", SPECTRAL, "--spot", SPOT, "--repeats", "0"],
    )
    .output()
    .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("--repeats must be between 1 and 100, got 0")
    );
    let o = command(
        &dir,
        &["--spectral", SPECTRAL, "--spot", SPOT, "--stage", "lamps"],
    )
    .output()
    .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown stage 'lamps'"));
    std::fs::remove_dir_all(&dir).unwrap();
}
