//! `metamer validate` end to end on readings whose colour differences are known without
//! metamer: 24 of the CIEDE2000 test pairs of Sharma, Wu & Dalal (2005) as box and
//! display readings (`tests/reference/validate_fixture.py` made the files), so the printed
//! and written ΔE00 must be the published values and ΔE*ab the pairs' Euclidean distances.

use std::process::{Command, Output};

use crate::support::{unused_dir, validate_data};

fn validate(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_metamer"))
        .arg("validate")
        .args(args)
        .output()
        .expect("metamer runs")
}

/// (patch, ΔE*ab, ΔE00) from expected.csv.
fn expected() -> Vec<(usize, f64, f64)> {
    std::fs::read_to_string(validate_data("expected.csv"))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("patch"))
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            (
                v[0].parse().unwrap(),
                v[1].parse().unwrap(),
                v[2].parse().unwrap(),
            )
        })
        .collect()
}

#[test]
fn prints_and_writes_the_published_colour_differences() {
    let dir = unused_dir("sharma");
    let (b, d) = (validate_data("box.csv"), validate_data("display.csv"));
    let out = validate(&[
        "--reference",
        b.to_str().unwrap(),
        "--test",
        d.to_str().unwrap(),
        "-o",
        dir.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The display file's white reading is the default white.
    assert!(
        stdout.contains("white X Y Z = 95.0470 100.0000 108.8830 (the white reading of"),
        "{stdout}"
    );
    let want = expected();
    assert_eq!(want.len(), 24);
    for &(k, de76, de00) in &want {
        let row = stdout
            .lines()
            .find(|l| l.starts_with(&format!("{k:>3} ")))
            .unwrap_or_else(|| panic!("no row for patch {k}:\n{stdout}"));
        assert!(
            row.contains(&format!(" {de76:.2} ")),
            "patch {k}: want ΔE*ab {de76:.2}: {row}"
        );
        assert!(
            row.contains(&format!(" {de00:.2} ")),
            "patch {k}: want ΔE00 {de00:.2}: {row}"
        );
    }
    // The CSV carries six decimals: the published four must hold to rounding.
    let csv = std::fs::read_to_string(dir.join("validation.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 24);
    for (row, &(k, de76, de00)) in rows.iter().zip(&want) {
        assert_eq!(row[col("patch")], k.to_string());
        let got76: f64 = row[col("de76")].parse().unwrap();
        let got00: f64 = row[col("de00")].parse().unwrap();
        assert!(
            (got76 - de76).abs() < 2e-6,
            "patch {k}: ΔE*ab {got76} vs {de76}"
        );
        assert!(
            (got00 - de00).abs() < 6e-5,
            "patch {k}: ΔE00 {got00} vs {de00}"
        );
        // Every interval holds its value; the verdict follows the interval.
        let (lo, hi): (f64, f64) = (
            row[col("de76_lo")].parse().unwrap(),
            row[col("de76_hi")].parse().unwrap(),
        );
        assert!(
            lo <= got76 + 1e-9 && got76 <= hi + 0.05,
            "patch {k}: {lo} {got76} {hi}"
        );
        let verdict = if hi < 2.3 {
            "below"
        } else if lo > 2.3 {
            "above"
        } else {
            "undecided"
        };
        assert_eq!(row[col("jnd")], verdict, "patch {k}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("validation.json")).unwrap())
            .unwrap();
    assert_eq!(json["format"], "metamer-validation");
    assert_eq!(
        json["box_vs_display"]["patches"].as_array().unwrap().len(),
        24
    );
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert!(
        html.contains("id=\"fig4\"")
            && html.contains("id=\"fig5\"")
            && !html.contains("id=\"fig6\"")
    );

    // A second run refuses to replace the report; --force replaces it.
    let again = validate(&[
        "--reference",
        b.to_str().unwrap(),
        "--test",
        d.to_str().unwrap(),
        "-o",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(again.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&again.stderr).contains("--force"));
    // The box's readings again as the simulation, replacing the report each time.
    let with_simulation = |extra: &[&str]| {
        let (b, d, o) = (
            b.to_str().unwrap(),
            d.to_str().unwrap(),
            dir.to_str().unwrap(),
        );
        let mut args = vec![
            "--reference",
            b,
            "--test",
            d,
            "-o",
            o,
            "--force",
            "--simulation",
            b,
        ];
        args.extend_from_slice(extra);
        let out = validate(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        out
    };
    let forced = with_simulation(&["--propagation", "linear"]);
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert!(html.contains("id=\"fig6\"") && html.contains("id=\"fig7\""));
    // The simulation is the box itself: box vs simulation differs by exactly 0.
    let stdout = String::from_utf8_lossy(&forced.stdout);
    assert!(
        stdout.contains("simulation vs box: 24 of 24 patches below the JND"),
        "{stdout}"
    );
    // --out-of-gamut marks the patches the display cannot show, in the comparisons that
    // have the display on one side; box vs simulation never went through the display.
    with_simulation(&["--out-of-gamut", "3"]);
    let csv = std::fs::read_to_string(dir.join("validation.csv")).unwrap();
    let mut marks: Vec<(String, String)> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|c| c[1] == "3")
        .map(|c| (c[0].to_string(), c[c.len() - 1].to_string()))
        .collect();
    marks.sort();
    let want = [
        ("box_vs_display", "1"),
        ("box_vs_simulation", "0"),
        ("display_vs_simulation", "1"),
    ]
    .map(|(a, b)| (a.to_string(), b.to_string()));
    assert_eq!(marks, want);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_readings_are_errors_naming_file_and_line() {
    let dir = unused_dir("bad");
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "patch,X,Y,Z\n1,1,2,3\n2,1,two,3\n").unwrap();
    let d = validate_data("display.csv");
    let out = validate(&[
        "--reference",
        bad.to_str().unwrap(),
        "--test",
        d.to_str().unwrap(),
        "-o",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.csv:3:") && err.contains("'two'"), "{err}");
    let out = validate(&[
        "--reference",
        d.to_str().unwrap(),
        "--test",
        d.to_str().unwrap(),
        "-o",
        dir.to_str().unwrap(),
        "--white",
        "1,0,1",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--white"));
    // spot --json lines, unnumbered, one per patch in order, are readings too.
    let spot: String = (1..=24)
        .map(|k| format!("{{\"XYZ\":[{0},{0},{0}],\"xyY\":[0.3,0.3,{0}],\"flags\":[],\"instrument\":\"cs100a\"}}\n", 10 + k))
        .collect();
    let spot_file = dir.join("spot.jsonl");
    std::fs::write(&spot_file, spot).unwrap();
    let out = validate(&[
        "--reference",
        spot_file.to_str().unwrap(),
        "--test",
        d.to_str().unwrap(),
        "-o",
        dir.join("o").to_str().unwrap(),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["inputs"][0]["format"], "metamer spot --json");
    std::fs::remove_dir_all(&dir).ok();
}
