//! `metamer experiment --simulation-image`: the simulation stage taken from another
//! renderer's image (here metamer's own radiosity image, standing in for it) read back as
//! the meter's readings; the stage names the image and its digest, the report names it as
//! the simulation's source, an unchanged image re-uses the stage and a changed one re-runs
//! it, and the flags only a rendering stage uses are refused.

use std::path::Path;
use std::process::Output;

use serde_json::Value;

use crate::experiment::{box_spots, SCENE};
use crate::support::{fresh_dir, metamer, stderr, text};

/// A radiosity image of the box's camera at `level` (another level, another image).
fn image(path: &Path, level: &str) {
    let o = metamer(&[
        "render",
        "image",
        SCENE,
        "--method",
        "radiosity",
        "--level",
        level,
        "--spp",
        "1",
        "--width",
        "160",
        "--height",
        "160",
        "--force",
        "-o",
        path.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

fn experiment(out: &Path, spots: &Path, image: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "experiment",
        "-o",
        out.to_str().unwrap(),
        "--box-scene",
        SCENE,
        "--box-spots",
        spots.to_str().unwrap(),
        "--simulation-image",
        image.to_str().unwrap(),
        // Only the reference white is traced, to a third of this.
        "--target-de",
        "0.5",
        "--repeats",
        "1",
    ];
    args.extend_from_slice(extra);
    metamer(&args)
}

fn how(o: &Output, stage: &str) -> String {
    text(&o.stdout)
        .lines()
        .find(|l| l.split_whitespace().next() == Some(stage))
        .and_then(|l| l.split_whitespace().nth(1))
        .unwrap_or_default()
        .to_string()
}

#[test]
fn an_external_image_is_the_simulation_read_back_named_and_reused_by_its_digest() {
    let dir = fresh_dir("external");
    let spots = box_spots(&dir);
    let img = dir.join("renderer.exr");
    image(&img, "2");
    let out = dir.join("exp");

    let first = experiment(&out, &spots, &img, &[]);
    assert!(first.status.success(), "{}", stderr(&first));
    assert_eq!(how(&first, "simulation"), "ran");
    let sim: Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("simulation/simulation.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(sim["method"], "external image");
    assert_eq!(sim["source"]["renderer"], "external renderer");
    assert_eq!(sim["source"]["image"], img.to_str().unwrap());
    let digest = metamer::digest::sha256_file(&img).unwrap();
    assert_eq!(sim["source"]["sha256"], digest.as_str());
    // The stage shows the image it read: the same pixels.
    assert_eq!(
        metamer::image::read_xyz_image(&out.join("simulation/image.exr")).unwrap(),
        metamer::image::read_xyz_image(&img).unwrap()
    );
    assert_eq!(sim["image_patches"].as_array().unwrap().len(), 24);
    // A noise-free image of the same scene: simulation and box agree far below the JND
    // (the read-back's mean over the cone against radiosity's; the level-2 image's mesh).
    let v: Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("validation/comparisons.json")).unwrap(),
    )
    .unwrap();
    let max = v["simulation_vs_box"]["max_de76"]["value"]
        .as_f64()
        .unwrap();
    assert!(max < 0.5, "{max}");
    let report = std::fs::read_to_string(out.join("validation/report.html")).unwrap();
    assert!(
        report.contains(&format!("external renderer: the image {}", img.display())),
        "the report does not name the image"
    );

    let again = experiment(&out, &spots, &img, &[]);
    assert!(again.status.success(), "{}", stderr(&again));
    assert_eq!(how(&again, "simulation"), "re-used");
    // Another image under the same name: its bytes differ, so the stage runs again.
    image(&img, "1");
    let changed = experiment(&out, &spots, &img, &[]);
    assert!(changed.status.success(), "{}", stderr(&changed));
    assert_eq!(how(&changed, "simulation"), "ran");

    for flag in ["--image-size", "--image-spp"] {
        let o = experiment(&dir.join("refused"), &spots, &img, &[flag, "64"]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("'--simulation-image <IMAGE>' cannot be used with"),
            "{}",
            stderr(&o)
        );
    }
    assert!(!dir.join("refused").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
