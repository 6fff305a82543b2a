//! Malformed input to the commands added after the first hardening pass: `validate`,
//! resumed journals edited by hand, the experiment's given box, `light fit`, inputs that
//! never end, and counts that cannot be measured. Each must fail at once with a clear
//! error, before any work and without writing anything.

use std::path::Path;
use std::process::Output;
use std::time::{Duration, Instant};

use serde_json::{json, Value};

use crate::support::{fresh_dir, metamer_unscaled, root, root_text, stderr};

#[test]
fn validate_refuses_what_cannot_be_computed_before_reading_anything() {
    let d = root().join("tests/data/validate");
    let (box_csv, display_csv) = (d.join("box.csv"), d.join("display.csv"));
    let dir = fresh_dir("validate");
    let out = dir.join("out");
    let run = |extra: &[&str], reference: &Path| {
        let args = [
            &[
                "validate",
                "--reference",
                reference.to_str().unwrap(),
                "--test",
                display_csv.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ][..],
            extra,
        ]
        .concat();
        let start = Instant::now();
        let o = metamer_unscaled(&args);
        (o, start.elapsed())
    };
    for (extra, words) in [
        // usize::MAX draws: a capacity overflow panic.
        (
            &["--draws", "18446744073709551615"][..],
            "--draws 18446744073709551615: at most 10000000",
        ),
        (&["--white", "1e308,1e308,1e308"], "--white: not a white"),
        (
            &["--model-term", "1e308"],
            "--model-term 1e308: must be a ΔE*ab from 0 to 1000",
        ),
    ] {
        let (o, _) = run(extra, &box_csv);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(words), "{extra:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    }
    // X = −1e308 in the readings made the report's axis loop without end.
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "patch,X,Y,Z\n1,-1e308,1,1\n").unwrap();
    let (o, took) = run(&[], &bad);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("bad.csv:2: not a measurement"),
        "{}",
        stderr(&o)
    );
    assert!(took < Duration::from_secs(10), "{took:?}");
    assert!(!out.exists(), "nothing written");
    std::fs::remove_dir_all(&dir).unwrap();
}

const CHARACTERIZE: [&str; 6] = [
    "characterize",
    "--display",
    "virtual:ideal-crt",
    "--ramp-steps",
    "3",
    "-o",
];

fn characterize(dir: &Path, instrument: &str, extra: &[&str]) -> Output {
    let args = [
        &CHARACTERIZE[..],
        &[dir.to_str().unwrap(), "--instrument", instrument],
        extra,
    ]
    .concat();
    metamer_unscaled(&args)
}

#[test]
fn a_journal_edited_to_hold_an_impossible_reading_is_refused_on_resume() {
    let dir = fresh_dir("journal");
    let run = dir.join("run");
    let sim = "sim:cs100a?time_scale=0";
    let o = characterize(&run, sim, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let log = run.join("log.jsonl");
    let mut lines: Vec<String> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    let mut entry: Value = serde_json::from_str(&lines[3]).unwrap();
    entry["reading"]["xyz"][0] = json!(-1e308);
    lines[3] = entry.to_string();
    std::fs::write(&log, lines.join("\n") + "\n").unwrap();
    let profile = std::fs::read(run.join("profile.json")).unwrap();
    let o = characterize(&run, sim, &["--resume", "--force"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    // It used to be fitted, and failed in words about a singular matrix.
    assert!(
        e.contains(&format!("{}, line 4: step 2", log.display()))
            && e.contains("not a measurement: XYZ [-1e308"),
        "{e}"
    );
    assert_eq!(std::fs::read(run.join("profile.json")).unwrap(), profile);

    // Any other setting of the simulated meter than the journal's is refused by name.
    let fresh = dir.join("fresh");
    assert!(characterize(&fresh, sim, &[]).status.success());
    for (instrument, extra, words) in [
        ("sim:cs100a?time_scale=0&noise=off", &[][..], "noise"),
        ("sim:cs100a?time_scale=0&seed=2", &[], "seed"),
        (
            sim,
            &["--speed", "slow"],
            "--speed was fast, this session's is slow",
        ),
        ("sim:i1pro?time_scale=0", &[], "this session has i1pro"),
    ] {
        let o = characterize(&fresh, instrument, &[&["--resume"], extra].concat());
        assert_eq!(o.status.code(), Some(1), "{instrument}: {}", stderr(&o));
        assert!(stderr(&o).contains(words), "{instrument}: {}", stderr(&o));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The validation box scene with its files named by absolute path, so it can be written
/// anywhere.
fn portable_box() -> Value {
    fn absolute(v: &mut Value, base: &Path) {
        match v {
            Value::Object(m) => {
                for (k, x) in m.iter_mut() {
                    match (k.as_str(), x.as_str()) {
                        ("file", Some(f)) => *x = json!(base.join(f).to_str().unwrap()),
                        _ => absolute(x, base),
                    }
                }
            }
            Value::Array(a) => a.iter_mut().for_each(|x| absolute(x, base)),
            _ => {}
        }
    }
    let scenes = root().join("data/scenes");
    let mut v: Value = serde_json::from_str(&root_text("data/scenes/validation-box.json")).unwrap();
    absolute(&mut v, &scenes);
    v
}

#[test]
fn the_experiment_checks_a_given_box_and_its_instruments_before_any_work() {
    let dir = fresh_dir("experiment");
    let spots = root().join("tests/data/report/experiment/box/spots.csv");
    let scene = dir.join("box.json");
    std::fs::write(&scene, portable_box().to_string()).unwrap();
    let mut dark = portable_box();
    dark["emitters"][0]["luminance_cd_m2"] = json!(0.0);
    let dark_scene = dir.join("dark.json");
    std::fs::write(&dark_scene, dark.to_string()).unwrap();
    let nan_spots = dir.join("nan.csv");
    std::fs::write(
        &nan_spots,
        std::fs::read_to_string(&spots)
            .unwrap()
            .replacen("\n1,", "\n1,NaN", 1),
    )
    .unwrap();
    let huge_spots = dir.join("huge.csv");
    let first = std::fs::read_to_string(&spots).unwrap();
    let row = first.lines().nth(1).unwrap();
    let cells: Vec<&str> = row.split(',').collect();
    let bad_row = format!("{},-1e308,{}", cells[0], cells[2..].join(","));
    std::fs::write(&huge_spots, first.replacen(row, &bad_row, 1)).unwrap();
    let out = dir.join("out");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    for (scene, spots, extra, words) in [
        // Every stage ran, then the validation drew an infinite ΔE.
        (
            &scene,
            &huge_spots,
            None,
            "huge.csv:2: not a measurement: XYZ [-1e308",
        ),
        (
            &dark_scene,
            &spots,
            None,
            "emitters: the scene emits no light",
        ),
        (&scene, &nan_spots, None, "nan.csv"),
        (
            &scene,
            &spots,
            Some("sim:cs100a?time_scale=1e308"),
            "time_scale=\"1e308\" is not a number from 0 to 1000",
        ),
    ] {
        let mut args = vec![
            "experiment".to_string(),
            "-o".into(),
            s(&out),
            "--box-scene".into(),
            s(scene),
            "--box-spots".into(),
            s(spots),
        ];
        if let Some(spec) = extra {
            args.extend(["--spot".to_string(), spec.to_string()]);
        }
        let start = Instant::now();
        let o = metamer_unscaled(&args.iter().map(String::as_str).collect::<Vec<_>>());
        assert_eq!(o.status.code(), Some(1), "{words}: {}", stderr(&o));
        assert!(stderr(&o).contains(words), "{words}: {}", stderr(&o));
        // Before: the simulation was rendered first (ten seconds), then this was found.
        assert!(
            !out.join("simulation").exists(),
            "{words}: the simulation ran"
        );
        assert!(start.elapsed() < Duration::from_secs(5), "{words}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn light_fit_checks_its_panel_and_outputs_before_fitting_or_writing() {
    let dir = fresh_dir("light");
    let falloff = dir.join("falloff.csv");
    std::fs::write(
        &falloff,
        "angle_deg,horizontal\n-60,0.5\n-30,0.8\n0,1\n30,0.8\n60,0.5\n",
    )
    .unwrap();
    let s = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let fit = |extra: &[&str]| {
        let f = s("falloff.csv");
        let out = s("light.json");
        metamer_unscaled(&[&["light", "fit", "--falloff", &f, "-o", &out][..], extra].concat())
    };
    let (ies_out, ldt_out) = (s("p.ies"), s("p.ldt"));
    for (extra, words) in [
        (
            vec![
                "--ies",
                &ies_out,
                "--width-m",
                "0",
                "--height-m",
                "0.3",
                "--luminance",
                "100",
            ],
            "panel width must be a positive number of at most 1e3 m, got 0.0",
        ),
        (
            vec![
                "--ies",
                &ies_out,
                "--width-m",
                "0.3",
                "--height-m",
                "0.3",
                "--luminance",
                "1e308",
            ],
            "at most 1e10 cd/m², got 1e308",
        ),
        (
            vec!["--ies", &ies_out, "--width-m", "0.3", "--height-m", "0.3"],
            "the readings are relative",
        ),
        // The IES file was written, then the EULUMDAT file refused as "existing".
        (
            vec![
                "--ies",
                &ies_out,
                "--ldt",
                &ies_out,
                "--width-m",
                "0.3",
                "--height-m",
                "0.3",
                "--luminance",
                "100",
            ],
            "is given for two outputs",
        ),
        (
            vec![
                "--ldt",
                &ldt_out,
                "--chart",
                &ldt_out,
                "--width-m",
                "0.3",
                "--height-m",
                "0.3",
                "--luminance",
                "100",
            ],
            "is given for two outputs",
        ),
    ] {
        let o = fit(&extra);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(words), "{extra:?}: {}", stderr(&o));
        // Refused before the fit: nothing printed, nothing written.
        assert!(
            o.stdout.is_empty(),
            "{}",
            String::from_utf8_lossy(&o.stdout)
        );
        for f in ["light.json", "p.ies", "p.ldt"] {
            assert!(!dir.join(f).exists(), "{extra:?}: {f} written");
        }
    }
    // Readings of 1e300 were fitted and written as 300-digit candela.
    std::fs::write(
        &falloff,
        "angle_deg,horizontal\n-30,1e300\n0,1e300\n30,1e300\n",
    )
    .unwrap();
    let o = fit(&[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("at -30°: luminance 1e300 must be finite, ≥ 0 and at most 1e10"),
        "{}",
        stderr(&o)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_device_that_never_ends_is_refused_as_an_input_file() {
    let dir = fresh_dir("devzero");
    let d = root().join("tests/data/dispread_analytic.ti3");
    let profile = dir.join("p.json");
    let o = metamer_unscaled(&[
        "fit",
        "--measurements",
        d.to_str().unwrap(),
        "-o",
        profile.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let p = profile.to_str().unwrap();
    let ies = dir.join("zero.ies");
    std::os::unix::fs::symlink("/dev/zero", &ies).unwrap();
    let (ies, out) = (ies.to_str().unwrap(), dir.join("out"));
    let out = out.to_str().unwrap();
    let plan = [
        "measure-box",
        "-o",
        out,
        "--spectral",
        "sim:i1pro",
        "--spot",
        "sim:cs100a",
    ];
    for args in [
        &[
            "verify",
            "--profile",
            "/dev/zero",
            "--measurements",
            "/dev/zero",
        ][..],
        &["verify", "--profile", p, "--measurements", "/dev/zero"],
        &["light", "fit", "--falloff", "/dev/zero", "-o", out],
        &["light", "show", ies],
        &[&plan[..], &["--plan", "/dev/zero"]].concat(),
    ] {
        let start = Instant::now();
        let o = metamer_unscaled(args);
        assert!(!o.status.success(), "{args:?}");
        let e = stderr(&o);
        // It used to read until the memory ran out.
        assert!(
            e.contains("more than 256 MB, larger than any file of this kind"),
            "{args:?}: {e}"
        );
        assert!(start.elapsed() < Duration::from_secs(20), "{args:?}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_billion_repeats_is_refused_before_measuring() {
    let dir = fresh_dir("repeats");
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    let spots = root().join("tests/data/report/experiment/box/spots.csv");
    let scene = root().join("data/scenes/validation-box.json");
    let given = [
        "--box-scene",
        scene.to_str().unwrap(),
        "--box-spots",
        spots.to_str().unwrap(),
    ];
    for args in [
        &["lab", "-o", out, "--repeats", "1000000000"][..],
        &[
            &["experiment", "-o", out, "--repeats", "1000000000"][..],
            &given,
        ]
        .concat(),
    ] {
        let o = metamer_unscaled(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("--repeats must be from 1 to 100, got 1000000000"),
            "{}",
            stderr(&o)
        );
        assert!(!Path::new(out).exists());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A measuring plan of no name, or a held-out set of no patch, is refused by its flag before
/// anything is written, on both commands that take the measuring plan; `--help` names both
/// plans.
#[test]
fn a_measuring_plan_is_refused_by_its_flag_before_measuring() {
    let dir = fresh_dir("measuring");
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    for command in ["lab", "experiment"] {
        for (flags, expect) in [
            (&["--measuring", "quick"][..], "paper or lean"),
            (
                &["--measuring", "lean", "--held-out", "0"][..],
                "--held-out must be at least 1",
            ),
            (
                &["--measuring", "lean", "--stop-de", "0"][..],
                "--stop-de must be a ΔE*ab above 0",
            ),
        ] {
            let args = [&[command, "-o", out, "--spectral", "sim:i1pro"][..], flags].concat();
            let args = if command == "lab" {
                [&args[..3], &args[5..]].concat()
            } else {
                args
            };
            let o = metamer_unscaled(&args);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
            assert!(stderr(&o).contains(expect), "{args:?}: {}", stderr(&o));
            assert!(!Path::new(out).exists());
        }
        let help = metamer_unscaled(&[command, "--help"]);
        let help = String::from_utf8_lossy(&help.stdout);
        assert!(
            help.contains("--measuring") && help.contains("paper") && help.contains("lean"),
            "{help}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A white in other units than the readings (`--white 0.95,1,1.09` against cd/m²: L* 290)
/// or of 1e-300 gave NaN and infinite colour differences with exit 0; readings taken on the
/// instrument's lamp (reflectance, white = 100) were compared as light without a word.
/// Each is refused before anything is written, naming the file or the option.
#[test]
fn validate_refuses_a_white_or_readings_in_other_units() {
    let d = root().join("tests/data/validate");
    let dir = fresh_dir("units");
    let out = dir.join("out");
    let display = d.join("display.csv");
    let validate = |reference: &Path, extra: &[&str]| {
        let args = [
            &[
                "validate",
                "--reference",
                reference.to_str().unwrap(),
                "--test",
                display.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ][..],
            extra,
        ]
        .concat();
        metamer_unscaled(&args)
    };
    // The readings here are relative to a white of Y = 100.
    let box_csv = d.join("box.csv");
    for (white, words) in [
        ("0.95,1,1.09", "different units (a relative white"),
        ("1e-300,1e-300,1e-300", "different units"),
        ("1e-300,1,1", "is not a white: its chromaticity"),
        (
            "1e6,1.05e6,1.1e6",
            "every reading is black against this white",
        ),
    ] {
        let o = validate(&box_csv, &["--white", white]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{white}: {e}");
        assert!(e.contains("--white: ") && e.contains(words), "{white}: {e}");
        assert!(!e.contains("NaN") && !e.contains("inf"), "{e}");
        assert!(!out.exists(), "nothing written");
    }
    // A box journal of reflectances (the materials stage) as the box's readings.
    let header = r#"{"type":"header","format":"metamer-session-journal","version":2,"kind":"measure-box","fingerprint":"x","options":{},"steps":24,"started_s":0,"data":{"instruments":{},"details":null}}"#;
    let mut journal = String::from(header) + "\n";
    for patch in 1..=24 {
        journal += &format!(
            r#"{{"type":"entry","index":{i},"label":"reflectance {patch} #1","role":"spectral","mode":"reflective","data":{{"stage":"materials","target":"patch","patch":{patch},"repeat":0}},"reading":{{"xyz":[30,31,32],"xyy":[0.32,0.33,31],"spectrum":null,"flags":[],"integration_s":null,"instrument":"i1pro","timestamp_s":0}}}}"#,
            i = patch - 1
        );
        journal.push('\n');
    }
    let materials = dir.join("materials.jsonl");
    std::fs::write(&materials, journal).unwrap();
    let o = validate(&materials, &[]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("materials.jsonl: its readings were taken in reflective mode")
            && e.contains("line 2")
            && e.contains("not luminances"),
        "{e}"
    );
    assert!(!out.exists(), "nothing written");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A repeat count out of range is named where it was written: in the plan file as the
/// plan's field, on the command line as the flag (so the user edits the right one).
#[test]
fn a_bad_repeat_count_is_named_where_it_was_written() {
    let dir = fresh_dir("plan-repeats");
    let plan = dir.join("plan.json");
    std::fs::write(
        &plan,
        r#"{"repeats": 0, "geometry": {"rows": 3, "cols": 3}}"#,
    )
    .unwrap();
    let sim = [
        "--spectral",
        "sim:i1pro?time_scale=0",
        "--spot",
        "sim:cs100a?time_scale=0",
    ];
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    let in_plan = metamer_unscaled(
        &[
            &["measure-box", "-o", out, "--plan", plan.to_str().unwrap()][..],
            &sim,
        ]
        .concat(),
    );
    assert_eq!(in_plan.status.code(), Some(2), "{}", stderr(&in_plan));
    assert_eq!(
        stderr(&in_plan).trim(),
        "error: plan: repeats: must be between 1 and 100, got 0"
    );
    let on_flag =
        metamer_unscaled(&[&["measure-box", "-o", out, "--repeats", "0"][..], &sim].concat());
    assert_eq!(on_flag.status.code(), Some(2), "{}", stderr(&on_flag));
    assert_eq!(
        stderr(&on_flag).trim(),
        "error: --repeats must be between 1 and 100, got 0"
    );
    // Refused before anything was written.
    assert!(!Path::new(out).exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
