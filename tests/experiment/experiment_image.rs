//! `metamer experiment` with the camera image: rendered by default from the radiosity
//! solution, its patch regions reading what the spot readings read, reproduced mirrored,
//! shown whole on the simulated monitor and read patch by patch where the patches lie on
//! the screen.

use std::path::Path;
use std::process::{Command, Output};

use metamer::color::{delta_e76, Xyz};
use metamer::image::read_xyz_image;
use serde_json::Value;

use crate::experiment::{box_spots, SCENE};
use crate::support::{fresh_dir, json};

fn run(out: &Path, spots: &Path, extra: &[&str]) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(["experiment", "-o"])
        .arg(out)
        .args(["--box-scene", SCENE, "--box-spots"])
        .arg(spots)
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

/// patch → (X, Y, Z, sd_X, sd_Y, sd_Z, n) of a readings CSV.
fn readings(path: &Path) -> Vec<(usize, [f64; 7])> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            (v[0] as usize, std::array::from_fn(|k| v[k + 1]))
        })
        .collect()
}

type V3 = [f64; 3];
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn unit(a: V3) -> V3 {
    let l = dot(a, a).sqrt();
    a.map(|x| x / l)
}
fn v3(v: &Value) -> V3 {
    std::array::from_fn(|k| v[k].as_f64().unwrap())
}

/// The scene's pinhole camera by hand from its file: forward to the look-at point, right
/// = forward × up, up' = right × forward, and the vertical field of view.
struct Pinhole {
    position: V3,
    forward: V3,
    right: V3,
    up: V3,
    tan_half: f64,
}

fn pinhole(scene: &Value) -> Pinhole {
    let c = &scene["camera"];
    let position = v3(&c["position"]);
    let forward = unit(sub(v3(&c["look_at"]), position));
    let right = unit(cross(forward, v3(&c["up"])));
    Pinhole {
        position,
        forward,
        right,
        up: cross(right, forward),
        tan_half: (c["vfov_deg"].as_f64().unwrap().to_radians() / 2.0).tan(),
    }
}

/// The centre of patch `k` from the scene file: corner + (edge_u + edge_v)/2.
fn patch_centre(scene: &Value, k: usize) -> V3 {
    let s = scene["surfaces"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["name"] == format!("patch {k}"))
        .unwrap();
    let (c, u, v) = (v3(&s["corner"]), v3(&s["edge_u"]), v3(&s["edge_v"]));
    std::array::from_fn(|i| c[i] + (u[i] + v[i]) / 2.0)
}

/// The default run renders the 1014² image from the radiosity solution; the image's mean
/// over each patch's 1° spot (computed here from the pixels: those whose centre ray lies
/// inside the cone, weighted by solid angle, cos³ off the optical axis) agrees with the
/// patch's spot reading within the simulation's ΔE*ab target; a second call re-uses every
/// stage.
#[test]
fn the_image_by_default_reads_what_the_spots_read_and_is_reused() {
    let dir = fresh_dir("default");
    let spots = box_spots(&dir);
    let out = dir.join("exp");
    let t = std::time::Instant::now();
    run(&out, &spots, &[]);
    let first = t.elapsed().as_secs_f64();
    let sim = json(&out.join("simulation/simulation.json"));
    assert_eq!(sim["image"], "image.exr");
    assert_eq!(sim["image_method"], "radiosity");
    let img = read_xyz_image(&out.join("simulation/image.exr")).unwrap();
    assert_eq!((img.width, img.height), (1014, 1014));

    let scene: Value = serde_json::from_str(&std::fs::read_to_string(SCENE).unwrap()).unwrap();
    let cam = pinhole(&scene);
    let half_cone = (0.5f64).to_radians().cos();
    let white = Xyz::from_array(v3(&sim["white"]));
    let rendered = readings(&out.join("simulation/spots.csv"));
    let (n, t2) = (img.width as f64, cam.tan_half);
    for (k, r) in &rendered {
        let axis = unit(sub(patch_centre(&scene, *k), cam.position));
        let (mut acc, mut wsum) = ([0.0; 3], 0.0);
        for py in 0..img.height {
            for px in 0..img.width {
                let sx = (2.0 * (px as f64 + 0.5) / n - 1.0) * t2;
                let sy = (1.0 - 2.0 * (py as f64 + 0.5) / n) * t2;
                let d = unit(std::array::from_fn(|i| {
                    cam.forward[i] + sx * cam.right[i] + sy * cam.up[i]
                }));
                if dot(d, axis) < half_cone {
                    continue;
                }
                let w = dot(d, cam.forward).powi(3);
                let p = img.at(px, py);
                for i in 0..3 {
                    acc[i] += w * f64::from(p[i]);
                }
                wsum += w;
            }
        }
        assert!(wsum > 0.0, "patch {k}: no pixel in the spot");
        let mean = acc.map(|a| a / wsum);
        let de = delta_e76(
            Xyz::from_array(mean).to_lab(white),
            Xyz::from_array([r[0], r[1], r[2]]).to_lab(white),
        );
        assert!(
            de < 0.1,
            "patch {k}: image {mean:?} vs spot {r:?}: ΔE*ab {de}"
        );
    }
    // The reproduction reports each patch region's out-of-gamut pixels.
    let rep = json(&out.join("reproduction/reproduction.json"));
    let regions = rep["image_patches"].as_array().unwrap();
    assert_eq!(regions.len(), 24);
    for r in regions {
        let (px, oog) = (
            r["pixels"].as_u64().unwrap(),
            r["out_of_gamut_pixels"].as_u64(),
        );
        assert!(px > 1000 && oog.unwrap() <= px, "{r}");
    }
    let shown = json(&out.join("display-spots/display-spots.json"));
    assert_eq!(shown["shown"], "image");
    assert!(
        first < 60.0,
        "the default run took {first:.1} s; it should stay well under a minute"
    );

    let again = run(&out, &spots, &[]);
    let table = String::from_utf8_lossy(&again.stdout);
    for stage in [
        "simulation",
        "display",
        "reproduction",
        "display-spots",
        "validation",
    ] {
        assert!(
            table
                .lines()
                .any(|l| l.starts_with(stage) && l.contains("re-used")),
            "{stage} ran again:\n{table}"
        );
    }
}

/// Patch 7's aim, by hand: its centre projected through the scene's pinhole to fractions
/// of the image, x mirrored (1 − x) as the display is seen in a mirror; the reproduction,
/// the display-spots record and the operator's prompt all say that place.
#[test]
fn the_aim_is_the_patch_centre_mirrored() {
    let dir = fresh_dir("aim");
    let spots = box_spots(&dir);
    let out = dir.join("exp");
    run(&out, &spots, &["--image-size", "128"]);
    let scene: Value = serde_json::from_str(&std::fs::read_to_string(SCENE).unwrap()).unwrap();
    let cam = pinhole(&scene);
    let d = sub(patch_centre(&scene, 7), cam.position);
    let z = dot(d, cam.forward);
    let x = (dot(d, cam.right) / z / cam.tan_half + 1.0) / 2.0;
    let y = (1.0 - dot(d, cam.up) / z / cam.tan_half) / 2.0;
    let (mx, my) = (1.0 - x, y);

    let rep = json(&out.join("reproduction/reproduction.json"));
    let r7 = rep["image_patches"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["patch"] == 7)
        .unwrap();
    assert_eq!(
        (r7["row"].as_u64(), r7["column"].as_u64()),
        (Some(2), Some(1))
    );
    assert!(
        (r7["x"].as_f64().unwrap() - mx).abs() < 1e-9,
        "{r7} vs {mx}"
    );
    assert!(
        (r7["y"].as_f64().unwrap() - my).abs() < 1e-9,
        "{r7} vs {my}"
    );
    // The spot's radius: tan 0.5° over the image plane's height 2·tan(vfov/2).
    let radius = 0.5f64.to_radians().tan() / (2.0 * cam.tan_half);
    assert!((r7["radius"].as_f64().unwrap() - radius).abs() < 1e-12);

    let shown = json(&out.join("display-spots/display-spots.json"));
    let a7 = shown["aims"]
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["patch"] == 7)
        .unwrap();
    // The simulated screen shows the image whole: screen fractions are image fractions.
    assert!((a7["x"].as_f64().unwrap() - mx).abs() < 1e-9);
    let prompt = a7["prompt"].as_str().unwrap();
    let want = format!(
        "patch 7 (row 2, column 1) — at {:.1} % from the left, {:.1} % from the top",
        100.0 * mx,
        100.0 * my
    );
    assert!(prompt.contains(&want), "{prompt} vs {want}");
    // Unmirrored, the same patch lies on the other side of the screen.
    let plain = dir.join("plain");
    run(&plain, &spots, &["--image-size", "128", "--no-mirror"]);
    let rep = json(&plain.join("reproduction/reproduction.json"));
    let r7 = &rep["image_patches"].as_array().unwrap()[6];
    assert!((r7["x"].as_f64().unwrap() - x).abs() < 1e-9);
}

/// The display read on the whole image and on each patch's colour full-screen: the same
/// light within the meter's noise and the image's quantisation. The simulated CS-100A
/// draws ±0.2 % of the reading per reading; each side averages three, so the two means
/// differ by a standard deviation of 0.2 %·√(2/3) ≈ 0.16 %. The image's pixels under a
/// spot are the rendered radiance quantised to 8 bits pixel by pixel, the patch colour is
/// the spot reading quantised once: half a code of the darkest patch's channels is below
/// 1 % of its luminance. So every patch's Y agrees within 4 σ + 1 %.
#[test]
fn display_spots_on_the_image_agree_with_patch_colours() {
    let dir = fresh_dir("agree");
    let spots = box_spots(&dir);
    let on_image = dir.join("image");
    let on_colours = dir.join("colours");
    run(&on_image, &spots, &["--image-size", "256"]);
    let o = run(&on_colours, &spots, &["--image-size", "0"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no image was rendered"), "{err}");
    let rec = json(&on_colours.join("display-spots/display-spots.json"));
    assert_eq!(rec["shown"], "patch colours");
    assert!(rec["note"].as_str().unwrap().contains("no image"));
    assert!(!on_colours.join("simulation/image.exr").exists());

    let a = readings(&on_image.join("display-spots/spots.csv"));
    let b = readings(&on_colours.join("display-spots/spots.csv"));
    assert_eq!(a.len(), 24);
    let sigma = 0.002 * (2.0f64 / 3.0).sqrt();
    for ((k, ra), (_, rb)) in a.iter().zip(&b) {
        let rel = (ra[1] - rb[1]).abs() / rb[1];
        assert!(
            rel < 4.0 * sigma + 0.01,
            "patch {k}: Y {} on the image, {} as a colour ({:.2} %)",
            ra[1],
            rb[1],
            100.0 * rel
        );
    }
}
