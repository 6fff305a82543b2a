//! The radiosity solver against the path tracer on the validation box and its ldc variant,
//! and its refusal of scenes it cannot solve.

use std::ffi::OsStr;
use std::path::Path;

use metamer::color::{delta_e76, Lab};
use metamer::render::radiosity::{qualifies, render_spots_radiosity, RadiosityOptions};
use metamer::render::scene::{Scene, SceneFile};
use metamer::render::{render_spots, SpotOptions};
use serde_json::{json, Value};

use crate::support::{fresh_dir, metamer_in_root, scenes_dir};

fn load(file: &str) -> Value {
    let text = std::fs::read_to_string(scenes_dir().join(file)).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn build(v: &Value) -> Scene {
    let f: SceneFile = serde_json::from_value(v.clone()).unwrap();
    Scene::build(&f, scenes_dir()).unwrap()
}

/// Each patch's CIELAB (against each method's own white) must agree within the path
/// tracer's 95 % half-width plus the solver's own bound. The path side runs to a looser
/// target (half-widths ≈ 0.3) so the test stays at a few CPU-seconds; its seed is fixed,
/// so the comparison is reproducible.
fn cross_check(file: &str) {
    let scene = build(&load(file));
    let rad = render_spots_radiosity(&scene, &RadiosityOptions::default(), &|_| {}).unwrap();
    assert!(rad.converged, "{file}: radiosity did not reach its target");
    let path = render_spots(
        &scene,
        &SpotOptions {
            target_de: 0.3,
            ..SpotOptions::default()
        },
    )
    .unwrap();
    for (r, p) in rad.patches.iter().zip(&path.patches) {
        let lab = |v: [f64; 3]| Lab::new(v[0], v[1], v[2]);
        let de = delta_e76(lab(r.lab), lab(p.lab));
        assert!(
            de < p.uncertainty.de_ab() + r.uncertainty.de_ab(),
            "{file} patch {}: ΔE*ab {de:.3} vs half-width {:.3} + bound {:.4}",
            r.patch,
            p.uncertainty.de_ab(),
            r.uncertainty.de_ab()
        );
        assert!(
            r.uncertainty.de_ab() < 0.1,
            "patch {}: bound {}",
            r.patch,
            r.uncertainty.de_ab()
        );
    }
    // The white itself: the same luminance within the path tracer's noise (its white is
    // refined to a third of the target, i.e. ≈ 0.2 % in Y at 2σ).
    let dy = rad.white[1] / path.white[1] - 1.0;
    assert!(
        dy.abs() < 0.003,
        "{file}: white Y differs by {:.3} %",
        dy * 100.0
    );
}

#[test]
fn radiosity_agrees_with_the_path_tracer_on_the_box() {
    cross_check("validation-box.json");
}

#[test]
fn radiosity_agrees_with_the_path_tracer_on_the_ldc_variant() {
    cross_check("validation-box-ldc.json");
}

#[test]
fn a_surface_inside_the_box_is_refused() {
    let mut v = load("validation-box.json");
    v["surfaces"].as_array_mut().unwrap().push(json!({
        "name": "shelf",
        "corner": [0.1, 0.2, 0.1],
        "edge_u": [0.0, 0.0, 0.2],
        "edge_v": [0.2, 0.0, 0.0],
        "reflectance": 0.5
    }));
    let scene = build(&v);
    let err = qualifies(&scene).unwrap_err().to_string();
    assert!(err.contains("not a convex enclosure"), "{err}");
    assert!(err.contains("shelf"), "{err}");
    // The box as it is qualifies: the chart and patches are decals on the right wall.
    assert!(qualifies(&build(&load("validation-box.json"))).is_ok());
}

/// `render spots --method radiosity` on a scene that is not convex says why and fails;
/// the JSON of a radiosity run names its method and carries each patch's bound.
#[test]
fn cli_method_choice() {
    let dir = fresh_dir("cli");
    let mut v = load("validation-box.json");
    v["surfaces"].as_array_mut().unwrap().push(json!({
        "name": "shelf", "corner": [0.1, 0.2, 0.1], "edge_u": [0.0, 0.0, 0.2],
        "edge_v": [0.2, 0.0, 0.0], "reflectance": 0.5
    }));
    // The scene's spectra are relative paths: write it next to the bundled one's data.
    let file = dir.join("shelf.json");
    let text = serde_json::to_string(&v)
        .unwrap()
        .replace("\"../", &format!("\"{}/../", scenes_dir().display()));
    std::fs::write(&file, text).unwrap();
    let o = metamer_in_root(&[
        OsStr::new("render"),
        OsStr::new("spots"),
        file.as_os_str(),
        OsStr::new("--method"),
        OsStr::new("radiosity"),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("not a convex enclosure") && err.contains("shelf"),
        "{err}"
    );

    let o = metamer_in_root(&[
        OsStr::new("render"),
        OsStr::new("spots"),
        OsStr::new("data/scenes/validation-box.json"),
        OsStr::new("--json"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["method"], "radiosity");
    let patches = r["patches"].as_array().unwrap();
    assert_eq!(patches.len(), 24);
    assert!(patches
        .iter()
        .all(|p| p["de_bound"].as_f64().unwrap() < 0.1));
}

/// `render probes`: a panel of 1000 cd/m², 1 m², 2 m above a black floor gives
/// E = π·L·4·F(0.5, 0.5, 2) under its centre (the corner factor of catalogue C-11).
#[test]
fn cli_probes() {
    let dir = fresh_dir("probes");
    let scene = json!({"name": "plane", "surfaces": [{"name": "floor",
        "corner": [-5.0, 0.0, -5.0], "edge_u": [0.0, 0.0, 10.0], "edge_v": [10.0, 0.0, 0.0],
        "reflectance": 0.0}],
        "emitters": [{"corner": [-0.5, 2.0, -0.5], "edge_u": [1.0, 0.0, 0.0],
        "edge_v": [0.0, 0.0, 1.0], "luminance_cd_m2": 1000.0}]});
    std::fs::write(dir.join("plane.json"), scene.to_string()).unwrap();
    std::fs::write(dir.join("points.csv"), "x,y,z,nx,ny,nz\n0,0,0,0,1,0\n").unwrap();
    let o = metamer_in_root(&[
        OsStr::new("render"),
        OsStr::new("probes"),
        dir.join("plane.json").as_os_str(),
        OsStr::new("--points"),
        dir.join("points.csv").as_os_str(),
        OsStr::new("--json"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["method"], "radiosity");
    let (x, y) = (0.25f64, 0.25f64);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    let corner =
        (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI);
    let want = std::f64::consts::PI * 1000.0 * 4.0 * corner;
    let got = r["probes"][0]["total_lux"].as_f64().unwrap();
    assert!((got - want).abs() < 1e-9 * want, "{got} vs {want}");
}

/// Against the pooled Mitsuba 3 readings of `benches/mitsuba/results` (four runs, each to a
/// 95 % half-width of 0.1; pooled, the half-width of a patch's mean is ≈ 0.06): every
/// patch within 0.083, the pooled half-width of the path tracer's own comparison there.
#[test]
fn radiosity_agrees_with_pooled_mitsuba() {
    let dir = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/benches/mitsuba/results"
    ));
    let runs: Vec<Value> = ["cmf_1", "cmf_2", "light_1", "light_2"]
        .iter()
        .map(|r| {
            let text = std::fs::read_to_string(dir.join(format!("mitsuba_{r}.json"))).unwrap();
            serde_json::from_str(&text).unwrap()
        })
        .collect();
    let mean = |get: &dyn Fn(&Value) -> &Value| -> [f64; 3] {
        std::array::from_fn(|i| {
            runs.iter()
                .map(|r| get(r)[i].as_f64().unwrap())
                .sum::<f64>()
                / runs.len() as f64
        })
    };
    let white = mean(&|r| &r["white"]);
    // The Mitsuba runs were of the box lit by LED-RGB1.
    let scene = build(&load("validation-box-led-rgb1.json"));
    let rad = render_spots_radiosity(&scene, &RadiosityOptions::default(), &|_| {}).unwrap();
    let to_lab = |x: metamer::color::Xyz, w: metamer::color::Xyz| x.to_lab(w);
    let mut worst: f64 = 0.0;
    for (k, r) in rad.patches.iter().enumerate() {
        let m = mean(&|run| &run["patches"][k]["XYZ"]);
        let de = delta_e76(to_lab(r.xyz, rad.white), to_lab(m.into(), white.into()));
        worst = worst.max(de);
        assert!(
            de < 0.083,
            "patch {}: ΔE*ab {de:.3} against Mitsuba",
            r.patch
        );
    }
    eprintln!("max ΔE*ab against pooled Mitsuba: {worst:.4}");
}
