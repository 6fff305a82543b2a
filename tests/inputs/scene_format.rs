//! The grown scene format: per-tile absolute spectra, the C-γ distribution, provenance,
//! reflectances a little above 1, writing and reading back, and the built-in box.

use metamer::color::{delta_e76, Lab};
use metamer::render::deadline::Deadline;
use metamer::render::radiosity::{render_spots_radiosity, run_level, Prepared, RadiosityOptions};
use metamer::render::scene::{Scene, SceneFile};
use metamer::render::{render_spots, SpotOptions};
use serde_json::{json, Value};

use crate::support::{fresh_dir, scenes_dir};

fn box_json(file: &str) -> Value {
    let text = std::fs::read_to_string(scenes_dir().join(file)).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn build(v: &Value) -> Scene {
    let f: SceneFile = serde_json::from_value(v.clone()).unwrap();
    Scene::build(&f, scenes_dir()).unwrap()
}

/// The emitter of `v` rewritten with absolute per-tile spectra: tile t gets s·S(λ)·k_t
/// inline on the 1 nm grid and gain g_t/k_t (k alternating 1 and 2, so some tiles share
/// the spectrum exactly and some only in proportion).
fn absolute_tiles(v: &mut Value, old: &Scene) {
    let s = &old.emitters[0].spectra[0];
    let nm: Vec<f64> = (380..=780).map(|x| x as f64).collect();
    let e = &mut v["emitters"][0];
    e.as_object_mut().unwrap().remove("spectrum");
    e.as_object_mut().unwrap().remove("luminance_cd_m2");
    for (i, t) in e["tiles"].as_array_mut().unwrap().iter_mut().enumerate() {
        let k = 1.0 + (i % 2) as f64;
        let g = t["gain"].as_f64().unwrap();
        t["gain"] = json!(g / k);
        t["spectrum"] = json!({"nm": nm, "values": s.iter().map(|x| x * k).collect::<Vec<_>>()});
    }
}

fn level_readings(scene: &Scene, level: usize) -> Vec<metamer::color::Xyz> {
    let p = Prepared::new(scene).unwrap();
    let l = run_level(&p, &RadiosityOptions::default(), level, Deadline::never()).unwrap();
    let mut out = l.patches;
    out.push(l.white);
    out
}

/// Tile spectra equal to gain × S give the readings of the relative form (radiosity, to
/// 1e-9 relative), and they share one spectrum.
#[test]
fn per_tile_spectra_equal_to_gain_times_s_render_as_the_old_form() {
    let v = box_json("validation-box.json");
    let old = build(&v);
    let mut w = v.clone();
    absolute_tiles(&mut w, &old);
    let new = build(&w);
    assert_eq!(new.emitters[0].spectra.len(), 1);
    for (a, b) in level_readings(&old, 2).iter().zip(level_readings(&new, 2)) {
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() <= 1e-9 * a[k].abs(), "{a:?} vs {b:?}");
        }
    }
}

/// Absolute tiles exclude the relative form's fields, and every tile needs a spectrum.
#[test]
fn absolute_tiles_are_checked() {
    let v = box_json("validation-box.json");
    let old = build(&v);
    let mut w = v.clone();
    absolute_tiles(&mut w, &old);
    let f = |w: &Value| {
        let f: SceneFile = serde_json::from_value(w.clone()).unwrap();
        Scene::build(&f, scenes_dir()).unwrap_err()
    };
    let mut a = w.clone();
    a["emitters"][0]["luminance_cd_m2"] = json!(100.0);
    assert_eq!(f(&a).path, "emitters[0].luminance_cd_m2");
    let mut b = w.clone();
    b["emitters"][0]["tiles"][7]
        .as_object_mut()
        .unwrap()
        .remove("spectrum");
    assert_eq!(f(&b).path, "emitters[0].tiles[7].spectrum");
}

/// An asymmetric C-γ table (brighter towards +edge_u than −edge_u, and towards +edge_v)
/// with a different spectrum on every other tile: the radiosity solver and the path tracer
/// agree within the path tracer's 95 % half-width plus the solver's bound.
#[test]
fn radiosity_agrees_with_the_path_tracer_on_an_asymmetric_box_with_tile_spectra() {
    let mut v = box_json("validation-box.json");
    let old = build(&v);
    absolute_tiles(&mut v, &old);
    // Every third tile bluer: its spectrum tilted by λ.
    let e = &mut v["emitters"][0];
    for (i, t) in e["tiles"].as_array_mut().unwrap().iter_mut().enumerate() {
        if i % 3 == 0 {
            let nm: Vec<f64> = t["spectrum"]["nm"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            let vals: Vec<f64> = t["spectrum"]["values"]
                .as_array()
                .unwrap()
                .iter()
                .zip(&nm)
                .map(|(x, l)| x.as_f64().unwrap() * (1.6 - (l - 380.0) / 400.0))
                .collect();
            t["spectrum"]["values"] = json!(vals);
        }
    }
    e["distribution"] = json!({"kind": "c_gamma", "table": {
        "c_deg": [0, 90, 180, 270],
        "gamma_deg": [0, 30, 60, 90],
        "values": [[1, 0.95, 0.7, 0.2], [1, 0.9, 0.6, 0.1], [1, 0.8, 0.4, 0.05], [1, 0.85, 0.5, 0.1]]
    }});
    let scene = build(&v);
    assert!(scene.emitters[0].spectra.len() >= 2);
    let rad = render_spots_radiosity(&scene, &RadiosityOptions::default(), &|_| {}).unwrap();
    assert!(rad.converged);
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
            "patch {}: ΔE*ab {de:.3} vs half-width {:.3} + bound {:.4}",
            r.patch,
            p.uncertainty.de_ab(),
            r.uncertainty.de_ab()
        );
    }
    let dy = rad.white[1] / path.white[1] - 1.0;
    assert!(dy.abs() < 0.003, "white Y differs by {:.3} %", dy * 100.0);
}

/// A scene written by `SceneFile::write` reads back to the same file and the same numbers;
/// provenance is carried through untouched.
#[test]
fn a_written_scene_reads_back_and_renders_the_same() {
    let dir = fresh_dir("write");
    let mut v = box_json("validation-box-ldc.json");
    let text = serde_json::to_string(&v)
        .unwrap()
        .replace("\"../", &format!("\"{}/../", scenes_dir().display()));
    v = serde_json::from_str(&text).unwrap();
    v["provenance"] = json!({"journal_sha256": "ab12", "instruments": ["cs100a"], "rms": 0.004});
    let f: SceneFile = serde_json::from_value(v).unwrap();
    let path = dir.join("box.json");
    f.write(&path).unwrap();
    let back = SceneFile::from_json(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(back, f);
    let a = Scene::build(&f, scenes_dir()).unwrap();
    let b = Scene::load(&path).unwrap();
    assert_eq!(b.provenance.as_ref().unwrap()["rms"], json!(0.004));
    assert_eq!(level_readings(&a, 1), level_readings(&b, 1));
}

/// Reflectance up to 1.05 is a warning, above it an error; a closed box at ρ = 1.05 with
/// an absorbing emitter still converges, to more light than at ρ = 1.
#[test]
fn reflectance_slightly_above_one_warns_and_converges() {
    let mut v = box_json("validation-box.json");
    for i in 0..6 {
        v["surfaces"][i]["reflectance"] = json!(1.05);
    }
    let scene = build(&v);
    assert_eq!(scene.warnings.len(), 6, "{:?}", scene.warnings);
    assert!(scene.warnings[0].starts_with("surfaces[0].reflectance"));
    let hot = level_readings(&scene, 1);
    for i in 0..6 {
        v["surfaces"][i]["reflectance"] = json!(1.0);
    }
    let unit = level_readings(&build(&v), 1);
    assert!(hot[24][1].is_finite() && hot[24][1] > unit[24][1]);
    v["surfaces"][2]["reflectance"] = json!(1.06);
    let f: SceneFile = serde_json::from_value(v).unwrap();
    let e = Scene::build(&f, scenes_dir()).unwrap_err();
    assert_eq!(e.path, "surfaces[2].reflectance");
}

/// The built-in box is the file's box.
#[test]
fn the_built_in_box_is_the_data_file() {
    let a = Scene::builtin("validation-box").unwrap();
    let b = Scene::load(&scenes_dir().join("validation-box.json")).unwrap();
    assert_eq!(level_readings(&a, 1), level_readings(&b, 1));
}

/// `metamer render spots` with no scene renders the built-in box from any directory.
#[test]
fn render_defaults_work_outside_the_repository() {
    let dir = fresh_dir("cwd");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(["render", "spots", "--method", "radiosity", "--json"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["patches"].as_array().unwrap().len(), 24);
}

/// An emitter whose distribution is an IES or EULUMDAT file renders like the same C-γ table
/// given inline: the files carry the shape to their printed precision (the radiosity
/// readings agree to 1e-4 relative, far below the meter's 0.2 %).
#[test]
fn ies_and_ldt_files_are_emitter_distributions() {
    use metamer::light::ies::{self, IesInfo};
    use metamer::light::ldt::{self, LdtInfo};
    use metamer::light::photometry::Panel;
    use metamer::light::CGammaTable;
    // cos^0.7 towards +edge_u, cos^1.3 elsewhere, interpolated linearly in C.
    let gamma: Vec<f64> = (0..=90).map(f64::from).collect();
    let c: Vec<f64> = (0..72).map(|k| f64::from(k) * 5.0).collect();
    let values: Vec<Vec<f64>> = c
        .iter()
        .map(|&cd| {
            let m = if cd <= 90.0 {
                0.7 + 0.6 * cd / 90.0
            } else if cd >= 270.0 {
                0.7 + 0.6 * (360.0 - cd) / 90.0
            } else {
                1.3
            };
            gamma
                .iter()
                .map(|g: &f64| {
                    if *g >= 90.0 {
                        0.0
                    } else {
                        g.to_radians().cos().powf(m)
                    }
                })
                .collect()
        })
        .collect();
    let table = CGammaTable::new(c, gamma, values).unwrap();
    let panel = Panel {
        width_m: 0.3,
        height_m: 0.3,
        normal_luminance_cd_m2: 100.0,
    };
    let dir = fresh_dir("photometric");
    let ies_info = IesInfo {
        test: "scene test".into(),
        issue_date: "2026-12-01".into(),
        luminaire: "test panel".into(),
        generation: "metamer test".into(),
        extrapolation: None,
    };
    let ldt_info = LdtInfo {
        luminaire: "test panel".into(),
        file_name: "light.ldt".into(),
        date_user: "2026-12-01 metamer".into(),
        extrapolation: None,
    };
    std::fs::write(
        dir.join("light.ies"),
        ies::to_string(&table, &panel, &ies_info),
    )
    .unwrap();
    std::fs::write(
        dir.join("light.ldt"),
        ldt::to_string(&table, &panel, &ldt_info),
    )
    .unwrap();
    let mut v = box_json("validation-box.json");
    // Spectral files named relative to the data directory, as the box names them.
    let inline = {
        let mut v = v.clone();
        v["emitters"][0]["distribution"] = json!({"kind": "c_gamma", "table": table});
        level_readings(&build(&v), 3)
    };
    for kind in ["ies", "ldt"] {
        let file = dir.join(format!("light.{kind}"));
        v["emitters"][0]["distribution"] = json!({"kind": kind, "file": file.to_str().unwrap()});
        let got = level_readings(&build(&v), 3);
        for (a, b) in got.iter().zip(&inline) {
            for k in 0..3 {
                assert!(
                    (a[k] - b[k]).abs() <= 1e-4 * b[k].abs() + 1e-9,
                    "{kind}: {a:?} vs {b:?}"
                );
            }
        }
    }
    // A missing file is an error naming the field.
    v["emitters"][0]["distribution"] = json!({"kind": "ies", "file": "no-such.ies"});
    let f: SceneFile = serde_json::from_value(v).unwrap();
    let e = Scene::build(&f, scenes_dir()).unwrap_err();
    assert_eq!(e.path, "emitters[0].distribution.file");
}

/// A scene saved by an editor that puts a UTF-8 byte-order mark first loads as without it.
#[test]
fn a_scene_with_a_byte_order_mark_loads() {
    let d = fresh_dir("bom");
    std::fs::create_dir_all(d.join("scenes")).unwrap();
    for csv in [
        "colorchecker_babelcolor_average.csv",
        "display_white_ips_lcd.csv",
        "paper_white_reflectance.csv",
    ] {
        std::fs::copy(scenes_dir().join("..").join(csv), d.join(csv)).unwrap();
    }
    let text = std::fs::read_to_string(scenes_dir().join("validation-box.json")).unwrap();
    let (plain, bom) = (d.join("scenes/plain.json"), d.join("scenes/bom.json"));
    std::fs::write(&plain, &text).unwrap();
    std::fs::write(&bom, format!("\u{feff}{text}")).unwrap();
    let a = Scene::load(&bom).unwrap();
    let b = Scene::load(&plain).unwrap();
    assert_eq!(format!("{a:?}"), format!("{b:?}"));
    std::fs::remove_dir_all(&d).ok();
}

/// A megabyte in a key, a value or a file name is quoted to 80 characters, not whole.
#[test]
fn a_megabyte_field_is_not_echoed_whole_in_a_scene_error() {
    let big = "y".repeat(1 << 20);
    let d = fresh_dir("echo");
    let mut key = box_json("validation-box.json");
    key["surfaces"][0][big.as_str()] = json!(1);
    let mut value = box_json("validation-box.json");
    value["surfaces"][0]["reflectance"] = json!({ "nm": [400, 700], "values": big });
    let mut file = box_json("validation-box.json");
    file["surfaces"][0]["reflectance"] = json!({ "file": big });
    for (what, v, words) in [
        ("key", key, "surfaces[0].yyy"),
        ("value", value, "surfaces[0].reflectance.values"),
        ("file", file, "surfaces[0].reflectance.file"),
    ] {
        let p = d.join(format!("{what}.json"));
        std::fs::write(&p, v.to_string()).unwrap();
        let e = Scene::load(&p).unwrap_err().to_string();
        assert!(e.len() < 1000, "{what}: {} bytes: {}", e.len(), &e[..1000]);
        assert!(e.contains(words), "{what}: {e}");
        assert!(e.contains('…'), "{what}: {e}");
    }
    std::fs::remove_dir_all(&d).ok();
}
