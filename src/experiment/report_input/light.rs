//! The light distribution fit's section from the box's `light.json` (the chosen model, why,
//! its parameters per half-plane, the candidates' cross-validated errors, the residuals),
//! the scene's provenance (when the box was measured, outliers, nominal stand-ins) and the
//! chart `light.svg`, inlined.

use std::path::Path;

use serde_json::Value;

use super::files::{read_json, unusable};
use crate::validation::report::LightFitSection;

const WHAT: &str = "light distribution fit";

fn num(v: &Value) -> Option<f64> {
    v.as_f64().filter(|x| x.is_finite())
}

/// A model's parameters in words: every key but `model`, numbers to 4 significant places.
fn params(p: &Value) -> String {
    let Some(map) = p.as_object() else {
        return String::new();
    };
    let fmt = |v: &Value| match v {
        Value::Number(_) => format!("{:.4}", num(v).unwrap_or(f64::NAN)),
        Value::Array(a) => format!(
            "[{}]",
            a.iter()
                .map(|x| format!("{:.4}", num(x).unwrap_or(f64::NAN)))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        other => other.to_string(),
    };
    map.iter()
        .filter(|(k, _)| k.as_str() != "model")
        .map(|(k, v)| format!("{k} = {}", fmt(v)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The section and notes on what it lacks, or the note saying why there is none.
pub fn section(box_dir: &Path) -> Result<(LightFitSection, Vec<String>), String> {
    let file = box_dir.join("light.json");
    let scene_file = box_dir.join("scene.json");
    let scene = read_json(&scene_file);
    let mut notes = Vec::new();
    let (v, file) = fit_source(file, &scene, &scene_file, &mut notes)?;
    let model = v["model"]
        .as_str()
        .ok_or_else(|| unusable(WHAT, &file, "names no chosen \"model\""))?;
    let mut rows: Vec<(String, String)> = vec![("chosen model".into(), model.into())];
    if let Some(why) = v["why"].as_str() {
        rows.push(("why".into(), why.into()));
    }
    if let Some(l) = num(&v["normal_luminance"]) {
        let readings: Vec<String> = v["normal_readings"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(num)
            .map(|x| format!("{x}"))
            .collect();
        let mut s = format!("{l} cd/m²");
        if !readings.is_empty() {
            s += &format!(" (readings {})", readings.join(", "));
        }
        rows.push(("luminance along the normal".into(), s));
    }
    for h in v["halves"].as_array().into_iter().flatten() {
        let mut s = params(&h["params"]);
        if let Some(r) = num(&h["rms"]) {
            s += &format!("; RMS {r:.5}");
        }
        rows.push((
            format!("half-plane {}", h["half"].as_str().unwrap_or("?")),
            s,
        ));
    }
    residual_rows(&v, &mut rows);
    match &scene {
        Ok(scene) => provenance(&scene["provenance"], &mut rows),
        Err(why) => notes.push(format!(
            "the light fit's section has no measurement details: {} {why}",
            scene_file.display()
        )),
    }
    let chart_svg = chart(box_dir, &mut notes);
    Ok((
        LightFitSection {
            summary: rows,
            chart_svg,
        },
        notes,
    ))
}

/// The fit as `light.json` holds it; without it (a box given as its scene and readings)
/// as the scene's provenance still records it (the chosen model, why, its residuals),
/// with a note; with neither, the note saying why there is no section.
fn fit_source(
    file: std::path::PathBuf,
    scene: &Result<Value, String>,
    scene_file: &Path,
    notes: &mut Vec<String>,
) -> Result<(Value, std::path::PathBuf), String> {
    match read_json(&file) {
        Ok(v) => Ok((v, file)),
        Err(why) => match scene
            .as_ref()
            .ok()
            .map(|s| &s["provenance"]["distribution_fit"])
            .filter(|f| f.is_object())
        {
            Some(fit) => {
                notes.push(format!(
                    "{} {why}: the light fit is shown as {} records it (no half-plane parameters or candidates)",
                    file.display(),
                    scene_file.display()
                ));
                Ok((fit.clone(), scene_file.to_path_buf()))
            }
            None => Err(unusable(WHAT, &file, why)),
        },
    }
}

/// The residuals' summary and each candidate model's errors.
fn residual_rows(v: &Value, rows: &mut Vec<(String, String)>) {
    let residuals: Vec<(String, f64)> = v["residuals"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|r| {
            Some((
                format!(
                    "{} {}°",
                    r["plane"].as_str().unwrap_or("?"),
                    num(&r["angle_deg"])?
                ),
                num(&r["residual"])?,
            ))
        })
        .collect();
    if !residuals.is_empty() {
        let rms =
            (residuals.iter().map(|r| r.1 * r.1).sum::<f64>() / residuals.len() as f64).sqrt();
        let worst = residuals
            .iter()
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .expect("not empty");
        rows.push((
            "residuals (measured − fitted, relative to the normal)".into(),
            format!(
                "{} readings, RMS {rms:.5}, largest {:+.5} at {}",
                residuals.len(),
                worst.1,
                worst.0
            ),
        ));
    }
    for c in v["candidates"].as_array().into_iter().flatten() {
        let name = c["model"].as_str().unwrap_or("?");
        let mut s = match (num(&c["rms"]), num(&c["cv_rms"]), num(&c["cv_max"])) {
            (Some(r), Some(cv), Some(mx)) => {
                format!("RMS {r:.5}, leave-one-out RMS {cv:.5}, max {mx:.5}")
            }
            (Some(r), _, _) => format!("RMS {r:.5}"),
            _ => "not fitted".into(),
        };
        if let Some(n) = c["note"].as_str() {
            s += &format!(" ({n})");
        }
        rows.push((format!("candidate {name}"), s));
    }
}

/// The fit's chart `light.svg`, or a note saying why it is not shown.
fn chart(box_dir: &Path, notes: &mut Vec<String>) -> Option<String> {
    let chart = box_dir.join("light.svg");
    match std::fs::read_to_string(&chart) {
        Ok(svg) => Some(svg),
        Err(e) => {
            notes.push(format!(
                "the light fit's chart is not shown: {} {}",
                chart.display(),
                if e.kind() == std::io::ErrorKind::NotFound {
                    "does not exist".to_string()
                } else {
                    format!("cannot be read: {e}")
                }
            ));
            None
        }
    }
}

/// What the measured scene's provenance says about the measurement.
fn provenance(p: &Value, rows: &mut Vec<(String, String)>) {
    if p.is_null() {
        return;
    }
    if let Some(d) = p["date"].as_str() {
        rows.push(("box measured".into(), d.into()));
    }
    let count = |k: &str| p[k].as_array().map(Vec::len);
    if let Some(n) = count("outliers") {
        rows.push(("readings flagged as outliers".into(), n.to_string()));
    }
    if let Some(list) = p["nominal_patches"].as_array() {
        let s = if list.is_empty() {
            "none: every patch's reflectance measured".to_string()
        } else {
            list.iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        };
        rows.push(("patches with nominal reflectance".into(), s));
    }
    if let Some(n) = p["clamped_values"].as_u64() {
        rows.push((
            "spectral values clamped to the physical range".into(),
            n.to_string(),
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::super::files::testdir;
    use super::*;

    const LIGHT: &str = r#"{"model":"cos-power",
      "why":"cos-power: the lowest leave-one-out RMS",
      "normal_luminance":101.65,"normal_readings":[101.5,101.8],
      "halves":[{"half":"C0","params":{"model":"cos-power","n":0.89976},"rms":0.000396}],
      "residuals":[
        {"plane":"horizontal","angle_deg":-80.0,"measured":0.35,"fitted":0.3503,"residual":-0.0003},
        {"plane":"vertical","angle_deg":40.0,"measured":0.8,"fitted":0.7996,"residual":0.0004}],
      "candidates":[{"model":"lambertian","rms":0.49121,"cv_rms":0.49122,"cv_max":0.91389,"note":null}]}"#;

    #[test]
    fn model_why_parameters_residuals_and_chart() {
        let dir = testdir::fresh("light");
        testdir::write(&dir, "light.json", LIGHT);
        testdir::write(
            &dir,
            "scene.json",
            r#"{"provenance":{"date":"2026-12-01T22:54:03Z","outliers":[],"nominal_patches":[13],"clamped_values":11}}"#,
        );
        testdir::write(&dir, "light.svg", "<svg width=\"4\"></svg>");
        let (l, notes) = section(&dir).unwrap();
        assert!(notes.is_empty(), "{notes:?}");
        let get = |k: &str| {
            l.summary
                .iter()
                .find(|(n, _)| n == k)
                .map(|(_, v)| v.as_str())
        };
        assert_eq!(get("chosen model"), Some("cos-power"));
        assert_eq!(get("half-plane C0"), Some("n = 0.8998; RMS 0.00040"));
        // RMS of −0.0003 and 0.0004: √((9 + 16)/2)·10⁻⁴ = 0.00035355.
        assert_eq!(
            get("residuals (measured − fitted, relative to the normal)"),
            Some("2 readings, RMS 0.00035, largest +0.00040 at vertical 40°")
        );
        assert_eq!(
            get("candidate lambertian"),
            Some("RMS 0.49121, leave-one-out RMS 0.49122, max 0.91389")
        );
        assert_eq!(
            get("luminance along the normal"),
            Some("101.65 cd/m² (readings 101.5, 101.8)")
        );
        assert_eq!(get("patches with nominal reflectance"), Some("13"));
        assert_eq!(get("box measured"), Some("2026-12-01T22:54:03Z"));
        assert_eq!(l.chart_svg.as_deref(), Some("<svg width=\"4\"></svg>"));

        // A box given as files without its chart: the section stays, the chart is noted.
        std::fs::remove_file(dir.join("light.svg")).unwrap();
        let (l, notes) = section(&dir).unwrap();
        assert!(l.chart_svg.is_none());
        assert!(notes[0].contains("light.svg does not exist"), "{notes:?}");

        // Without light.json the scene's provenance still names the model and residuals.
        std::fs::remove_file(dir.join("light.json")).unwrap();
        testdir::write(
            &dir,
            "scene.json",
            r#"{"provenance":{"date":"2026-12-01T22:54:03Z","distribution_fit":{"model":"cos-power","why":"lowest","rms":0.0004,
              "residuals":[{"plane":"horizontal","angle_deg":0.0,"measured":1.0,"fitted":1.0003,"residual":-0.0003}]}}}"#,
        );
        let (l, notes) = section(&dir).unwrap();
        assert_eq!(
            l.summary[0],
            ("chosen model".to_string(), "cos-power".to_string())
        );
        assert!(l.summary.iter().any(|(k, v)| k.starts_with("residuals")
            && v == "1 readings, RMS 0.00030, largest -0.00030 at horizontal 0°"));
        assert!(
            notes[0].contains("light.json does not exist: the light fit is shown as"),
            "{notes:?}"
        );
        std::fs::write(dir.join("scene.json"), "{}").unwrap();
        let e = section(&dir).unwrap_err();
        assert!(e.ends_with("light.json does not exist"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
