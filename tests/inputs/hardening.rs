//! One small input per class of malformed input a tester found: each must give a clear
//! error (or a bounded answer), never a panic, a hang or a silent NaN.

use std::path::{Path, PathBuf};

use metamer::color::Xyz;
use metamer::display::gamut::nearest_lab;
use metamer::display::measurements::{parse_ti3, read_measurement_file};
use metamer::display::{fit_profile, ModelKind, Profile};
use metamer::image::{read_xyz_image, write_xyz_image, XyzImage};

use crate::support::{dispread_analytic, fresh_dir, metamer_in_root, stderr};

fn scratch(name: &str) -> PathBuf {
    fresh_dir("scratch").join(name)
}

/// A fitted PLCC profile as JSON, to be broken by the tests.
fn profile_json() -> serde_json::Value {
    let m = read_measurement_file(&dispread_analytic()).unwrap();
    let p = fit_profile(ModelKind::Plcc, &m.patches, None).unwrap();
    serde_json::to_value(&p).unwrap()
}

fn load(name: &str, json: &serde_json::Value) -> Result<Profile, String> {
    let path = scratch(name);
    std::fs::write(&path, json.to_string()).unwrap();
    Profile::load(&path).map_err(|e| e.to_string())
}

#[test]
fn a_profile_with_an_empty_tone_curve_is_refused_not_indexed() {
    let mut json = profile_json();
    json["parameters"]["trc"][1] = serde_json::json!({"type": "table", "drive": [], "value": []});
    let e = load("empty-trc.json", &json).unwrap_err();
    assert!(
        e.ends_with(
            "inconsistent parameters: the green tone curve is unusable: a table needs at least 2 \
             drive levels and one value per level, found 0 drive levels and 0 values"
        ),
        "{e}"
    );
}

#[test]
fn a_profile_with_a_zero_or_nan_white_is_refused() {
    let mut json = profile_json();
    json["white_xyz"] = serde_json::json!([0.0, 0.0, 0.0]);
    let e = load("zero-white.json", &json).unwrap_err();
    assert!(e.contains("the white must have Y > 0"), "{e}");
    // serde_json writes NaN as null, which is no number at all.
    json["white_xyz"] = serde_json::json!([1.0, null, 1.0]);
    assert!(load("null-white.json", &json).is_err());
}

#[test]
fn nearest_lab_answers_at_once_for_non_finite_targets_and_whites() {
    let forward = |rgb: [f64; 3]| Xyz::from(rgb.map(|v| 100.0 * v));
    let white = Xyz::from_array([100.0; 3]);
    let start = std::time::Instant::now();
    for (target, white) in [
        (Xyz::from_array([f64::NAN, 1.0, 1.0]), white),
        (Xyz::from_array([f64::INFINITY, 1.0, 1.0]), white),
        (
            Xyz::from_array([500.0, 1.0, 1.0]),
            Xyz::from_array([0.0; 3]),
        ),
    ] {
        let rgb = nearest_lab(&forward, [0.5; 3], target, white);
        assert!(rgb.iter().all(|v| (0.0..=1.0).contains(v)), "{rgb:?}");
    }
    assert!(start.elapsed().as_secs() < 5);
}

#[test]
fn a_pfm_whose_size_overflows_or_has_a_nan_pixel_is_refused() {
    let p = scratch("overflow.pfm");
    std::fs::write(&p, b"PF\n18446744073709551615 3\n-1.0\n\0\0\0\0").unwrap();
    let e = read_xyz_image(&p).unwrap_err().to_string();
    assert!(
        e.contains("18446744073709551615×3 pixels is more than"),
        "{e}"
    );
    let mut nan = b"PF\n1 1\n-1.0\n".to_vec();
    for v in [1.0f32, f32::NAN, 1.0] {
        nan.extend(v.to_le_bytes());
    }
    let p = scratch("nan.pfm");
    std::fs::write(&p, nan).unwrap();
    let e = read_xyz_image(&p).unwrap_err().to_string();
    assert!(
        e.ends_with("pixel (0, 0) (from the top left) is [1.0, NaN, 1.0], not a finite XYZ"),
        "{e}"
    );
}

#[test]
fn an_exr_says_its_pixels_are_xyz_and_a_truncated_one_is_named_so() {
    let img = XyzImage {
        width: 2,
        height: 2,
        pixels: vec![[1.0, 2.0, 3.0]; 4],
    };
    let p = scratch("xyz.exr");
    write_xyz_image(&p, &img, &metamer::output::OutputPolicy::new(true)).unwrap();
    let meta = exr::meta::MetaData::read_from_file(&p, false).unwrap();
    let c = meta.headers[0].shared_attributes.chromaticities.unwrap();
    // OpenEXR's XYZ convention: the xy of (1,0,0), (0,1,0), (0,0,1) and (1,1,1).
    assert_eq!((c.red.0, c.red.1), (1.0, 0.0));
    assert_eq!((c.green.0, c.green.1), (0.0, 1.0));
    assert_eq!((c.blue.0, c.blue.1), (0.0, 0.0));
    assert_eq!((c.white.0, c.white.1), (1.0 / 3.0, 1.0 / 3.0));
    assert_eq!(meta.headers[0].own_attributes.white_luminance, Some(1.0));
    assert_eq!(read_xyz_image(&p).unwrap(), img);
    let bytes = std::fs::read(&p).unwrap();
    let cut = scratch("cut.exr");
    std::fs::write(&cut, &bytes[..bytes.len() - 20]).unwrap();
    let e = read_xyz_image(&cut).unwrap_err().to_string();
    assert!(!e.contains("reference to missing bytes"), "{e}");
    assert!(e.contains("truncated"), "{e}");
}

#[test]
fn a_ti3_with_a_bom_reads_and_an_impossible_reading_is_refused() {
    let text = std::fs::read_to_string(dispread_analytic()).unwrap();
    let with_bom = format!("\u{feff}{text}");
    let a = parse_ti3(&with_bom, Path::new("bom.ti3")).unwrap();
    let b = parse_ti3(&text, Path::new("plain.ti3")).unwrap();
    assert_eq!(a, b);
    // The first data row's X replaced by −1e308.
    let begin = text.find("BEGIN_DATA\n").unwrap() + "BEGIN_DATA\n".len();
    let row_end = begin + text[begin..].find('\n').unwrap();
    let mut fields: Vec<&str> = text[begin..row_end].split_whitespace().collect();
    let x = fields.len() - 3;
    fields[x] = "-1e308";
    let bad = format!("{}{}{}", &text[..begin], fields.join(" "), &text[row_end..]);
    let e = parse_ti3(&bad, Path::new("bad.ti3"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a measurement: XYZ [-1e308"), "{e}");
}

#[test]
fn a_megabyte_field_is_echoed_as_80_characters() {
    let p = scratch("huge.csv");
    std::fs::write(&p, format!("X,Y,Z\n1,2,{}\n", "7x".repeat(500_000))).unwrap();
    let e = metamer::display::reproduce::read_targets(&p)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("(1000000 characters in all)"),
        "{}",
        &e[..e.len().min(300)]
    );
    assert!(e.len() < 300, "{} characters", e.len());
}

#[test]
fn color_results_that_overflow_are_errors_and_a_chosen_column_is_named() {
    let p = scratch("huge-spectrum.csv");
    std::fs::write(&p, "nm,a\n500,1e308\n510,1e308\n").unwrap();
    let o = metamer_in_root(&["color", "xyz", p.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("the result is not a finite number"),
        "{}",
        stderr(&o)
    );
    let p = scratch("pairs.csv");
    std::fs::write(&p, "L1,a1,b1,L2,a2,b2\n50,1e308,0,50,-1e308,0\n").unwrap();
    let o = metamer_in_root(&["color", "delta-e", "--pairs", p.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains(":2: the colour difference is not a finite number"),
        "{}",
        stderr(&o)
    );
    let p = scratch("two.csv");
    std::fs::write(&p, "nm,a,b\n500,0.01,0.02\n510,0.01,0.02\n").unwrap();
    let o = metamer_in_root(&[
        "color",
        "xyz",
        p.to_str().unwrap(),
        "--column",
        "b",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["column"], "b");
}

#[test]
fn options_that_cannot_work_fail_before_the_work() {
    let o = metamer_in_root(&["budget", "-o", "unused", "--trials", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--trials must be at least 1"),
        "{}",
        stderr(&o)
    );
    let file = scratch("a-file");
    std::fs::write(&file, "").unwrap();
    let o = metamer_in_root(&["budget", "-o", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("is a file"), "{}", stderr(&o));
    let o = metamer_in_root(&[
        "reproduce",
        "--profile",
        "p.json",
        "--xyz",
        "t.csv",
        "-o",
        "o.csv",
        "--bits",
        "16",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--bits sets the PNG depth of --image"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn a_ti3_row_scaled_past_belief_by_its_white_luminance_is_refused() {
    // Found by the fuzz harness: each value is below 10¹⁰ but LUMINANCE_XYZ_CDM2's Y of
    // 2·10⁹ scales the white-relative row by 2·10⁹ / 100: Z becomes 4.6·10¹⁶ on line 10.
    let text = "CTI3\nKEYWORD \"LUMINANCE_XYZ_CDM2\"\nLUMINANCE_XYZ_CDM2 \"1 2000000000 1\"\n\
                NUMBER_OF_FIELDS 6\nBEGIN_DATA_FORMAT\nRGB_R RGB_G RGB_B XYZ_X XYZ_Y XYZ_Z\n\
                END_DATA_FORMAT\nNUMBER_OF_SETS 1\nBEGIN_DATA\n100 100 100 95 100 2305843009\n\
                END_DATA\n";
    let e = parse_ti3(text, Path::new("scaled.ti3"))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("scaled.ti3:10: not a measurement once scaled to cd/m²"),
        "{e}"
    );
}

#[test]
fn an_exr_header_claiming_more_pixels_than_its_file_can_hold_is_refused_before_decoding() {
    // Found by the fuzz harness: a 300-byte file whose data window asked the decoder for
    // 1.8 GB. A written 2×2 image with its data window's maximum raised to 8191×8191.
    let img = XyzImage {
        width: 2,
        height: 2,
        pixels: vec![[1.0, 2.0, 3.0]; 4],
    };
    let p = scratch("small.exr");
    write_xyz_image(&p, &img, &metamer::output::OutputPolicy::new(true)).unwrap();
    let mut bytes = std::fs::read(&p).unwrap();
    let name = b"dataWindow\0box2i\0";
    let at = bytes.windows(name.len()).position(|w| w == name).unwrap() + name.len() + 4;
    // box2i: xMin, yMin, xMax, yMax as little-endian i32.
    bytes[at + 8..at + 12].copy_from_slice(&8191i32.to_le_bytes());
    bytes[at + 12..at + 16].copy_from_slice(&8191i32.to_le_bytes());
    let big = scratch("big.exr");
    std::fs::write(&big, &bytes).unwrap();
    let e = read_xyz_image(&big).unwrap_err().to_string();
    assert!(e.contains("8192×8192 pixels, more than a file of"), "{e}");
}

/// A profile whose tone curve ends at 1e300 predicted colours no display shows, and
/// `verify` printed "ΔE00 mean NaN … max 3.649" with exit 0 (the maximum hid the NaN
/// patch). The first such patch is now an error naming it, and nothing prints NaN.
#[test]
fn verify_refuses_a_profile_whose_predictions_are_no_colours() {
    let mut json = profile_json();
    let trc = &mut json["parameters"]["trc"][0];
    assert_eq!(trc["type"], "table", "{trc}");
    let last = trc["value"].as_array().unwrap().len() - 1;
    trc["value"][last] = serde_json::json!(1e300);
    let path = scratch("trc-1e300.json");
    std::fs::write(&path, json.to_string()).unwrap();
    let o = metamer_in_root(&[
        "verify",
        "--profile",
        path.to_str().unwrap(),
        "--measurements",
        dispread_analytic().to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("the profile predicts X, Y, Z")
            && e.contains("which is not a colour a display shows"),
        "{e}"
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(!out.contains("NaN") && !e.contains("NaN"), "{out}{e}");
}
