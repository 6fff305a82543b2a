//! `metamer light fit` and `metamer light show` through the binary.

use std::process::Command;

use crate::support::unused_dir;

#[test]
fn fit_exports_and_show_reads_back() {
    let dir = unused_dir("fit");
    std::fs::create_dir_all(&dir).unwrap();
    let bin = env!("CARGO_BIN_EXE_metamer");
    let run = |args: &[&str]| {
        let out = Command::new(bin)
            .args(args)
            .current_dir(&dir)
            .output()
            .unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let csv = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/light_falloff_9_angles.csv"
    );
    let fit_args = [
        "light",
        "fit",
        "--falloff",
        csv,
        "-o",
        "LIGHT.json",
        "--ies",
        "p.ies",
        "--ldt",
        "p.ldt",
        "--chart",
        "LIGHT.svg",
        "--width-m",
        "0.3",
        "--height-m",
        "0.3",
        "--luminance",
        "1000",
    ];
    let (code, out, err) = run(&fit_args);
    assert_eq!(code, Some(0), "{out}{err}");
    for m in [
        "lambertian",
        "cos-power",
        "cos-poly",
        "lobes",
        "series",
        "spline",
        "chose ",
    ] {
        assert!(out.contains(m), "{m} missing from\n{out}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("LIGHT.json")).unwrap()).unwrap();
    assert_eq!(json["normal_luminance"], 1.0);
    // The chart shows every candidate's held-out error as the fit scored it, the tie
    // limit, and the unit (relative readings) in its title.
    let svg = std::fs::read_to_string(dir.join("LIGHT.svg")).unwrap();
    assert!(svg.contains("(chosen)"));
    assert!(
        svg.contains("readings relative to the normal (1 at 0°)"),
        "title"
    );
    assert!(svg.contains("held-out error: leave-one-out RMS"));
    assert!(svg.contains("tie limit"));
    for c in json["candidates"].as_array().unwrap() {
        let v = c["cv_rms"].as_f64().unwrap();
        let shown = format!("{:.*}", (2 - v.log10().floor() as i32).max(0) as usize, v);
        assert!(
            svg.contains(&format!("\n{shown}\n")),
            "{} {shown}",
            c["model"]
        );
    }
    // The panel: I₀ = 1000 cd/m² · 0.09 m² = 90 cd, read back from both files.
    for f in ["p.ies", "p.ldt"] {
        let (code, out, err) = run(&["light", "show", f]);
        assert_eq!(code, Some(0), "{out}{err}");
        assert!(out.contains("normal 90.000 cd"), "{out}");
        assert!(out.contains("normal luminance 1000.0 cd/m²"), "{out}");
    }
    // Existing outputs need --force; relative readings need --luminance for candela.
    let (code, _, err) = run(&fit_args);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--force"), "{err}");
    let (code, _, err) = run(&[
        "light",
        "fit",
        "--falloff",
        csv,
        "-o",
        "b.json",
        "--ies",
        "b.ies",
        "--width-m",
        "0.3",
        "--height-m",
        "0.3",
    ]);
    assert_eq!(code, Some(2));
    assert!(err.contains("--luminance"), "{err}");
    let (code, _, err) = run(&[
        "light",
        "fit",
        "--falloff",
        csv,
        "-o",
        "c.json",
        "--ldt",
        "c.ldt",
    ]);
    assert_eq!(code, Some(2));
    assert!(err.contains("--width-m"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
