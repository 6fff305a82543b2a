//! The display model's section from the characterization's `summary.json`: the model, the
//! fit's verdict, its diagnostics, and the held-out verification.

use std::path::Path;

use serde_json::Value;

use super::files::{read_json, unusable};
use crate::experiment::display::SUMMARY_FILE;
use crate::validation::report::DisplayModelSection;

const WHAT: &str = "display model";

fn num(v: &Value) -> Option<f64> {
    v.as_f64().filter(|x| x.is_finite())
}

fn triple(v: &Value) -> Option<String> {
    let a = v.as_array().filter(|a| a.len() == 3)?;
    let n: Option<Vec<f64>> = a.iter().map(num).collect();
    n.map(|n| format!("{:.4}, {:.4}, {:.4}", n[0], n[1], n[2]))
}

/// The section, or the note saying why there is none.
pub fn section(dir: &Path) -> Result<DisplayModelSection, String> {
    let file = dir.join(SUMMARY_FILE);
    let v = read_json(&file).map_err(|why| unusable(WHAT, &file, why))?;
    let model = v["model"]
        .as_str()
        .ok_or_else(|| unusable(WHAT, &file, "names no \"model\""))?
        .to_string();
    let mut rows: Vec<(String, String)> = Vec::new();
    let mut row = |k: &str, val: String| rows.push((k.to_string(), val));
    if let Some(d) = v["display_description"].as_str().or(v["display"].as_str()) {
        row("display", d.to_string());
    }
    if let Some(i) = v["instrument"].as_str() {
        row("measured with", i.to_string());
    }
    let fit = &v["fit_residuals"];
    let ver = &v["verification"];
    if let Some(s) = readings_text(&v) {
        row("readings", s);
    }
    if let Some(w) = triple(&v["white_xyz"]) {
        row("white X, Y, Z (cd/m²)", w);
    }
    if let Some(b) = triple(&v["black_xyz"]) {
        row("black X, Y, Z (cd/m²)", b);
    }
    if let Some(s) = residuals_text(fit) {
        row("fit residuals", s);
    }
    for f in v["failures"].as_array().into_iter().flatten() {
        if let Some(f) = f.as_str() {
            row("PLCC assumption contradicted", f.to_string());
        }
    }
    let verification_de00 = match (num(&ver["mean"]), num(&ver["p95"]), num(&ver["max"])) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };
    let patches = ver["patches"].as_array();
    if let Some(w) = worst_patch(patches) {
        row("worst verification patch", w);
    }
    if verification_de00.is_none() {
        rows.push((
            "verification".into(),
            "none (the plan held no verification patches)".into(),
        ));
    }
    Ok(DisplayModelSection {
        model,
        verdict: v["verdict"].as_str().unwrap_or_default().to_string(),
        diagnostics: rows,
        verification_de00,
        verification_patches: patches.map_or(0, Vec::len),
    })
}

/// How the session's readings divide: the fit's (its colours, some read more than once)
/// and the held-out verification patches'; the fit residuals are over the fit's readings.
fn readings_text(v: &Value) -> Option<String> {
    let fit_readings = v["fit_residuals"]["patches"].as_u64();
    let r = v["readings"].as_u64()?;
    let held_out = v["verification"]["patches"]
        .as_array()
        .map(|p| p.len() as u64);
    Some(match (fit_readings, v["fit_patches"].as_u64(), held_out) {
        (Some(fr), Some(fc), Some(vc)) if fr >= fc && fr + vc <= r => {
            let mut s = format!("{r}: {fr} for the fit");
            if fr > fc {
                s += &format!(" ({fc} colours, {} of them read again)", fr - fc);
            } else {
                s += &format!(" ({fc} colours)");
            }
            s += &format!(" and {vc} held out for verification");
            if r > fr + vc {
                s += &format!("; {} not used", r - fr - vc);
            }
            s
        }
        (_, Some(fc), _) => format!("{r} ({fc} colours fitted)"),
        _ => r.to_string(),
    })
}

/// The fit's residuals over its readings, in words.
fn residuals_text(fit: &Value) -> Option<String> {
    let (mean, p95, max) = (
        num(&fit["mean_de00"])?,
        num(&fit["p95_de00"])?,
        num(&fit["max_de00"])?,
    );
    let mut s = format!("ΔE00 mean {mean:.3}, p95 {p95:.3}, max {max:.3}");
    if let Some(n) = fit["patches"].as_u64() {
        s += &format!(" over the {n} fit readings");
    }
    if let Some(w) = triple(&fit["worst_rgb"]) {
        s += &format!(" (worst at drive {w})");
    }
    if let Some(r) = num(&fit["rms_xyz"]) {
        s += &format!("; XYZ RMS {r:.4} cd/m²");
    }
    Some(s)
}

/// The verification patch of the largest ΔE00, in words.
fn worst_patch(patches: Option<&Vec<Value>>) -> Option<String> {
    let w = patches?
        .iter()
        .filter(|q| num(&q["delta_e00"]).is_some())
        .max_by(|a, b| {
            num(&a["delta_e00"])
                .unwrap_or(0.0)
                .total_cmp(&num(&b["delta_e00"]).unwrap_or(0.0))
        })?;
    Some(format!(
        "{} (RGB {}): ΔE00 {:.2}",
        w["label"].as_str().unwrap_or("?"),
        w["rgb8"]
            .as_array()
            .map(|a| a
                .iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(", "))
            .unwrap_or_default(),
        num(&w["delta_e00"]).unwrap_or(0.0)
    ))
}

#[cfg(test)]
mod tests {
    use super::super::files::testdir;
    use super::*;

    #[test]
    fn model_verdict_diagnostics_and_verification_from_a_summary() {
        let dir = testdir::fresh("display");
        testdir::write(
            &dir,
            SUMMARY_FILE,
            r#"{"display":"virtual:ips-lcd","display_description":"simulated monitor","instrument":"sim:cs100a",
            "model":"lut","verdict":"PLCC's assumptions fail: drift","failures":["the red channel drifts"],
            "readings":782,"fit_patches":729,"white_xyz":[29.4,31.0,34.5],"black_xyz":[0.03,0.034,0.06],
            "fit_residuals":{"patches":734,"mean_de00":0.0013,"p95_de00":0.0,"max_de00":0.2486,"worst_rgb":[1.0,1.0,1.0],"rms_xyz":0.0066},
            "verification":{"white_xyz":[29.4,31.0,34.5],"patches":[
              {"label":"random 1","rgb8":[150,152,143],"measured_xyz":[1,1,1],"predicted_xyz":[1,1,1],"delta_e00":0.43},
              {"label":"random 2","rgb8":[10,20,30],"measured_xyz":[1,1,1],"predicted_xyz":[1,1,1],"delta_e00":0.72}],
              "mean":0.575,"p95":0.7055,"max":0.72}}"#,
        );
        let d = section(&dir).unwrap();
        assert_eq!(d.model, "lut");
        assert_eq!(d.verdict, "PLCC's assumptions fail: drift");
        assert_eq!(d.verification_de00, Some([0.575, 0.7055, 0.72]));
        assert_eq!(d.verification_patches, 2);
        let get = |k: &str| {
            d.diagnostics
                .iter()
                .find(|(n, _)| n == k)
                .map(|(_, v)| v.as_str())
        };
        // 782 readings: 734 fit readings of 729 colours and 2 verification patches leave 46 not used.
        assert_eq!(
            get("readings"),
            Some("782: 734 for the fit (729 colours, 5 of them read again) and 2 held out for verification; 46 not used")
        );
        assert_eq!(
            get("fit residuals"),
            Some("ΔE00 mean 0.001, p95 0.000, max 0.249 over the 734 fit readings (worst at drive 1.0000, 1.0000, 1.0000); XYZ RMS 0.0066 cd/m²")
        );
        assert_eq!(
            get("PLCC assumption contradicted"),
            Some("the red channel drifts")
        );
        assert_eq!(
            get("worst verification patch"),
            Some("random 2 (RGB 10, 20, 30): ΔE00 0.72")
        );
        std::fs::write(dir.join(SUMMARY_FILE), "{\"verdict\":1}").unwrap();
        let e = section(&dir).unwrap_err();
        assert!(
            e.starts_with("no display model section: ") && e.ends_with("names no \"model\""),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
