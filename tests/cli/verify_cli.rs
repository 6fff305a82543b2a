//! `metamer fit --model auto` and `metamer verify` through the binary.

use std::process::Command;

use metamer::display::characterize::plan::random_patches;
use metamer::display::scattered::scattered_patches;
use metamer::rig::{Preset, VirtualPanel};

use crate::support::unused_dir;

fn csv(panel: &VirtualPanel, codes: &[[u8; 3]]) -> String {
    let mut s = String::from("r,g,b,X,Y,Z\n");
    for &c in codes {
        let x = panel.xyz(c);
        s += &format!(
            "{},{},{},{},{},{}\n",
            f64::from(c[0]) / 255.0,
            f64::from(c[1]) / 255.0,
            f64::from(c[2]) / 255.0,
            x[0],
            x[1],
            x[2]
        );
    }
    s
}

#[test]
fn auto_explains_its_choice_and_verify_reports_held_out_errors() {
    let dir = unused_dir("auto");
    std::fs::create_dir_all(&dir).unwrap();
    // The ideal CRT is additive with power-law channels: shaper-matrix is exact on it.
    let panel = VirtualPanel::preset(Preset::IdealCrt);
    std::fs::write(dir.join("fit.csv"), csv(&panel, &scattered_patches(60, 2))).unwrap();
    std::fs::write(dir.join("test.csv"), csv(&panel, &random_patches(40, 9))).unwrap();
    let bin = env!("CARGO_BIN_EXE_metamer");
    let out = Command::new(bin)
        .args(["fit", "--model", "auto", "--measurements"])
        .arg(dir.join("fit.csv"))
        .arg("-o")
        .arg(dir.join("p.json"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("5-fold cross-validation"), "{text}");
    assert!(text.contains("shaper-matrix  CV mean ΔE00"), "{text}");
    // plcc needs ramps, which a scattered set does not have: it is listed with the reason.
    assert!(text.contains("plcc           not fitted"), "{text}");
    let out = Command::new(bin)
        .args(["verify", "--json", "--profile"])
        .arg(dir.join("p.json"))
        .arg("--measurements")
        .arg(dir.join("test.csv"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["patches"], 40);
    let (mean, p95, max) = (
        v["de00"]["mean"].as_f64().unwrap(),
        v["de00"]["p95"].as_f64().unwrap(),
        v["de00"]["max"].as_f64().unwrap(),
    );
    assert!(mean <= p95 && p95 <= max && max < 0.1, "{v}");
    assert!(v["de76"]["mean"].as_f64().unwrap() < 0.1, "{v}");
    let out = Command::new(bin)
        .args(["verify", "--profile"])
        .arg(dir.join("missing.json"))
        .arg("--measurements")
        .arg(dir.join("test.csv"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.json"));
    std::fs::remove_dir_all(&dir).ok();
}

/// `verify` on a `.ti3` in dispread's exact shape with its `CAL` table: every data row is
/// a patch, and the patches it reports are the file's rows as read by hand here (drive
/// value / 100, XYZ × LUMINANCE_XYZ_CDM2's Y / 100, the white normalised to Y = 100).
#[test]
fn verify_reads_a_dispread_ti3_with_its_cal_table() {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dispread_cal.ti3");
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.contains("\nCAL"), "the test file lost its CAL table");
    let lines: Vec<&str> = text.lines().collect();
    let begin = lines.iter().position(|l| l.trim() == "BEGIN_DATA").unwrap();
    let end = lines.iter().position(|l| l.trim() == "END_DATA").unwrap();
    let rows: Vec<Vec<f64>> = lines[begin + 1..end]
        .iter()
        .map(|l| l.split_whitespace().map(|v| v.parse().unwrap()).collect())
        .collect();
    let dir = unused_dir("ti3");
    std::fs::create_dir_all(&dir).unwrap();
    let bin = env!("CARGO_BIN_EXE_metamer");
    let out = Command::new(bin)
        .args(["fit", "--model", "shaper-matrix", "--measurements"])
        .arg(&file)
        .arg("-o")
        .arg(dir.join("p.json"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = Command::new(bin)
        .args(["verify", "--json", "--profile"])
        .arg(dir.join("p.json"))
        .arg("--measurements")
        .arg(&file)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["patches"].as_u64().unwrap() as usize, rows.len());
    let worst = v["worst"].as_array().unwrap();
    assert!(!worst.is_empty());
    for w in worst {
        let row = &rows[w["index"].as_u64().unwrap() as usize - 1];
        for k in 0..3 {
            let rgb = w["rgb"][k].as_f64().unwrap();
            let xyz = w["measured_xyz"][k].as_f64().unwrap();
            assert!((rgb - row[1 + k] / 100.0).abs() < 1e-12, "{w}");
            assert!((xyz - row[4 + k] * 120.25 / 100.0).abs() < 1e-9, "{w}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
