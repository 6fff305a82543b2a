//! The simulation stage from another renderer: its XYZ image of the measured scene's
//! camera read back as the 24 meter readings (`render spots-from-image`, the same cones and
//! uncertainty) instead of rendered. The stage writes what a rendering stage writes —
//! `spots.csv` with each reading's uncertainty, `image.exr` (the image as read, for the
//! reproduction stage to show) and `simulation.json` — and `simulation.json` names the
//! image, its SHA-256 and "external renderer" as the readings' source. The image's digest
//! is among the stage's inputs (see `run`), so a changed image re-runs the stage and an
//! unchanged one is re-used.

use std::path::Path;
use std::time::Instant;

use super::error::ExperimentError;
use super::progress::Progress;
use super::readings::write_readings;
use super::simulation::{
    as_readings, from_render, patches_in_image, ExternalSource, SimulationMethod,
    SimulationOptions, SimulationSummary, IMAGE_FILE, SPOTS_FILE, SUMMARY_FILE,
};
use crate::image::write_xyz_image;
use crate::output::OutputPolicy;
use crate::render::job::spots_from_image::{self, SpotsFromImageRequest};

/// What the summary and report call the source.
pub const RENDERER: &str = "external renderer";

/// Reads `image` back against `scene_file` into `dir`; returns the files written.
pub fn read_back(
    scene_file: &Path,
    image: &Path,
    opts: &SimulationOptions,
    dir: &Path,
    progress: &dyn Fn(Progress),
) -> Result<(SimulationSummary, Vec<&'static str>), ExperimentError> {
    let start = Instant::now();
    progress(Progress::Note(format!(
        "reading the 24 meter cones from {} (an external renderer's image)",
        image.display()
    )));
    let request = SpotsFromImageRequest {
        target_de: opts.target_de,
        max_seconds: opts.max_seconds,
        seed: opts.seed,
        ..SpotsFromImageRequest::new(image.to_path_buf(), Some(scene_file.to_path_buf()))
    };
    let report = spots_from_image::run(&request, &|_| {}).map_err(from_render)?;
    // The read-back's warnings (a reference white cut short) are the operator's to see: the
    // readings' XYZ stand, their printed CIELAB does not.
    for w in &report.warnings {
        progress(Progress::Note(format!("warning: {w}")));
    }
    std::fs::create_dir_all(dir).map_err(|source| ExperimentError::Io {
        file: dir.to_path_buf(),
        source,
    })?;
    write_readings(&dir.join(SPOTS_FILE), &as_readings(&report.patches))?;
    // The reproduction shows the stage's own image.exr: the image as read, re-encoded.
    let img = &report.pixels;
    let image_patches = patches_in_image(&report.scene, img, &report.patches, report.white)?;
    write_xyz_image(&dir.join(IMAGE_FILE), img, &OutputPolicy::new(true))?;
    let summary = SimulationSummary {
        method: SimulationMethod::ExternalImage,
        white: report.white,
        converged: true,
        seconds: start.elapsed().as_secs_f64(),
        spots: report.patches.clone(),
        image: Some(IMAGE_FILE.to_string()),
        image_method: Some(RENDERER.to_string()),
        image_patches,
        source: Some(ExternalSource {
            image: image.to_path_buf(),
            sha256: report.sha256.clone(),
            renderer: RENDERER.to_string(),
        }),
        warnings: report.warnings.clone(),
    };
    let text = serde_json::to_string_pretty(&summary).map_err(ExperimentError::Json)?;
    super::cache::write_atomic(&dir.join(SUMMARY_FILE), text.as_bytes())?;
    Ok((summary, vec![SPOTS_FILE, SUMMARY_FILE, IMAGE_FILE]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::job::image::{run as render_image, ImageRequest};
    use crate::render::method::Method;
    use std::cell::RefCell;

    /// A reference white that stops at its time limit short of its target is stated: a
    /// warning line for the operator and the same words in `simulation.json`, which reads
    /// back with them. Its target here (a third of 0.0003 ΔE*ab) would take hours.
    #[test]
    fn a_white_cut_short_is_printed_and_kept_in_the_summary() {
        let dir = std::env::temp_dir().join(format!("metamer-ext-white-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let image = dir.join("box.exr");
        // The built-in box, by the name a scene argument may give.
        let scene = std::path::PathBuf::from("validation-box");
        render_image(
            &ImageRequest {
                method: Method::Radiosity,
                level: 1,
                width: Some(128),
                height: Some(128),
                ..ImageRequest::new(1, image.clone())
            },
            &|_| {},
        )
        .unwrap();
        let opts = SimulationOptions {
            max_seconds: 1.0,
            ..SimulationOptions::new(0.0003, 1, 0, 0, Some(image.clone()))
        };
        let notes = RefCell::new(Vec::new());
        let (summary, _) = read_back(&scene, &image, &opts, &dir.join("stage"), &|p| {
            if let Progress::Note(n) = p {
                notes.borrow_mut().push(n)
            }
        })
        .unwrap();
        assert_eq!(summary.warnings.len(), 1, "{:?}", summary.warnings);
        let w = &summary.warnings[0];
        assert!(
            w.starts_with("the reference white stopped at the time limit (1 s)"),
            "{w}"
        );
        assert!(!w.contains("  "), "{w}");
        assert!(
            notes.borrow().contains(&format!("warning: {w}")),
            "{:?}",
            notes.borrow()
        );
        let text = std::fs::read_to_string(dir.join("stage").join(SUMMARY_FILE)).unwrap();
        let back: SimulationSummary = serde_json::from_str(&text).unwrap();
        assert_eq!(back.warnings, summary.warnings);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
