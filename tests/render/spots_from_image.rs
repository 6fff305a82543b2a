//! `metamer render spots-from-image`: metamer's own path-traced image of the validation box
//! read back as the 24 meter readings agrees with `render spots` within the image's
//! stated noise, its JSON is what `validate --simulation` reads, and every image that does
//! not fit the scene is refused naming what differs.

use std::path::{Path, PathBuf};

use metamer::image::{write_xyz_image, XyzImage};
use metamer::output::OutputPolicy;
use serde_json::Value;

use crate::support::{
    fresh_dir, metamer, scenes_dir, srgb_from_xyz, stderr, text, write_rgb_exr, XYZ_CHROMATICITIES,
};

/// The white `render spots` found for the built-in box by radiosity (cd/m²); given to the
/// read-back so the refusals do not trace one first.
const WHITE: &str = "17.9607,19.0511,20.3257";

fn run_json(args: &[&str]) -> Value {
    let o = metamer(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    serde_json::from_str(&text(&o.stdout)).unwrap()
}

fn write(path: &Path, width: usize, height: usize, pixel: [f32; 3]) {
    let img = XyzImage {
        width,
        height,
        pixels: vec![pixel; width * height],
    };
    write_xyz_image(path, &img, &OutputPolicy::new(true)).unwrap();
}

/// The refusal of reading `image` back (of the built-in box unless `scene` is given).
fn refusal(image: &Path, scene: Option<&Path>) -> String {
    let mut args = vec![
        "render".to_string(),
        "spots-from-image".into(),
        image.to_str().unwrap().into(),
        "--white".into(),
        WHITE.into(),
    ];
    if let Some(s) = scene {
        args.extend(["--scene".into(), s.to_str().unwrap().into()]);
    }
    let o = metamer(&args);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(o.stdout.is_empty());
    stderr(&o)
}

#[test]
fn a_path_traced_image_reads_back_as_render_spots_within_its_stated_noise() {
    let dir = fresh_dir("round-trip");
    let image = dir.join("box.exr");
    // 192² keeps the camera's field of view: the 1° cone is about 12 pixels across, some
    // 110 of them, each of 16 independent paths.
    let o = metamer(&[
        "render",
        "image",
        "--spp",
        "16",
        "--width",
        "192",
        "--height",
        "192",
        "-o",
        image.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // The reference: the radiosity solver, deterministic and bounded far below the
    // image's noise.
    let spots = run_json(&[
        "render",
        "spots",
        "--method",
        "radiosity",
        "--target-de",
        "0.05",
        "--json",
    ]);
    let w = &spots["white"];
    let white = format!("{},{},{}", w[0], w[1], w[2]);
    let back = run_json(&[
        "render",
        "spots-from-image",
        image.to_str().unwrap(),
        "--white",
        &white,
        "--json",
    ]);
    assert_eq!(back["method"], "external image");
    assert_eq!(back["image"]["width"], 192);
    assert_eq!(back["image"]["sha256"].as_str().unwrap().len(), 64);
    let (a, b) = (
        spots["patches"].as_array().unwrap(),
        back["patches"].as_array().unwrap(),
    );
    assert_eq!((a.len(), b.len()), (24, 24));
    let f = |v: &Value, k: &str, i: usize| v[k][i].as_f64().unwrap();
    for (r, t) in a.iter().zip(b) {
        assert_eq!(r["patch"], t["patch"]);
        // Each X, Y, Z within 4 of the image's standard errors (plus the radiosity
        // bound's share): 72 comparisons of normal errors all pass at 4σ with odds
        // above 99.5 %, so a failure is a bias, not bad luck.
        let bound = r["de_bound"].as_f64().unwrap();
        for i in 0..3 {
            let (x, y, s) = (f(r, "XYZ", i), f(t, "XYZ", i), f(t, "XYZ_stderr", i));
            assert!(
                (x - y).abs() <= 4.0 * s + bound / 100.0 * x,
                "patch {}: XYZ[{i}] {y} read back against {x} rendered, σ {s}",
                r["patch"]
            );
            assert!(s > 0.0 && s < 0.02 * x, "patch {}: σ {s}", r["patch"]);
        }
        // The same in CIELAB (both against the radiosity white): ΔE*ab within 4 RMS of
        // the image's, 4/1.96 times its 95 % half-width, plus the bound.
        let de = (0..3)
            .map(|i| (f(r, "Lab", i) - f(t, "Lab", i)).powi(2))
            .sum::<f64>()
            .sqrt();
        let h = t["de_ci95"].as_f64().unwrap();
        assert!(
            de <= 4.0 / 1.96 * h + bound,
            "patch {}: ΔE*ab {de} against half-width {h}",
            r["patch"]
        );
        assert!(h < 1.5, "patch {}: half-width {h}", r["patch"]);
    }

    // `validate --simulation` takes the read-back as the simulation's readings.
    let spots_file = dir.join("spots.json");
    std::fs::write(&spots_file, spots.to_string()).unwrap();
    let back_file = dir.join("back.json");
    std::fs::write(&back_file, back.to_string()).unwrap();
    let out = dir.join("validation");
    let o = metamer(&[
        "validate",
        "--reference",
        spots_file.to_str().unwrap(),
        "--test",
        spots_file.to_str().unwrap(),
        "--simulation",
        back_file.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: Value = serde_json::from_str(&text(&o.stdout)).unwrap();
    let all = v.to_string();
    assert!(all.contains("renderer (external image)"), "{all}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The shipped validation box with its files' paths made absolute, so it can be changed
/// and written elsewhere.
fn shipped_scene() -> Value {
    fn absolute(v: &mut Value, base: &Path) {
        match v {
            Value::Object(m) => {
                for (k, x) in m.iter_mut() {
                    match x {
                        Value::String(s) if k == "file" => {
                            *s = base.join(&*s).to_str().unwrap().to_string()
                        }
                        _ => absolute(x, base),
                    }
                }
            }
            Value::Array(a) => a.iter_mut().for_each(|x| absolute(x, base)),
            _ => {}
        }
    }
    let path = scenes_dir().join("validation-box.json");
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    absolute(&mut v, scenes_dir());
    v
}

fn scene_without(dir: &Path, key: &str) -> PathBuf {
    let mut v = shipped_scene();
    v.as_object_mut().unwrap().remove(key).unwrap();
    let p = dir.join(format!("no-{key}.json"));
    std::fs::write(&p, v.to_string()).unwrap();
    p
}

#[test]
fn an_image_that_does_not_fit_the_scene_is_refused_naming_what_differs() {
    let dir = fresh_dir("refusals");
    let p = dir.join("wide.pfm");
    write(&p, 128, 64, [1.0; 3]);
    let e = refusal(&p, None);
    assert!(
        e.contains("wide.pfm: the image is 128×64 pixels, the scene camera's 1014×1014"),
        "{e}"
    );

    let p = dir.join("small.pfm");
    write(&p, 24, 24, [1.0; 3]);
    let e = refusal(&p, None);
    assert!(e.contains("small.pfm: patch 1's cone covers"), "{e}");
    assert!(e.contains("render the image larger"), "{e}");

    let p = dir.join("black.exr");
    write(&p, 128, 128, [0.0; 3]);
    let e = refusal(&p, None);
    assert!(
        e.contains("black.exr: every pixel in patch 1's cone is zero"),
        "{e}"
    );

    let p = dir.join("negative.pfm");
    write(&p, 128, 128, [1.0, -0.5, 1.0]);
    let e = refusal(&p, None);
    assert!(
        e.contains("negative.pfm: patch 1's 1° cone: pixel ("),
        "{e}"
    );
    assert!(e.contains("not a finite XYZ ≥ 0"), "{e}");

    // Radiance in W/(sr·m²) where cd/m² are expected: 683 times too small, and too bright
    // by as much. Patch 19 reads about 0.9 of the white at the right scale.
    for (name, y) in [("watts.pfm", 17.3 / 683.0), ("bright.pfm", 17.3 * 683.0)] {
        let p = dir.join(name);
        write(&p, 128, 128, [y; 3]);
        let e = refusal(&p, None);
        assert!(
            e.contains(&format!("{name}: patch 19 (the chart's white) reads Y = ")),
            "{e}"
        );
        assert!(e.contains("outside 0.1–10"), "{e}");
    }

    // A crop of the camera's frame: where its pixels sit is in the header, not the size.
    let p = dir.join("crop.exr");
    write_rgb_exr(
        &p,
        (64, 64),
        (32, 32),
        (128, 128),
        Some(XYZ_CHROMATICITIES),
        None,
        |_, _| [17.0; 3],
    );
    let e = refusal(&p, None);
    assert!(
        e.contains(
            "crop.exr: its data window (32, 32)–(95, 95) does not cover its display window \
             (0, 0)–(127, 127)"
        ),
        "{e}"
    );

    // whiteLuminance is defined for RGB; on channels named X, Y, Z its meaning is a guess.
    let p = dir.join("xyz-nits.exr");
    {
        use exr::prelude::*;
        let channels = SpecificChannels::build()
            .with_channel("X")
            .with_channel("Y")
            .with_channel("Z")
            .with_pixel_fn(|_: Vec2<usize>| (8.5f32, 8.5f32, 8.5f32));
        let mut image = Image::from_channels((128, 128), channels);
        image.layer_data.attributes.white_luminance = Some(2.0);
        image.write().to_file(&p).unwrap();
    }
    let e = refusal(&p, None);
    assert!(
        e.contains("xyz-nits.exr: its whiteLuminance is 2, which OpenEXR defines for RGB"),
        "{e}"
    );

    // Neither X, Y, Z nor R, G, B: a luminance-only image holds no colour to read.
    let p = dir.join("luminance.exr");
    {
        use exr::prelude::*;
        let channels = SpecificChannels::build()
            .with_channel("L")
            .with_pixel_fn(|_: Vec2<usize>| (17.0f32,));
        Image::from_channels((128, 128), channels)
            .write()
            .to_file(&p)
            .unwrap();
    }
    let e = refusal(&p, None);
    assert!(
        e.contains("luminance.exr") && e.contains("has the channels L"),
        "{e}"
    );

    let good = dir.join("good.pfm");
    write(&good, 128, 128, [17.0; 3]);
    let e = refusal(&good, Some(&scene_without(&dir, "meter")));
    assert!(
        e.contains("no-meter.json: the scene has no meter (its acceptance angle)"),
        "{e}"
    );
    let e = refusal(&good, Some(&scene_without(&dir, "camera")));
    assert!(e.contains("no-camera.json: the scene has no camera"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The 24 readings' XYZ of `image` read back against the built-in box with the given
/// white.
fn read_back(image: &Path) -> Vec<[f64; 3]> {
    let v = run_json(&[
        "render",
        "spots-from-image",
        image.to_str().unwrap(),
        "--white",
        WHITE,
        "--json",
    ]);
    v["patches"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| std::array::from_fn(|i| p["XYZ"][i].as_f64().unwrap()))
        .collect()
}

/// What an OpenEXR header says of its pixels is what the read-back reads, each file's XYZ
/// known by construction: whiteLuminance scales to cd/m², R, G, B without chromaticities
/// are BT.709 with D65, and overscan around the display window is cut off.
#[test]
fn an_exr_header_is_read_as_openexr_defines_it() {
    let dir = fresh_dir("exr-header");
    // A uniform image reads, in every cone, its one XYZ.
    let xyz = [16.0f64, 17.0, 18.5];
    let uniform = |name: &str, got: Vec<[f64; 3]>, tolerance: f64| {
        assert_eq!(got.len(), 24);
        for (k, g) in got.iter().enumerate() {
            for c in 0..3 {
                assert!(
                    (g[c] - xyz[c]).abs() <= tolerance * xyz[c],
                    "{name}: patch {}: XYZ {g:?} against {xyz:?}",
                    k + 1
                );
            }
        }
    };
    let p = dir.join("nits.exr");
    write_rgb_exr(
        &p,
        (128, 128),
        (0, 0),
        (128, 128),
        Some(XYZ_CHROMATICITIES),
        Some(2.0),
        |_, _| xyz.map(|v| (v / 2.0) as f32),
    );
    // Halving and doubling are exact in binary; the cone's weighted mean rounds.
    uniform("whiteLuminance 2", read_back(&p), 1e-6);
    let p = dir.join("rec709.exr");
    write_rgb_exr(&p, (128, 128), (0, 0), (128, 128), None, None, |_, _| {
        srgb_from_xyz(xyz)
    });
    // The standard's four-decimal matrix is its exact inverse to a few parts in 10⁴.
    uniform("no chromaticities", read_back(&p), 1e-3);

    // A pattern, so a frame read from the wrong place reads other values.
    let pattern = |x: usize, y: usize| {
        let f = 1.0 + 0.3 * ((x as f64 / 7.0).sin() * (y as f64 / 5.0).cos());
        xyz.map(|v| (v * f) as f32)
    };
    let plain = dir.join("plain.exr");
    let img = XyzImage {
        width: 128,
        height: 128,
        pixels: (0..128 * 128).map(|i| pattern(i % 128, i / 128)).collect(),
    };
    write_xyz_image(&plain, &img, &OutputPolicy::new(true)).unwrap();
    let p = dir.join("overscan.exr");
    write_rgb_exr(
        &p,
        (140, 136),
        (-8, -4),
        (128, 128),
        Some(XYZ_CHROMATICITIES),
        None,
        |x, y| {
            if (8..136).contains(&x) && (4..132).contains(&y) {
                pattern(x - 8, y - 4)
            } else {
                [1e4; 3]
            }
        },
    );
    assert_eq!(read_back(&p), read_back(&plain));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A white traced for the read-back that stops at its time limit short of its target is
/// used with a stated warning: on stderr, and in the JSON's `warnings` and `white_trace`.
/// One that reaches its target says so and warns of nothing.
#[test]
fn a_white_cut_short_by_the_time_limit_is_a_stated_warning() {
    let dir = fresh_dir("short-white");
    let p = dir.join("box.pfm");
    write(&p, 128, 128, [17.0; 3]);
    let image = p.to_str().unwrap();
    // A third of 0.0003 ΔE*ab takes the path tracer hours; it gets a second.
    let o = metamer(&[
        "render",
        "spots-from-image",
        image,
        "--target-de",
        "0.0003",
        "--max-seconds",
        "1",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("warning: the reference white stopped at the time limit (1 s)"),
        "{e}"
    );
    let v: Value = serde_json::from_str(&text(&o.stdout)).unwrap();
    let trace = &v["white_trace"];
    assert_eq!(trace["reached"], false, "{v}");
    assert!(
        (trace["target_de"].as_f64().unwrap() - 0.0001).abs() < 1e-12,
        "{trace}"
    );
    assert!(trace["de_ci95"].as_f64().unwrap() > 0.0001, "{trace}");
    assert!(trace["samples"].as_u64().unwrap() >= 2, "{trace}");
    assert_eq!(trace["XYZ"], v["white"]);
    let warnings = v["warnings"].as_array().unwrap();
    assert_eq!(warnings.len(), 1);
    assert!(e.contains(warnings[0].as_str().unwrap()), "{e}");

    let o = metamer(&[
        "render",
        "spots-from-image",
        image,
        "--target-de",
        "6",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    let v: Value = serde_json::from_str(&text(&o.stdout)).unwrap();
    assert_eq!(v["white_trace"]["reached"], true, "{v}");
    assert!(v["white_trace"]["de_ci95"].as_f64().unwrap() < 2.0);
    assert_eq!(v["warnings"], Value::Array(vec![]));
    std::fs::remove_dir_all(&dir).unwrap();
}
