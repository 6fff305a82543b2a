//! The whole bridge to another renderer: `metamer export --to mitsuba3`, Mitsuba 3
//! (`scalar_spectral`, an independent spectral renderer) renders the camera's image into an
//! OpenEXR file with X, Y, Z channels, and `metamer render spots-from-image` reads the 24
//! meter readings back; they must agree with `metamer render spots` (the radiosity solver,
//! whose bound is far below the image's noise) within the read-back's own stated
//! uncertainty, on the Lambertian box and, within the stated difference of its emitter's
//! Lambertian form, on a box measured by `measure-box`.
//!
//! Without Mitsuba the tests print "skipped" with the reason and pass, unless
//! `METAMER_ORACLES=required` (CI sets it after installing the wheel), when they fail
//! (`support::oracle`).

use std::path::Path;
use std::process::Command;

use serde_json::Value;

use crate::support::oracle::MITSUBA;
use crate::support::{fresh_dir, metamer, metamer_unscaled, scenes_dir, stderr, text};

/// 256² at 64 spp: about 240 pixels in each meter cone, a ΔE*ab half-width near 1, in a
/// few seconds.
const SIZE: usize = 256;
const SPP: usize = 64;
/// Per component, |read-back − reference| within this many of the read-back's standard
/// errors: 72 comparisons all pass at 4.5σ with odds better than 99.9 % when the stated
/// error is right and nothing is biased.
const SIGMAS: f64 = 4.5;

/// Renders `xml` with Mitsuba into `exr`; false when Mitsuba is not importable and not
/// required.
fn mitsuba(xml: &Path, exr: &Path) -> bool {
    let script = r#"
import sys
import mitsuba as mi
mi.set_variant("scalar_spectral")
size = int(sys.argv[3])
scene = mi.load_file(sys.argv[1], spp=int(sys.argv[2]), width=size, height=size)
mi.render(scene, seed=11)
scene.sensors()[0].film().bitmap().write(sys.argv[4])
"#;
    let Some(python) = MITSUBA.find() else {
        return false;
    };
    let out = Command::new(python)
        .args(["-c", script])
        .arg(xml)
        .arg(SPP.to_string())
        .arg(SIZE.to_string())
        .arg(exr)
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "Mitsuba 3 did not render the export: {}",
        text(&out.stderr)
    );
    true
}

fn run_json(args: &[&str]) -> Value {
    let o = metamer(args);
    assert!(o.status.success(), "metamer {args:?}: {}", stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

fn triple(v: &Value) -> [f64; 3] {
    std::array::from_fn(|i| v[i].as_f64().unwrap())
}

/// CIE 15:2018 CIELAB against `white`, written here from the standard.
fn lab(xyz: [f64; 3], white: [f64; 3]) -> [f64; 3] {
    let f = |t: f64| {
        if t > 216.0 / 24389.0 {
            t.cbrt()
        } else {
            (24389.0 / 27.0 * t + 16.0) / 116.0
        }
    };
    let [fx, fy, fz] = std::array::from_fn::<f64, 3, _>(|i| f(xyz[i] / white[i]));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// Per patch: ΔE*ab of the read-back from the reference (against the reference's white),
/// the read-back's 95 % half-width, and each component's difference in standard errors.
struct Agreement {
    de: Vec<f64>,
    half_width: Vec<f64>,
    z: Vec<f64>,
}

/// Exports `scene`, renders it with Mitsuba and reads it back; None when skipped.
fn round_trip(scene: &Path, dir: &Path) -> Option<(Agreement, String)> {
    let out = dir.join("mitsuba");
    let s = scene.to_str().unwrap();
    let o = metamer(&["export", s, "--to", "mitsuba3", "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "export: {}", stderr(&o));
    let exr = dir.join("mitsuba.exr");
    if !mitsuba(&out.join("scene.xml"), &exr) {
        return None;
    }
    let reference = run_json(&["render", "spots", s, "--method", "radiosity", "--json"]);
    let white = triple(&reference["white"]);
    let back = run_json(&[
        "render",
        "spots-from-image",
        exr.to_str().unwrap(),
        "--scene",
        s,
        "--white",
        &format!("{},{},{}", white[0], white[1], white[2]),
        "--json",
    ]);
    let (r, b) = (
        reference["patches"].as_array().unwrap(),
        back["patches"].as_array().unwrap(),
    );
    assert_eq!((r.len(), b.len()), (24, 24));
    let mut agreement = Agreement {
        de: vec![],
        half_width: vec![],
        z: vec![],
    };
    for (p, q) in r.iter().zip(b) {
        assert_eq!(p["patch"], q["patch"]);
        let (x, y) = (triple(&p["XYZ"]), triple(&q["XYZ"]));
        let se = triple(&q["XYZ_stderr"]);
        let (la, lb) = (lab(x, white), lab(y, white));
        agreement
            .de
            .push((0..3).map(|i| (la[i] - lb[i]).powi(2)).sum::<f64>().sqrt());
        agreement.half_width.push(q["de_ci95"].as_f64().unwrap());
        agreement.z.extend((0..3).map(|i| (y[i] - x[i]) / se[i]));
    }
    let readme = std::fs::read_to_string(out.join("README.md")).unwrap();
    Some((agreement, readme))
}

fn summary(a: &Agreement) -> String {
    let n = a.z.len() as f64;
    format!(
        "ΔE*ab mean {:.3}, max {:.3} (mean 95 % half-width {:.3}); z mean {:.3}, rms {:.3}",
        a.de.iter().sum::<f64>() / 24.0,
        a.de.iter().cloned().fold(0.0, f64::max),
        a.half_width.iter().sum::<f64>() / 24.0,
        a.z.iter().sum::<f64>() / n,
        (a.z.iter().map(|z| z * z).sum::<f64>() / n).sqrt()
    )
}

#[test]
fn mitsuba_reads_back_as_render_spots_on_the_lambertian_box() {
    let dir = fresh_dir("lambertian");
    let scene = scenes_dir().join("validation-box-led-rgb1.json");
    let Some((a, readme)) = round_trip(&scene, &dir) else {
        return;
    };
    assert!(readme.contains("exact"), "{readme}");
    eprintln!(
        "export → Mitsuba {SIZE}² {SPP} spp → read-back vs render spots: {}",
        summary(&a)
    );
    for (i, z) in a.z.iter().enumerate() {
        assert!(
            z.abs() <= SIGMAS,
            "patch {} component {}: {z:.2} standard errors from render spots ({})",
            i / 3 + 1,
            i % 3,
            summary(&a)
        );
    }
    // A bias shared by every patch (units, a spectrum's scale, the film's integration)
    // shows in the mean of the 72 z, whose own standard deviation is 1/√72 ≈ 0.12.
    let mean = a.z.iter().sum::<f64>() / a.z.len() as f64;
    assert!(mean.abs() < 0.5, "a shared bias: {}", summary(&a));
    // The stated uncertainty is the pixels' spread: it must neither hide the differences
    // nor inflate them more than twice.
    let rms = (a.z.iter().map(|z| z * z).sum::<f64>() / a.z.len() as f64).sqrt();
    assert!(
        (0.5..1.6).contains(&rms),
        "stated errors off: {}",
        summary(&a)
    );
}

#[test]
fn mitsuba_reads_back_the_measured_box_within_its_emitters_stated_difference() {
    let dir = fresh_dir("measured");
    let boxdir = dir.join("box");
    let o = metamer_unscaled(&[
        "measure-box",
        "-o",
        boxdir.to_str().unwrap(),
        "--spectral",
        "sim:i1pro?time_scale=0",
        "--spot",
        "sim:cs100a?time_scale=0",
        "--repeats",
        "1",
    ]);
    assert!(o.status.success(), "measure-box: {}", stderr(&o));
    let Some((a, readme)) = round_trip(&boxdir.join("scene.json"), &dir) else {
        return;
    };
    // The export's README states each patch's ΔE*ab between the scene and the Lambertian
    // form it wrote: "| patch | ΔE*ab |" rows.
    let stated: Vec<f64> = readme
        .lines()
        .filter_map(|l| {
            let cells: Vec<&str> = l.trim_matches('|').split('|').map(str::trim).collect();
            match cells.as_slice() {
                [p, de] if p.parse::<usize>().is_ok() => de.parse::<f64>().ok(),
                _ => None,
            }
        })
        .collect();
    assert_eq!(stated.len(), 24, "{readme}");
    eprintln!(
        "measured box: export → Mitsuba → read-back vs render spots of the scene: {}; the \
         form's stated difference mean {:.3}, max {:.3}",
        summary(&a),
        stated.iter().sum::<f64>() / 24.0,
        stated.iter().cloned().fold(0.0, f64::max)
    );
    for (k, form) in stated.iter().enumerate() {
        // Mitsuba renders the written form; the form is `stated` from the scene.
        let allowed = form + SIGMAS / 1.96 * a.half_width[k];
        assert!(
            a.de[k] <= allowed,
            "patch {}: ΔE*ab {:.3} from render spots, more than the form's {form:.3} plus the \
             image's noise ({})",
            k + 1,
            a.de[k],
            summary(&a)
        );
    }
}
