//! Bad scenes and options: a clear error in bounded time, never a panic, a huge
//! allocation or a NaN printed as a result.

use std::path::PathBuf;
use std::time::Instant;

use metamer::render::radiosity::{render_spots_radiosity, RadiosityOptions};
use metamer::render::scene::{Scene, SceneFile};
use metamer::render::spot::SpotError;
use metamer::render::{render_spots, SpotOptions};
use serde_json::{json, Value};

use crate::support::{fresh_dir, metamer, scenes_dir};

fn box_json() -> Value {
    let text = std::fs::read_to_string(scenes_dir().join("validation-box.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn build_err(v: &Value) -> (String, String) {
    let f: SceneFile = serde_json::from_value(v.clone()).unwrap();
    let e = Scene::build(&f, scenes_dir()).unwrap_err();
    (e.path, e.message)
}

fn temp_file(tag: &str, v: &Value) -> PathBuf {
    let d = fresh_dir(tag);
    let text = serde_json::to_string(v)
        .unwrap()
        .replace("\"../", &format!("\"{}/../", scenes_dir().display()));
    let f = d.join("scene.json");
    std::fs::write(&f, text).unwrap();
    f
}

#[test]
fn a_huge_tile_grid_is_refused_before_allocating() {
    let mut v = box_json();
    v["emitters"][0]["rows"] = json!(100_000);
    v["emitters"][0]["cols"] = json!(100_000);
    let t = Instant::now();
    let (path, message) = build_err(&v);
    assert_eq!(path, "emitters[0].rows");
    assert!(message.contains("1000"), "{message}");
    assert!(t.elapsed().as_secs_f64() < 1.0);
}

#[test]
fn too_many_surfaces_are_refused() {
    let mut v = box_json();
    let s = v["surfaces"][0].clone();
    v["surfaces"] = json!(vec![s; 20_001]);
    assert_eq!(build_err(&v).0, "surfaces");
}

#[test]
fn a_dark_scene_or_an_infinite_light_is_refused() {
    let mut v = box_json();
    v["emitters"][0]["luminance_cd_m2"] = json!(0.0);
    let (path, message) = build_err(&v);
    assert_eq!(path, "emitters");
    assert!(message.contains("no light"), "{message}");
    let mut v = box_json();
    for t in v["emitters"][0]["tiles"].as_array_mut().unwrap() {
        t["gain"] = json!(0.0);
    }
    assert_eq!(build_err(&v).0, "emitters");
    let mut v = box_json();
    v["emitters"][0]["tiles"][4]["gain"] = json!(1e308);
    let (path, message) = build_err(&v);
    assert_eq!(path, "emitters[0].tiles[4].gain");
    assert!(message.contains("above"), "{message}");
}

#[test]
fn the_json_path_of_a_bad_field_is_reported() {
    let mut v = box_json();
    v["surfaces"][0]["reflectance"]["outside"] = json!("clamp");
    let f = temp_file("path", &v);
    let e = Scene::load(&f).unwrap_err().to_string();
    assert!(e.contains("surfaces[0].reflectance.outside"), "{e}");
    assert!(e.contains("hold_ends"), "{e}");
}

#[test]
fn a_zero_or_negative_time_limit_is_refused() {
    let scene = Scene::load(&scenes_dir().join("validation-box.json")).unwrap();
    for s in [0.0, -1.0, f64::NAN] {
        let o = SpotOptions {
            max_seconds: s,
            ..SpotOptions::default()
        };
        assert!(matches!(
            render_spots(&scene, &o),
            Err(SpotError::BadTimeLimit(_))
        ));
        let r = RadiosityOptions {
            max_seconds: s,
            ..RadiosityOptions::default()
        };
        assert!(render_spots_radiosity(&scene, &r, &|_| {}).is_err());
    }
    let o = metamer(&["render", "spots", "--max-seconds", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--max-seconds"));
}

/// 4,000 small tiles on the floor make every ray scan thousands of rectangles: both
/// methods stop at the limit with an error or a partial result, never later.
#[test]
fn the_time_limit_holds_on_a_detailed_scene() {
    let mut v = box_json();
    let floor = v["surfaces"][0].clone();
    let n = 63;
    let side = 0.5 / n as f64;
    for i in 0..n {
        for j in 0..n {
            let mut s = floor.clone();
            s["name"] = json!(format!("tile {i} {j}"));
            s["corner"] = json!([j as f64 * side, 0.001, i as f64 * side]);
            s["edge_u"] = json!([0.0, 0.0, side]);
            s["edge_v"] = json!([side, 0.0, 0.0]);
            v["surfaces"].as_array_mut().unwrap().push(s);
        }
    }
    let f: SceneFile = serde_json::from_value(v).unwrap();
    let scene = Scene::build(&f, scenes_dir()).unwrap();
    let t = Instant::now();
    let r = render_spots(
        &scene,
        &SpotOptions {
            max_seconds: 1.0,
            target_de: 0.01,
            ..SpotOptions::default()
        },
    );
    let secs = t.elapsed().as_secs_f64();
    assert!(secs < 2.5, "path tracer took {secs} s for a 1 s limit");
    match r {
        Ok(r) => assert!(!r.converged && r.patches.iter().all(|p| p.xyz[1].is_finite())),
        Err(e) => assert!(matches!(e, SpotError::TimeLimit { .. }), "{e}"),
    }
    let t = Instant::now();
    let r = render_spots_radiosity(
        &scene,
        &RadiosityOptions {
            max_seconds: 1.0,
            ..RadiosityOptions::default()
        },
        &|_| {},
    );
    let secs = t.elapsed().as_secs_f64();
    assert!(secs < 2.5, "radiosity took {secs} s for a 1 s limit");
    assert!(r.is_err());
}
