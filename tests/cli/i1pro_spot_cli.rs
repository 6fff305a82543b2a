//! `metamer spot` with the simulated i1Pro: the reading's XYZ against `metamer color xyz` of
//! the same spectrum and of the light itself, record → replay, and the reflective
//! ColorChecker with the white-tile calibration negotiated through the session operator.

use std::process::Output;
use std::sync::Arc;

use metamer::color::{colorchecker, ColorCheckerSet};
use metamer::session::ScriptedOperator;
use metamer::spot::{read, SimulatedHands};
use metamer_drivers::i1pro::emulator::{
    EmulatorConfig, REPEATABILITY_REFLECTANCE, REPEATABILITY_Y,
};
use metamer_drivers::i1pro::open::sim_with;
use metamer_drivers::i1pro::ManualClock;
use metamer_drivers::{MeasureMode, OpenOptions, SharedWorld, View, World};
use serde_json::Value;

use crate::support::{fresh_dir, metamer_in_root};

fn ok(o: &Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn xyz(line: &str) -> [f64; 3] {
    let v: Value = serde_json::from_str(line).unwrap();
    std::array::from_fn(|k| v["XYZ"][k].as_f64().unwrap())
}

/// The XYZ of the default light as the instrument's bands hold it, computed by
/// `metamer color xyz` from a CSV built here straight from the CIE table
/// (data/illuminant_led_rgb1.csv, 5 nm) at 380, 390, …, 730 nm, scaled to the 100 cd/m²
/// that `metamer color xyz` gives the whole table.
fn light_on_the_grid(dir: &std::path::Path) -> [f64; 3] {
    let full = ok(&metamer_in_root(&[
        "color",
        "xyz",
        "data/illuminant_led_rgb1.csv",
        "--json",
    ]));
    let k = 100.0 / xyz(full.trim())[1];
    let table = std::fs::read_to_string("data/illuminant_led_rgb1.csv").unwrap();
    let mut csv = String::from("nm,led\n");
    for line in table.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let (nm, v) = line.split_once(',').unwrap();
        let nm: i32 = nm.trim().parse().unwrap();
        if (380..=730).contains(&nm) && nm % 10 == 0 {
            let v: f64 = v.trim().parse().unwrap();
            csv.push_str(&format!("{nm},{}\n", v * k));
        }
    }
    let path = dir.join("led_grid.csv");
    std::fs::write(&path, csv).unwrap();
    xyz(ok(&metamer_in_root(&[
        "color",
        "xyz",
        path.to_str().unwrap(),
        "--json",
    ]))
    .trim())
}

#[test]
fn emissive_json_matches_color_xyz_of_its_spectrum_and_of_the_light() {
    let dir = fresh_dir("emissive");
    let want = light_on_the_grid(&dir);
    // Without noise: the whole-count rounding of the reading and the darks, about one count
    // in a blue band of 4000 at the sensor target.
    for (spec, tol) in [
        ("sim:i1pro?time_scale=0&noise=off", 3e-4),
        ("sim:i1pro?time_scale=0&noise=off&rev=e", 3e-4),
        ("sim:i1pro?time_scale=0&seed=7", 4.0 * REPEATABILITY_Y),
    ] {
        let csv = dir.join("spectrum.csv");
        let _ = std::fs::remove_file(&csv);
        let out = ok(&metamer_in_root(&[
            "spot",
            "--instrument",
            spec,
            "--json",
            "--spectrum",
            csv.to_str().unwrap(),
        ]));
        let line = out.trim();
        let got = xyz(line);
        let v: Value = serde_json::from_str(line).unwrap();
        assert_eq!(v["spectrum"]["start_nm"], 380.0);
        assert_eq!(v["spectrum"]["step_nm"], 10.0);
        assert_eq!(v["spectrum"]["values"].as_array().unwrap().len(), 36);
        // The CSV gives the very same XYZ through the colour core.
        let again = xyz(ok(&metamer_in_root(&[
            "color",
            "xyz",
            csv.to_str().unwrap(),
            "--json",
        ]))
        .trim());
        for k in 0..3 {
            assert!(
                (got[k] - again[k]).abs() <= 1e-12 * got[k].abs(),
                "{got:?} {again:?}"
            );
            assert!(
                (got[k] - want[k]).abs() / want[k] < tol,
                "{spec}: {got:?} vs {want:?}"
            );
        }
    }
}

#[test]
fn a_recorded_session_replays_to_the_identical_readings() {
    let dir = fresh_dir("record");
    let rec = dir.join("session.jsonl");
    let live = ok(&metamer_in_root(&[
        "spot",
        "--instrument",
        "sim:i1pro?time_scale=0",
        "--count",
        "2",
        "--json",
        "--record",
        rec.to_str().unwrap(),
    ]));
    let replayed = ok(&metamer_in_root(&[
        "spot",
        "--instrument",
        &format!("replay:{}", rec.display()),
        "--count",
        "2",
        "--json",
    ]));
    assert_eq!(live, replayed);
    assert_eq!(live.lines().count(), 2);
    // Reflective too, with its white-tile calibration in the transcript.
    let rec = dir.join("reflective.jsonl");
    let args = ["--mode", "reflective", "--integration", "auto"];
    let mut first = vec!["spot", "--instrument", "sim:i1pro?time_scale=0"];
    first.extend(args);
    let rec_arg = rec.to_str().unwrap().to_string();
    first.extend(["--record", &rec_arg]);
    let live = ok(&metamer_in_root(&first));
    let spec = format!("replay:{}", rec.display());
    let mut second = vec!["spot", "--instrument", &spec];
    second.extend(args);
    let replayed = ok(&metamer_in_root(&second));
    assert_eq!(
        live.lines().nth(1),
        replayed.lines().nth(1),
        "{live}\n{replayed}"
    );
}

#[test]
fn reflective_colorchecker_prompts_for_the_tile_once_and_again_after_expiry() {
    let patches = colorchecker(ColorCheckerSet::BabelColorAverage);
    let world = Arc::new(SharedWorld::new(View::WhiteTile));
    let clock = ManualClock::new();
    let mut m = sim_with(
        world.clone() as Arc<dyn World>,
        EmulatorConfig {
            time_scale: 0.0,
            ..EmulatorConfig::default()
        },
        &OpenOptions::default(),
        Arc::new(clock.clone()),
    )
    .unwrap();
    let mut operator = ScriptedOperator::confirming();
    for (i, patch) in patches.iter().enumerate() {
        if i == 16 {
            // Past the white calibration's hour.
            clock.advance(3600.5);
        }
        let target = View::surface(patch.clone()).unwrap();
        world.set(target.clone());
        let hands = SimulatedHands {
            world: world.clone(),
            target,
        };
        let r = read(
            m.as_mut(),
            MeasureMode::Reflective,
            &mut operator,
            Some(&hands),
        )
        .unwrap();
        let s = r.spectrum.unwrap();
        for (w, v) in s.values().iter().enumerate() {
            let want = patch.value_at(380.0 + 10.0 * w as f64);
            assert!(
                (v - want).abs() < 4.0 * REPEATABILITY_REFLECTANCE,
                "patch {i} band {w}: {v} vs {want}"
            );
        }
    }
    assert_eq!(
        operator.prompts,
        vec!["i1pro: place the instrument on its white calibration tile"; 2]
    );
}

#[test]
fn bad_integration_and_modes_are_usage_or_instrument_errors() {
    let o = metamer_in_root(&[
        "spot",
        "--instrument",
        "sim:i1pro?time_scale=0",
        "--integration",
        "10",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("--integration 10: expected auto or a time in seconds from 0.004716 to 2"),
        "{e}"
    );
    let o = metamer_in_root(&[
        "spot",
        "--instrument",
        "sim:cs100a?time_scale=0",
        "--integration",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("the cs100a has no integration time"), "{e}");
    let o = metamer_in_root(&[
        "spot",
        "--instrument",
        "sim:cs100a?time_scale=0",
        "--mode",
        "ambient",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("the cs100a cannot do"), "{e}");
}
