//! Malformed input to the readers added after the first hardening pass: the light fit's
//! fall-off CSV, `validate`'s readings, IES and EULUMDAT files and the measure-box plan.
//! Each must give a clear error naming the file and line, or the same result as the
//! well-formed input.

use std::path::Path;

use metamer::light::{ies, ldt, Falloff};
use metamer::measure_box::BoxPlan;
use metamer::validation::readings::parse_readings;

use crate::support::{fresh_dir, root, root_text};

const BOM: &str = "\u{feff}";

/// An IES and an EULUMDAT file as `metamer light fit` writes them.
fn photometric_files() -> (String, String) {
    use metamer::light::ies::IesInfo;
    use metamer::light::ldt::LdtInfo;
    use metamer::light::{CGammaTable, Panel};
    let gamma: Vec<f64> = (0..=18).map(|i| 5.0 * i as f64).collect();
    let values = gamma.iter().map(|g| g.to_radians().cos()).collect();
    let table = CGammaTable::symmetric(gamma, values).unwrap();
    let panel = Panel {
        width_m: 0.3,
        height_m: 0.3,
        normal_luminance_cd_m2: 100.0,
    };
    let ies_info = IesInfo {
        test: "hardening".into(),
        issue_date: "2026-12-02".into(),
        luminaire: "panel".into(),
        generation: "metamer".into(),
        extrapolation: None,
    };
    let ldt_info = LdtInfo {
        luminaire: "panel".into(),
        file_name: "panel.ldt".into(),
        date_user: "2026-12-02".into(),
        extrapolation: None,
    };
    (
        ies::to_string(&table, &panel, &ies_info),
        ldt::to_string(&table, &panel, &ldt_info),
    )
}

#[test]
fn a_byte_order_mark_is_not_part_of_the_first_line() {
    // The fall-off file starts with a comment: behind a BOM it was taken for the header.
    let f = root_text("data/light_falloff_9_angles.csv");
    let plain = Falloff::parse_csv(&f, Path::new("f.csv")).unwrap();
    let marked = Falloff::parse_csv(&format!("{BOM}{f}"), Path::new("f.csv")).unwrap();
    assert_eq!(marked, plain);

    for rel in [
        "tests/data/validate/box.csv",
        "tests/data/validate/display.csv",
    ] {
        let r = root_text(rel);
        let plain = parse_readings(&r, Path::new("r.csv")).unwrap();
        let marked = parse_readings(&format!("{BOM}{r}"), Path::new("r.csv")).unwrap();
        assert_eq!(marked.patches, plain.patches, "{rel}");
        assert_eq!(marked.white, plain.white, "{rel}");
    }
    // JSON spot lines behind a BOM were read as a CSV without a header.
    let lines = "{\"patch\": 1, \"XYZ\": [10, 11, 12]}\n{\"patch\": 2, \"XYZ\": [20, 21, 22]}\n";
    let marked = parse_readings(&format!("{BOM}{lines}"), Path::new("spots.jsonl")).unwrap();
    assert_eq!(
        marked.patches[&2].xyz,
        metamer::color::Xyz::new(20.0, 21.0, 22.0)
    );

    // An IES file behind a BOM was read as the 1986 format (no version line).
    let (ies_text, _) = photometric_files();
    let plain = ies::parse(&ies_text, Path::new("p.ies")).unwrap();
    let marked = ies::parse(&format!("{BOM}{ies_text}"), Path::new("p.ies")).unwrap();
    assert_eq!(marked.1.format, plain.1.format);
    assert_eq!(marked.0, plain.0);

    let dir = fresh_dir("bom");
    let plan = dir.join("plan.json");
    std::fs::write(&plan, format!("{BOM}{{\"repeats\": 2}}")).unwrap();
    assert_eq!(BoxPlan::load(&plan).unwrap().repeats, 2);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The error of a reader given a one-megabyte field: the file and line, and at most 80
/// characters of the field with its length.
fn short_and_counted(e: &str, starts: &str) {
    assert!(e.starts_with(starts), "{}", &e[..e.len().min(300)]);
    assert!(
        e.contains("7x7x7x7x") && e.contains("… (100000"),
        "{}",
        &e[..e.len().min(300)]
    );
    assert!(
        e.contains(" characters in all)"),
        "{}",
        &e[..e.len().min(300)]
    );
    assert!(e.len() < 400, "{} characters", e.len());
}

#[test]
fn a_megabyte_field_is_echoed_as_80_characters() {
    let field = "7x".repeat(500_000);
    let e = Falloff::parse_csv(
        &format!("angle_deg,horizontal\n0,1\n20,{field}\n"),
        Path::new("f.csv"),
    )
    .unwrap_err()
    .to_string();
    short_and_counted(&e, "f.csv:3: horizontal: '7x7x");
    let e = Falloff::parse_csv(&format!("angle_deg,{field}\n"), Path::new("f.csv"))
        .unwrap_err()
        .to_string();
    short_and_counted(&e, "f.csv:1: expected the header");

    let e = parse_readings(&format!("patch,X,Y,Z\n1,{field},1,1\n"), Path::new("r.csv"))
        .unwrap_err()
        .to_string();
    short_and_counted(&e, "r.csv:2: X: '7x7x");
    let e = parse_readings(&format!("{field},X,Y,Z\n"), Path::new("r.csv"))
        .unwrap_err()
        .to_string();
    short_and_counted(&e, "r.csv:1: the header '7x7x");
    let e = parse_readings(
        &format!("{{\"patch\": \"{field}\", \"XYZ\": [1, 2, 3]}}\n"),
        Path::new("r.jsonl"),
    )
    .unwrap_err()
    .to_string();
    short_and_counted(&e, "r.jsonl:1: \"patch\": \"7x7x");

    let (ies_text, ldt_text) = photometric_files();
    // The first number after TILT=NONE is the lamp count.
    let at = ies_text.find("TILT=NONE\r\n").unwrap() + "TILT=NONE\r\n".len();
    let bad = format!("{}{field} {}", &ies_text[..at], &ies_text[at..]);
    let e = ies::parse(&bad, Path::new("p.ies"))
        .unwrap_err()
        .to_string();
    short_and_counted(&e, "p.ies:");
    // Line 3 of an EULUMDAT file is the symmetry indicator.
    let mut lines: Vec<&str> = ldt_text.lines().collect();
    lines[2] = &field;
    let e = ldt::parse(&lines.join("\n"), Path::new("p.ldt"))
        .unwrap_err()
        .to_string();
    short_and_counted(&e, "p.ldt:3:");
}

#[test]
fn readings_no_instrument_can_have_taken_are_refused_where_they_enter() {
    for (row, words) in [
        ("1,-1e308,1,1", "r.csv:2: not a measurement: XYZ [-1e308"),
        (
            "1,1e300,1e300,1e300",
            "r.csv:2: not a measurement: XYZ [1e300",
        ),
        (
            "1,1,1,-50",
            "r.csv:2: not a measurement: XYZ [1.0, 1.0, -50.0]",
        ),
    ] {
        let e = parse_readings(&format!("patch,X,Y,Z\n{row}\n"), Path::new("r.csv"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(words), "{row}: {e}");
    }
    // A spread of 1e308 became an infinite uncertainty once combined over the repeats.
    let e = parse_readings(
        "patch,X,Y,Z,sd_X,sd_Y,sd_Z,n\n1,10,11,12,0.1,1e308,0.1,3\n",
        Path::new("r.csv"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("r.csv:2: a standard deviation of [0.1, 1e308, 0.1]"),
        "{e}"
    );
    let e = parse_readings(
        r#"{"patches": [{"patch": 1, "XYZ": [10, 11, 12], "de_ci95": 1e300}]}"#,
        Path::new("render.json"),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("a 95 % ΔE*ab bound of 1e300"), "{e}");
    // A dark patch's noise below zero is a reading, not an impossibility.
    let ok = parse_readings("patch,X,Y,Z\n1,0.004,-0.003,0.002\n", Path::new("r.csv")).unwrap();
    assert_eq!(
        ok.patches[&1].xyz,
        metamer::color::Xyz::new(0.004, -0.003, 0.002)
    );
}

/// A scene whose light table reaches 1e300 was accepted, and the renderer then blamed the
/// reflectances ("its reflectances return more light than reaches them") and named no
/// file. The scene reader names the file and the table's value, and says why.
#[test]
fn a_light_table_brighter_than_any_light_is_named_in_the_scene_file() {
    let dir = fresh_dir("table");
    let scenes = root().join("data/scenes");
    let mut v: serde_json::Value =
        serde_json::from_str(&root_text("data/scenes/validation-box.json")).unwrap();
    // Spectrum files are relative to the scene's directory.
    fn absolute(v: &mut serde_json::Value, base: &Path) {
        match v {
            serde_json::Value::Object(m) => {
                for (k, x) in m.iter_mut() {
                    match (k.as_str(), x.as_str()) {
                        ("file", Some(f)) => *x = base.join(f).to_str().unwrap().into(),
                        _ => absolute(x, base),
                    }
                }
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(|x| absolute(x, base)),
            _ => {}
        }
    }
    absolute(&mut v, &scenes);
    let gamma: Vec<f64> = (0..=90).map(f64::from).collect();
    let mut values: Vec<f64> = gamma.iter().map(|g| g.to_radians().cos()).collect();
    values[89] = 1e300;
    v["emitters"][0]["distribution"] = serde_json::json!({
        "kind": "c_gamma",
        "table": {"c_deg": [0], "gamma_deg": gamma, "values": [values]},
    });
    let scene = dir.join("bright.json");
    std::fs::write(&scene, v.to_string()).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(["render", "spots"])
        .arg(&scene)
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("bright.json: emitters[0].distribution.table: values[0][89] (C 0°, γ 89°)")
            && e.contains("at most 1e6 times the normal's; got 1.000e300"),
        "{e}"
    );
    assert!(!e.contains("reflectances"), "{e}");
}
