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
use crate::render::job::spots_from_image::{self, Request};

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
    let request = Request {
        target_de: opts.target_de,
        max_seconds: opts.max_seconds,
        seed: opts.seed,
        ..Request::new(image.to_path_buf(), Some(scene_file.to_path_buf()))
    };
    let report = spots_from_image::run(&request, &|_| {}).map_err(from_render)?;
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
    };
    let text = serde_json::to_string_pretty(&summary).map_err(ExperimentError::Json)?;
    super::cache::write_atomic(&dir.join(SUMMARY_FILE), text.as_bytes())?;
    Ok((summary, vec![SPOTS_FILE, SUMMARY_FILE, IMAGE_FILE]))
}
