//! The simulation stage: the measured scene's 24 spot readings rendered to a ΔE*ab target
//! (the deterministic radiosity solver where the scene qualifies, the path tracer where it
//! does not) and, optionally, the camera's image for the display.

use std::path::Path;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::error::ExperimentError;
use super::progress::Progress;
use super::readings::{write_readings, PatchStat};
use crate::output::OutputPolicy;
use crate::render::image::{render_image, ImageOptions};
use crate::render::image_io::write_xyz_image;
use crate::render::radiosity::{self, render_spots_radiosity, RadiosityOptions};
use crate::render::{render_spots_with_progress, Scene, SpotOptions, Strategy};

/// What the simulation stage renders.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SimulationOptions {
    /// Every patch's ΔE*ab uncertainty (radiosity: the extrapolation bound; path tracer:
    /// the 95 % half-width) is driven below this.
    pub target_de: f64,
    pub seed: u64,
    /// No refinement is started after this many seconds.
    pub max_seconds: f64,
    /// The camera image (square, this many pixels a side) and its samples per pixel; None
    /// renders the spots only.
    pub image: Option<ImageSpec>,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageSpec {
    pub size: usize,
    pub spp: u64,
}

/// One rendered spot reading.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SimSpot {
    pub patch: usize,
    #[serde(rename = "XYZ")]
    pub xyz: [f64; 3],
    /// The render's ΔE*ab uncertainty for this patch (see [`SimulationOptions::target_de`]).
    pub de_uncertainty: f64,
}

/// What `simulation/simulation.json` holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SimulationSummary {
    pub method: String,
    /// The scene's reference white (a perfect diffuser in place of patch 19), cd/m².
    pub white: [f64; 3],
    pub converged: bool,
    pub seconds: f64,
    pub spots: Vec<SimSpot>,
    /// `image.exr` when an image was rendered.
    pub image: Option<String>,
}

pub const SPOTS_FILE: &str = "spots.csv";
pub const SUMMARY_FILE: &str = "simulation.json";
pub const IMAGE_FILE: &str = "image.exr";

/// Renders `scene_file` into `dir`; returns the files written (relative to `dir`).
pub fn simulate(
    scene_file: &Path,
    opts: &SimulationOptions,
    dir: &Path,
    progress: &dyn Fn(Progress),
) -> Result<(SimulationSummary, Vec<&'static str>), ExperimentError> {
    let start = Instant::now();
    let scene = Scene::load(scene_file)?;
    let (method, white, converged, spots) = if radiosity::qualifies(&scene).is_ok() {
        let ropts = RadiosityOptions {
            target_de: opts.target_de,
            max_seconds: opts.max_seconds,
            ..RadiosityOptions::default()
        };
        let r = render_spots_radiosity(&scene, &ropts, &|l| {
            progress(Progress::Note(format!(
                "radiosity level {}: {} elements, {:.2} s",
                l.level, l.elements, l.seconds
            )))
        })?;
        let spots = r
            .patches
            .iter()
            .map(|p| SimSpot {
                patch: p.patch,
                xyz: p.xyz,
                de_uncertainty: p.de_bound,
            })
            .collect::<Vec<_>>();
        ("radiosity", r.white, r.converged, spots)
    } else {
        let sopts = SpotOptions {
            target_de: opts.target_de,
            max_seconds: opts.max_seconds,
            seed: opts.seed,
            ..SpotOptions::default()
        };
        let r = render_spots_with_progress(&scene, &sopts, &|p| {
            progress(Progress::Note(format!(
                "path tracing: worst 95 % half-width {:.3} ΔE*ab",
                p.worst_de
            )))
        })?;
        let spots = r
            .patches
            .iter()
            .map(|p| SimSpot {
                patch: p.patch,
                xyz: p.xyz,
                de_uncertainty: p.de_ci95,
            })
            .collect::<Vec<_>>();
        ("path tracer", r.white, r.converged, spots)
    };
    if let Some(bad) = spots.iter().find(|s| !s.xyz.iter().all(|v| v.is_finite())) {
        return Err(ExperimentError::NotFinite {
            what: format!("the rendered reading of patch {}", bad.patch),
        });
    }
    std::fs::create_dir_all(dir).map_err(|source| ExperimentError::Io {
        file: dir.to_path_buf(),
        source,
    })?;
    let stats: Vec<PatchStat> = spots
        .iter()
        .map(|s| PatchStat::of(s.patch, &[s.xyz]))
        .collect();
    write_readings(&dir.join(SPOTS_FILE), &stats)?;
    let mut files = vec![SPOTS_FILE, SUMMARY_FILE];
    let image = match opts.image {
        Some(spec) => {
            progress(Progress::Note(format!(
                "rendering the {0}×{0} image at {1} samples per pixel",
                spec.size, spec.spp
            )));
            let io = ImageOptions {
                width: spec.size,
                height: spec.size,
                spp: spec.spp,
                seed: opts.seed,
                strategy: Strategy::default(),
                window: None,
            };
            let img = render_image(&scene, &io, &|_| {})?;
            // The stage directory is the stage's own: a re-run replaces its files.
            write_xyz_image(&dir.join(IMAGE_FILE), &img, &OutputPolicy::new(true))?;
            files.push(IMAGE_FILE);
            Some(IMAGE_FILE.to_string())
        }
        None => None,
    };
    let summary = SimulationSummary {
        method: method.into(),
        white,
        converged,
        seconds: start.elapsed().as_secs_f64(),
        spots,
        image,
    };
    let text = serde_json::to_string_pretty(&summary).map_err(ExperimentError::Json)?;
    super::cache::write_atomic(&dir.join(SUMMARY_FILE), text.as_bytes())?;
    Ok((summary, files))
}
