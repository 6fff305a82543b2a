//! `metamer export --to mitsuba3` rendered by Mitsuba 3 (`scalar_spectral`, the PyPI
//! wheel) against metamer's own image of the same scene: the exported file must load as it
//! is, come out in metamer's orientation and in cd/m², and agree patch by patch within the
//! two renderers' noise. Mitsuba is an independent renderer (BSD-3), so this checks the
//! geometry, spectra, emitter units, camera and film of the export at once.
//!
//! Without Mitsuba (or the numpy its script reads the pixels with) the test prints
//! "skipped" with the reason and passes, unless `METAMER_ORACLES=required` (CI sets it after
//! installing the wheel), when it fails (`support::oracle`).

use std::path::Path;
use std::process::Command;

use metamer::export::{self, ExportRequest, Renderer};
use metamer::image::read_xyz_image;
use metamer::render::image::Frame;
use metamer::render::job::image::ImageRequest;
use metamer::render::method::Method;
use metamer::render::Scene;

use crate::support::oracle::{MITSUBA, MITSUBA_NUMPY};
use crate::support::{fresh_dir, scenes_dir};

const SIZE: usize = 80;
const SPP: u64 = 256;
/// Half-width of the square of pixels averaged per patch: at 80 px a patch is about 10 px
/// wide on the image (40 mm at about 1 m, seen 31° off its normal).
const HALF: i64 = 3;

/// Renders `xml` at SIZE × SIZE and returns its X, Y, Z pixels, row 0 at the top; None when
/// Mitsuba is not importable and not required.
fn mitsuba_render(xml: &Path, raw: &Path) -> Option<Vec<[f32; 3]>> {
    let script = r#"
import sys
import numpy as np
import mitsuba as mi
mi.set_variant("scalar_spectral")
scene = mi.load_file(sys.argv[1], spp=int(sys.argv[2]), width=int(sys.argv[3]), height=int(sys.argv[3]))
img = np.array(mi.render(scene, seed=7), dtype="<f4")
assert img.shape == (int(sys.argv[3]), int(sys.argv[3]), 3), img.shape
img.tofile(sys.argv[4])
"#;
    let python = MITSUBA_NUMPY.find()?;
    let out = Command::new(python)
        .args(["-c", script])
        .arg(xml)
        .arg(SPP.to_string())
        .arg(SIZE.to_string())
        .arg(raw)
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "Mitsuba 3 did not render the export: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(raw).unwrap();
    assert_eq!(bytes.len(), SIZE * SIZE * 12);
    let f: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    Some(f.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect())
}

/// Mean and standard error of the mean of each channel over the square around (cx, cy).
fn region(pixels: &[[f32; 3]], cx: f64, cy: f64) -> ([f64; 3], [f64; 3]) {
    let (x0, y0) = (cx.floor() as i64, cy.floor() as i64);
    let mut v: Vec<[f64; 3]> = Vec::new();
    for y in y0 - HALF..=y0 + HALF {
        for x in x0 - HALF..=x0 + HALF {
            let p = pixels[y as usize * SIZE + x as usize];
            v.push([p[0] as f64, p[1] as f64, p[2] as f64]);
        }
    }
    let n = v.len() as f64;
    let mut mean = [0.0; 3];
    let mut se = [0.0; 3];
    for k in 0..3 {
        mean[k] = v.iter().map(|p| p[k]).sum::<f64>() / n;
        let var = v.iter().map(|p| (p[k] - mean[k]).powi(2)).sum::<f64>() / (n - 1.0);
        se[k] = (var / n).sqrt();
    }
    (mean, se)
}

fn lab(xyz: [f64; 3], white: [f64; 3]) -> [f64; 3] {
    let f = |t: f64| {
        if t > (6.0f64 / 29.0).powi(3) {
            t.cbrt()
        } else {
            t / (3.0 * (6.0f64 / 29.0).powi(2)) + 4.0 / 29.0
        }
    };
    let (fx, fy, fz) = (
        f(xyz[0] / white[0]),
        f(xyz[1] / white[1]),
        f(xyz[2] / white[2]),
    );
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

#[test]
fn mitsuba_renders_the_exported_lambertian_box_as_metamer_does() {
    let dir = fresh_dir("export-mitsuba");
    let scene_file = scenes_dir().join("validation-box-led-rgb1.json");
    let out = dir.join("mitsuba");
    let report = export::run(&ExportRequest::new(
        Some(scene_file.clone()),
        Renderer::Mitsuba3,
        out.clone(),
    ))
    .unwrap();
    assert!(report.approximation.is_exact());
    let Some(theirs) = mitsuba_render(&out.join("scene.xml"), &dir.join("mitsuba.raw")) else {
        return;
    };

    let mut request = ImageRequest::new(SPP, dir.join("metamer.pfm"));
    request.scene = Some(scene_file.clone());
    request.method = Method::PathTracer;
    request.width = Some(SIZE);
    request.height = Some(SIZE);
    metamer::render::job::image::run(&request, &|_| {}).unwrap();
    let ours = read_xyz_image(&dir.join("metamer.pfm")).unwrap();
    assert_eq!((ours.width, ours.height), (SIZE, SIZE));

    let scene = Scene::load(&scene_file).unwrap();
    let camera = scene.camera.unwrap();
    let frame = Frame::of(&camera, SIZE, SIZE);
    let at = |k: usize| {
        let s = &scene.surfaces[scene.patch_surface(k).unwrap()];
        frame.project(s.rect.centre() - camera.position).unwrap()
    };
    let (cx, cy) = at(19);
    let white = region(&ours.pixels, cx, cy).0;
    let (mut worst, mut sum) = (0.0f64, 0.0);
    for k in 1..=24 {
        let (cx, cy) = at(k);
        let (a, sa) = region(&ours.pixels, cx, cy);
        let (b, sb) = region(&theirs, cx, cy);
        for c in 0..3 {
            // Five standard errors of the difference (the region's spread counts its small
            // real gradient as noise too), and 0.3 % for the two integrations of the same
            // 1 nm tables (a sum of bins against the integral of their interpolant). A
            // mirrored image, wrong units or a wrong spectrum is off by far more.
            let allowed = 5.0 * (sa[c].powi(2) + sb[c].powi(2)).sqrt() + 0.003 * a[c];
            assert!(
                (a[c] - b[c]).abs() <= allowed,
                "patch {k} channel {c}: metamer {} Mitsuba {} (allowed ±{allowed})",
                a[c],
                b[c]
            );
        }
        let (la, lb) = (lab(a, white), lab(b, white));
        let de = (0..3).map(|i| (la[i] - lb[i]).powi(2)).sum::<f64>().sqrt();
        worst = worst.max(de);
        sum += de;
    }
    eprintln!(
        "Mitsuba vs metamer image, {SIZE}² at {SPP} spp, {}-pixel regions: ΔE*ab max {worst:.3}, \
         mean {:.3}",
        (2 * HALF + 1).pow(2),
        sum / 24.0
    );
}

#[test]
fn mitsuba_loads_the_export_of_a_cos_power_box() {
    let dir = fresh_dir("export-mitsuba-ldc");
    let out = dir.join("mitsuba");
    let mut request = ExportRequest::new(
        Some(scenes_dir().join("validation-box-ldc.json")),
        Renderer::Mitsuba3,
        out.clone(),
    );
    request.measure_difference = false;
    let report = export::run(&request).unwrap();
    assert!(!report.approximation.is_exact());
    let readme = std::fs::read_to_string(out.join("README.md")).unwrap();
    assert!(readme.contains("Lambertian tiles"), "{readme}");
    // A 8 × 8 image at 1 spp: only that the file loads and renders.
    let script = r#"
import sys
import mitsuba as mi
mi.set_variant("scalar_spectral")
scene = mi.load_file(sys.argv[1], spp=1, width=8, height=8)
mi.render(scene)
"#;
    let Some(python) = MITSUBA.find() else {
        return;
    };
    let o = Command::new(python)
        .args(["-c", script])
        .arg(out.join("scene.xml"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
