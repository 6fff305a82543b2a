//! Photometric files as other tools write them, and inputs that must not be fitted or read
//! as something else, through the binary: Windows-1252 labels are read, values that
//! cannot be told apart are refused with the file and line, `light show` keeps its
//! columns, and `light fit` never writes a number that is not finite.

use std::path::Path;
use std::process::Command;

use crate::support::fresh_dir;

/// Exit code, stdout, stderr of `metamer args…` in `dir`.
fn run(dir: &Path, args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Fits the project's nine-angle falloff and writes it as `p.ldt` in `dir`.
fn write_ldt(dir: &Path) {
    let csv = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/light_falloff_9_angles.csv"
    );
    let args = [
        "light",
        "fit",
        "--falloff",
        csv,
        "-o",
        "l.json",
        "--ldt",
        "p.ldt",
        "--width-m",
        "0.3",
        "--height-m",
        "0.3",
        "--luminance",
        "1000",
    ];
    let (code, out, err) = run(dir, &args);
    assert_eq!(code, Some(0), "{out}{err}");
}

/// A rotationally symmetric Lambertian panel of 0.6 m × 0.6 m at 1000 cd/m² (I₀ = 360
/// cd, I = 360·cos γ), its keyword lines in Windows-1252 as a European manufacturer's
/// tool writes them: ü (0xFC), a no-break space (0xA0) in the catalogue number, the
/// degree sign (0xB0) and the euro sign (0x80, where Latin-1 has a control code).
fn windows_1252_ies(tilt: &[u8], data: &[u8]) -> Vec<u8> {
    let mut f: Vec<u8> = Vec::new();
    f.extend_from_slice(b"IESNA:LM-63-2002\r\n[TEST] 4711\r\n");
    f.extend_from_slice(b"[MANUFAC] Leuchten M\xfcller GmbH\r\n");
    f.extend_from_slice(b"[LUMCAT] PL\xa0600\r\n");
    f.extend_from_slice(b"[LUMINAIRE] panel 60\xb060 cm, 12\x80\r\n");
    f.extend_from_slice(tilt);
    f.extend_from_slice(b"1 -1 1 4 1 1 2 0.6 0.6 0\r\n1 1 40\r\n0 30 60 90\r\n0\r\n");
    f.extend_from_slice(data);
    f
}

const LAMBERTIAN: &[u8] = b"360 311.769 180 0\r\n";

#[test]
fn an_ies_with_windows_1252_labels_reads_as_the_other_readers_read_it() {
    let dir = fresh_dir("cp1252");
    std::fs::write(
        dir.join("panel.ies"),
        windows_1252_ies(b"TILT=NONE\r\n", LAMBERTIAN),
    )
    .unwrap();
    let (code, out, err) = run(&dir, &["light", "show", "panel.ies"]);
    assert_eq!(code, Some(0), "{out}{err}");
    assert!(out.contains("text lines read as Windows-1252"), "{out}");
    for label in [
        "MANUFAC     Leuchten Müller GmbH",
        "LUMCAT      PL\u{a0}600",
        "LUMINAIRE   panel 60°60 cm, 12€",
    ] {
        assert!(out.contains(label), "{label} missing from\n{out}");
    }
    // The numbers are ASCII either way: I₀ = 360 cd over 0.36 m² is 1000 cd/m², and a
    // Lambertian panel sends π·I₀ = 1130.97 lm.
    assert!(out.contains("normal 360.00 cd"), "{out}");
    assert!(out.contains("normal luminance 1000.0 cd/m²"), "{out}");
    assert!(out.contains("flux 1131.0 lm"), "{out}");
    // The same file in UTF-8 says nothing about an encoding.
    let utf8 = String::from_utf8(
        windows_1252_ies(b"TILT=NONE\r\n", LAMBERTIAN)
            .iter()
            .map(|&b| if b < 0x80 { b } else { b'x' })
            .collect(),
    )
    .unwrap();
    std::fs::write(dir.join("ascii.ies"), utf8).unwrap();
    let (code, out, _) = run(&dir, &["light", "show", "ascii.ies"]);
    assert_eq!(code, Some(0));
    assert!(!out.contains("Windows-1252"), "{out}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_ldt_with_windows_1252_labels_reads() {
    let dir = fresh_dir("ldt1252");
    write_ldt(&dir);
    let written = std::fs::read(dir.join("p.ldt")).unwrap();
    let first_break = written.iter().position(|&b| b == b'\r').unwrap();
    let mut latin = b"Leuchten M\xfcller".to_vec();
    latin.extend_from_slice(&written[first_break..]);
    std::fs::write(dir.join("m.ldt"), latin).unwrap();
    let (code, out, err) = run(&dir, &["light", "show", "m.ldt"]);
    assert_eq!(code, Some(0), "{out}{err}");
    assert!(out.contains("company     Leuchten Müller"), "{out}");
    assert!(out.contains("text lines read as Windows-1252"), "{out}");
    assert!(out.contains("normal 90.000 cd"), "{out}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn light_show_keeps_its_columns_for_large_and_tiny_values() {
    let dir = fresh_dir("columns");
    // I₀ = 1 cd; at 75° 10 cd, i.e. f = 10/cos 75° = 38.6; at 30° 1e-7 cd.
    let text = "IES:LM-63-2019\r\n[TEST] columns\r\nTILT=NONE\r\n\
                1 -1 1 7 1 1 2 0.01 0.01 0\r\n1 1 0\r\n0 15 30 45 60 75 90\r\n0\r\n\
                1 0.5 0.0000001 0.3 2 10 0\r\n";
    std::fs::write(dir.join("c.ies"), text).unwrap();
    let (code, out, err) = run(&dir, &["light", "show", "c.ies"]);
    assert_eq!(code, Some(0), "{out}{err}");
    let table: Vec<&str> = out
        .lines()
        .skip_while(|l| !l.contains("relative luminance f(C, γ)"))
        .skip(1)
        .collect();
    assert_eq!(table.len(), 5, "{out}");
    let width = table[0].chars().count();
    for row in &table[1..] {
        // A label and seven values, each its own column, every row as wide as the header.
        assert_eq!(row.split_whitespace().count(), 8, "{row}");
        assert_eq!(row.chars().count(), width, "{out}");
    }
    assert!(table[1].contains(" 38.637 "), "{out}");
    assert!(table[1].contains(" 1.155e-7 "), "{out}");
    assert!(out.contains("candela: 0 … 10.000 cd"), "{out}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_ies_value_with_a_comma_inside_is_refused_with_its_line() {
    let dir = fresh_dir("comma");
    std::fs::write(
        dir.join("d.ies"),
        windows_1252_ies(b"TILT=NONE\r\n", b"360 311,769 180 0\r\n"),
    )
    .unwrap();
    let (code, _, err) = run(&dir, &["light", "show", "d.ies"]);
    assert_ne!(code, Some(0));
    assert!(
        err.contains("d.ies:11: '311,769': a comma inside a value"),
        "{err}"
    );
    // Commas that separate values are the format's own.
    std::fs::write(
        dir.join("c.ies"),
        windows_1252_ies(b"TILT=NONE\r\n", b"360,311.769, 180, 0\r\n"),
    )
    .unwrap();
    let (code, out, err) = run(&dir, &["light", "show", "c.ies"]);
    assert_eq!(code, Some(0), "{out}{err}");
    // A value too many after the table: the counts and the numbers disagree.
    std::fs::write(
        dir.join("t.ies"),
        windows_1252_ies(b"TILT=NONE\r\n", b"360 311.769 180 0 7\r\n"),
    )
    .unwrap();
    let (code, _, err) = run(&dir, &["light", "show", "t.ies"]);
    assert_ne!(code, Some(0));
    assert!(
        err.contains("t.ies:11: 1 value(s) after the last candela value"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_tilt_table_of_the_wrong_length_is_named_as_such() {
    let dir = fresh_dir("tilt");
    let with_tilt = |factors: &[u8]| {
        let mut t = b"TILT=INCLUDE\r\n1\r\n3\r\n0 45 90\r\n".to_vec();
        t.extend_from_slice(factors);
        windows_1252_ies(&t, LAMBERTIAN)
    };
    std::fs::write(dir.join("ok.ies"), with_tilt(b"1 0.95 0.9\r\n")).unwrap();
    let (code, out, err) = run(&dir, &["light", "show", "ok.ies"]);
    assert_eq!(code, Some(0), "{out}{err}");
    // One factor short: the table takes the lamp count from the next line, and every
    // field after it shifts (this was reported as a wrong photometric type).
    std::fs::write(dir.join("short.ies"), with_tilt(b"1 0.95\r\n")).unwrap();
    let (code, _, err) = run(&dir, &["light", "show", "short.ies"]);
    assert_ne!(code, Some(0));
    assert!(
        err.contains("short.ies:11: the TILT=INCLUDE table ends in the middle of line 11"),
        "{err}"
    );
    assert!(!err.contains("photometric type"), "{err}");
    std::fs::write(dir.join("long.ies"), with_tilt(b"1 0.95 0.9 0.8\r\n")).unwrap();
    let (code, _, err) = run(&dir, &["light", "show", "long.ies"]);
    assert_ne!(code, Some(0));
    assert!(
        err.contains("long.ies:10: the TILT=INCLUDE table ends"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_ldt_listing_a_c_plane_twice_is_refused_with_its_line() {
    let dir = fresh_dir("ldtdup");
    write_ldt(&dir);
    let text = std::fs::read_to_string(dir.join("p.ldt")).unwrap();
    let mut lines: Vec<&str> = text.split("\r\n").collect();
    // 26 header lines, one lamp set of six, ten direct ratios: the C angles from line 43,
    // 0°, 5°, 10°, …
    assert_eq!((lines[42], lines[43], lines[44]), ("0", "5", "10"));
    lines[44] = "5";
    std::fs::write(dir.join("dup.ldt"), lines.join("\r\n")).unwrap();
    let (code, _, err) = run(&dir, &["light", "show", "dup.ldt"]);
    assert_ne!(code, Some(0));
    assert!(
        err.contains("dup.ldt:45: the C angles must increase: C5° then C5°"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn light_fit_never_writes_a_number_that_is_not_finite() {
    let dir = fresh_dir("tiny");
    // A normal reading of 1e-300 made every other reading 1e300 times it: the fit's sums
    // of squares overflowed and light.json held nulls where numbers belong.
    std::fs::write(
        dir.join("tiny.csv"),
        "angle_deg,horizontal,vertical\n-40,0.8,0.8\n-20,0.9,0.9\n0,1e-300,1e-300\n20,0.9,0.9\n40,0.8,0.8\n",
    )
    .unwrap();
    let (code, out, err) = run(
        &dir,
        &["light", "fit", "--falloff", "tiny.csv", "-o", "l.json"],
    );
    assert_ne!(code, Some(0), "{out}");
    assert!(
        err.contains("tiny.csv: the horizontal plane at -40°: the reading 8e-1 is 8.000e299 times the normal luminance 1e-300"),
        "{err}"
    );
    assert!(!dir.join("l.json").exists());
    // Both planes look along the normal at 0°: readings a factor of 10 apart are an error
    // in one of them, not a distribution.
    std::fs::write(
        dir.join("apart.csv"),
        "angle_deg,horizontal,vertical\n-40,0.8,0.08\n-20,0.9,0.09\n0,1,0.1\n20,0.9,0.09\n40,0.8,0.08\n",
    )
    .unwrap();
    let (code, _, err) = run(
        &dir,
        &["light", "fit", "--falloff", "apart.csv", "-o", "l.json"],
    );
    assert_ne!(code, Some(0));
    assert!(err.contains("differ by a factor of 10.000"), "{err}");
    // Tiny but consistent readings (any unit) fit, and every number written is finite.
    std::fs::write(
        dir.join("small.csv"),
        "angle_deg,horizontal,vertical\n-40,0.8e-300,0.8e-300\n-20,0.9e-300,0.9e-300\n0,1e-300,1e-300\n20,0.9e-300,0.9e-300\n40,0.8e-300,0.8e-300\n",
    )
    .unwrap();
    let (code, out, err) = run(
        &dir,
        &["light", "fit", "--falloff", "small.csv", "-o", "l.json"],
    );
    assert_eq!(code, Some(0), "{out}{err}");
    let json = std::fs::read_to_string(dir.join("l.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    // serde writes a number that is not finite as null: every fitted candidate's scores
    // are numbers.
    for c in v["candidates"].as_array().unwrap() {
        if !c["halves"].as_array().unwrap().is_empty() {
            assert!(c["rms"].is_f64(), "{c}");
        }
    }
    assert_eq!(v["normal_luminance"], 1e-300);
    assert!(out.contains("normal luminance 1.000e-300"), "{out}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_light_table_past_a_million_times_the_normal_is_refused_in_a_scene_with_its_file() {
    let dir = fresh_dir("bigtable");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
    std::fs::create_dir_all(dir.join("scenes")).unwrap();
    for csv in [
        "colorchecker_babelcolor_average.csv",
        "display_white_ips_lcd.csv",
        "paper_white_reflectance.csv",
    ] {
        std::fs::copy(data.join(csv), dir.join(csv)).unwrap();
    }
    // 10 cd along the normal, 1e300 cd at 45°: f = 1e300/(10·cos 45°) = 1.414e299. This
    // went into the radiosity solver, overflowed, and was reported as reflectances that
    // return more light than reaches them, naming no file.
    std::fs::write(
        dir.join("big.ies"),
        "IES:LM-63-2019\r\n[TEST] big\r\nTILT=NONE\r\n1 -1 1 3 1 1 2 0.3 0.3 0\r\n\
         1 1 0\r\n0 45 90\r\n0\r\n10 1e300 0\r\n",
    )
    .unwrap();
    let mut scene: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(data.join("scenes/validation-box.json")).unwrap(),
    )
    .unwrap();
    scene["emitters"][0]["distribution"] = serde_json::json!({"kind": "ies", "file": "../big.ies"});
    std::fs::write(dir.join("scenes/ies.json"), scene.to_string()).unwrap();
    let table =
        serde_json::json!({"c_deg": [0], "gamma_deg": [0, 45, 90], "values": [[1, 1e300, 0]]});
    scene["emitters"][0]["distribution"] = serde_json::json!({"kind": "c_gamma", "table": table});
    std::fs::write(dir.join("scenes/inline.json"), scene.to_string()).unwrap();
    for (file, words) in [
        (
            "scenes/ies.json",
            "scenes/ies.json: emitters[0].distribution.file: scenes/../big.ies: values[0][1] (C 0°, γ 45°)",
        ),
        ("scenes/inline.json", "emitters[0].distribution.table: "),
    ] {
        let (code, out, err) = run(&dir, &["render", "spots", file, "--max-seconds", "20"]);
        assert_eq!(code, Some(1), "{out}{err}");
        assert!(err.contains(words), "{err}");
        assert!(!err.contains("reflectance"), "{err}");
    }
    let (_, _, err) = run(&dir, &["render", "spots", "scenes/inline.json"]);
    assert!(err.contains("the normal's; got 1.000e300"), "{err}");
    let (_, _, err) = run(&dir, &["render", "spots", "scenes/ies.json"]);
    assert!(err.contains("the normal's; got 1.414e299"), "{err}");
    // `light show` refuses the file too, with its name.
    let (code, _, err) = run(&dir, &["light", "show", "big.ies"]);
    assert_eq!(code, Some(1));
    assert!(
        err.contains("big.ies: values[0][1] (C 0°, γ 45°): relative luminance must be finite, ≥ 0 and at most 1e6 times the normal's; got 1.414e299"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
