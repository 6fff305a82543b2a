//! The radiosity solver against the path tracer on the validation box and its ldc variant,
//! and its refusal of scenes it cannot solve.

use std::path::Path;

use metamer::color::{delta_e76, Lab};
use metamer::render::radiosity::{qualifies, render_spots_radiosity, RadiosityOptions};
use metamer::render::scene::{Scene, SceneFile};
use metamer::render::{render_spots, SpotOptions};
use serde_json::{json, Value};

fn data_dir() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/data/scenes"))
}

fn load(file: &str) -> Value {
    let text = std::fs::read_to_string(data_dir().join(file)).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn build(v: &Value) -> Scene {
    let f: SceneFile = serde_json::from_value(v.clone()).unwrap();
    Scene::build(&f, data_dir()).unwrap()
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
            de < p.de_ci95 + r.de_bound,
            "{file} patch {}: ΔE*ab {de:.3} vs half-width {:.3} + bound {:.4}",
            r.patch,
            p.de_ci95,
            r.de_bound
        );
        assert!(r.de_bound < 0.1, "patch {}: bound {}", r.patch, r.de_bound);
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
