//! `metamer export --to blender` rendered by Blender 4.2's Cycles (the PyPI `bpy`), read
//! back with `render spots-from-image` and compared per patch with what an ideal RGB
//! renderer of the export must produce: metamer's radiosity solver on the scene's RGB form
//! (`export::rgb::rgb_form`), an independent computation of the same numbers (a
//! deterministic solver, not a path tracer, and not Blender). Agreement checks the
//! script's geometry, camera orientation, emission units, colours and the EXR's colour
//! space at once. The same test prints, per patch, the ΔE*ab between that RGB expectation
//! and metamer's spectral rendering: what rendering this box in RGB costs.
//!
//! Without bpy the test prints "skipped" with the reason and passes, unless
//! `METAMER_ORACLES=required`, when it fails (`support::oracle`).

use std::process::Command;

use metamer::color::Xyz;
use metamer::experiment::readings::{write_readings, PatchReading};
use metamer::export::{self, rgb, ExportRequest, Renderer};
use metamer::render::job::spots_from_image;
use metamer::render::radiosity::{render_spots_radiosity, RadiosityOptions, RadiosityResult};
use metamer::render::Scene;

use crate::support::fresh_dir;
use crate::support::oracle::BLENDER;

/// 192² keeps the meter's 1° cone about 12 pixels across (tests/render/spots_from_image.rs).
const SIZE: usize = 192;
const SAMPLES: u32 = 64;

fn lab(xyz: Xyz, white: Xyz) -> [f64; 3] {
    let l = xyz.to_lab(white);
    [l.l, l.a, l.b]
}

fn de(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}

/// Exports the built-in box `name`, renders it with Cycles and compares; None when bpy is
/// missing and not required.
fn round_trip(name: &str) -> Option<()> {
    let dir = fresh_dir(&format!("export-blender-{name}"));
    let out = dir.join("blender");
    let report = export::run(&ExportRequest::new(
        Some(name.into()),
        Renderer::Blender,
        out.clone(),
    ))
    .unwrap();
    assert!(report.approximation.is_exact());
    let python = BLENDER.find()?;
    let image = dir.join("cycles.exr");
    let size = SIZE.to_string();
    let o = Command::new(python)
        .arg(out.join("scene.py"))
        .args(["--samples", &SAMPLES.to_string(), "--width", &size])
        .args(["--height", &size, "--threads", "2", "-o"])
        .arg(&image)
        .output()
        .expect("python3 runs");
    assert!(
        o.status.success(),
        "Cycles did not render the export: {}",
        String::from_utf8_lossy(&o.stderr)
    );

    let scene = Scene::builtin(name).unwrap();
    let options = RadiosityOptions {
        target_de: 0.05,
        ..RadiosityOptions::default()
    };
    let spectral = render_spots_radiosity(&scene, &options, &|_| {}).unwrap();
    let form = rgb::rgb_form(&scene, &report.approximation);
    let options = RadiosityOptions {
        white: Some(spectral.white),
        ..options
    };
    let expected = render_spots_radiosity(&form, &options, &|_| {}).unwrap();

    let mut request =
        spots_from_image::SpotsFromImageRequest::new(image.clone(), Some(name.into()));
    request.white = Some(spectral.white);
    let back = spots_from_image::run(&request, &|_| {}).unwrap();
    let json: serde_json::Value = serde_json::from_str(&back.to_json().unwrap()).unwrap();
    let patches = json["patches"].as_array().unwrap();
    assert_eq!(patches.len(), 24);

    let white = spectral.white;
    let (mut zz, mut n, mut worst_z) = (0.0, 0.0, 0.0f64);
    let mut rows = Vec::new();
    for ((s, e), p) in spectral.patches.iter().zip(&expected.patches).zip(patches) {
        assert_eq!(s.patch, e.patch);
        assert_eq!(p["patch"].as_u64(), Some(e.patch as u64));
        let got = Xyz {
            x: p["XYZ"][0].as_f64().unwrap(),
            y: p["XYZ"][1].as_f64().unwrap(),
            z: p["XYZ"][2].as_f64().unwrap(),
        };
        let bound = e.uncertainty.de_ab();
        for k in 0..3 {
            let se = p["XYZ_stderr"][k].as_f64().unwrap();
            let diff = got[k] - e.xyz[k];
            // Four standard errors of the image's cone mean, plus the solver's bound (a
            // ΔE*ab, taken as that many percent of the value as tests/render/spots_from_image
            // does): 72 normal comparisons all pass at 4σ with odds above 99.5 %. A wrong
            // colour space, unit, colour or mirrored image is off by far more.
            assert!(
                diff.abs() <= 4.0 * se + bound / 100.0 * e.xyz[k].abs(),
                "{name} patch {}: XYZ[{k}] Cycles {} against the RGB form's {} (σ {se}, bound \
                 {bound})",
                e.patch,
                got[k],
                e.xyz[k]
            );
            let z = diff / se;
            zz += z * z;
            n += 1.0;
            worst_z = worst_z.max(z.abs());
        }
        rows.push((
            e.patch,
            de(lab(got, white), lab(e.xyz, white)),
            de(lab(e.xyz, white), lab(s.xyz, white)),
            e.xyz[1] / s.xyz[1],
        ));
    }
    let rms = (zz / n).sqrt();
    eprintln!(
        "{name}: Cycles ({SIZE}², {SAMPLES} spp) against the RGB form: z rms {rms:.2}, max \
         |z| {worst_z:.2} over 72 channels"
    );
    eprintln!("patch | ΔE*ab Cycles vs RGB form | ΔE*ab RGB form vs spectral (the cost) | Y ratio");
    for (p, a, b, y) in &rows {
        eprintln!("{p} | {a:.3} | {b:.3} | {y:.4}");
    }
    let costs: Vec<f64> = rows.iter().map(|r| r.2).collect();
    eprintln!(
        "{name}: cost of rendering in RGB, ΔE*ab max {:.3}, mean {:.3}",
        costs.iter().cloned().fold(0.0, f64::max),
        costs.iter().sum::<f64>() / costs.len() as f64
    );
    // Noise alone gives an rms of z near 1; a bias the per-channel bound let through
    // (a small unit or colour error) shows as an rms well above it.
    assert!(rms < 2.0, "{name}: z rms {rms}");
    if name == "validation-box" {
        experiment_takes(&dir, &image, &spectral);
    }
    Some(())
}

/// `metamer experiment --simulation-image` takes the Cycles image as the simulation: the
/// stage names the image, and the report compares box, display and Cycles on 24 patches.
/// The box's readings are metamer's spectral rendering (a box read without meter noise).
fn experiment_takes(dir: &std::path::Path, image: &std::path::Path, box_: &RadiosityResult) {
    let spots = dir.join("box-spots.csv");
    let rows: Vec<(usize, PatchReading)> = box_
        .patches
        .iter()
        .map(|p| (p.patch, PatchReading::of(&[p.xyz])))
        .collect();
    write_readings(&spots, &rows).unwrap();
    let out = dir.join("experiment");
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/scenes/validation-box.json"
    );
    let o = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(["experiment", "-o"])
        .arg(&out)
        .args(["--box-scene", scene, "--box-spots"])
        .arg(&spots)
        .arg("--simulation-image")
        .arg(image)
        .args(["--target-de", "0.5", "--repeats", "1"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let read = |f: &str| std::fs::read_to_string(out.join(f)).unwrap();
    let sim: serde_json::Value = serde_json::from_str(&read("simulation/simulation.json")).unwrap();
    assert_eq!(sim["method"], "external image");
    assert_eq!(sim["source"]["image"], image.to_str().unwrap());
    let v: serde_json::Value = serde_json::from_str(&read("validation/comparisons.json")).unwrap();
    for side in [
        "display_vs_box",
        "simulation_vs_box",
        "display_vs_simulation",
    ] {
        assert!(
            v[side]["max_de76"]["value"].as_f64().is_some(),
            "{side}: {v}"
        );
    }
    assert!(read("validation/report.html")
        .contains(&format!("external renderer: the image {}", image.display())));
}

#[test]
fn cycles_renders_the_exported_default_box_as_its_rgb_form() {
    round_trip("validation-box");
}

#[test]
fn cycles_renders_the_exported_led_box_as_its_rgb_form() {
    round_trip("validation-box-led-rgb1");
}

#[test]
fn the_export_script_states_its_colours_and_settings() {
    let dir = fresh_dir("export-blender-script");
    let out = dir.join("blender");
    export::run(&ExportRequest::new(None, Renderer::Blender, out.clone())).unwrap();
    let script = std::fs::read_to_string(out.join("scene.py")).unwrap();
    for needle in [
        "cycles.use_denoising = False",
        "cycles.sample_clamp_direct = 0.0",
        "cycles.pixel_filter_type = \"BOX\"",
        "view_transform = \"Standard\"",
        "data.sensor_fit = \"VERTICAL\"",
    ] {
        assert!(script.contains(needle), "{needle}");
    }
    let readme = std::fs::read_to_string(out.join("README.md")).unwrap();
    assert!(readme.contains("von Kries"), "{readme}");
}
