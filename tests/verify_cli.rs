//! `metamer fit --model auto` and `metamer verify` through the binary.

use std::process::Command;

use metamer::display::characterize::plan::random_patches;
use metamer::display::scattered::scattered_patches;
use metamer::rig::{Preset, VirtualPanel};

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
    let dir = std::env::temp_dir().join(format!("metamer-verify-{}", std::process::id()));
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
