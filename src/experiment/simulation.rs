//! The simulation stage: the measured scene's 24 spot readings rendered to a ΔE*ab target
//! (the deterministic radiosity solver where the scene qualifies, the path tracer where it
//! does not) and the camera's image for the display: from the same radiosity solution
//! when the spots came from one (a few seconds at the paper's 1014²), else by the path
//! tracer. Each patch's spot footprint in the image is read back and compared with its
//! spot reading, and its place in the image recorded for aiming the meter at the display.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::error::ExperimentError;
use super::progress::Progress;
use super::readings::{write_readings, PatchReading};
use crate::color::{delta_e76, Xyz};
use crate::image::{write_xyz_image, XyzImage};
use crate::output::OutputPolicy;
use crate::render::image::{spot_mean, Frame};
use crate::render::job::image::{self, Film, RadiosityLight};
use crate::render::job::spots::{self, Readings, SpotsReport, SpotsRequest};
use crate::render::job::{RenderError, RenderEvent};
use crate::render::method::Method;
use crate::render::spot::{patch_aim, RenderedReading, Uncertainty};
use crate::render::Scene;
use crate::validation::propagate::render_lab_sigma;

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
    /// Another renderer's XYZ image of the scene's camera: the stage reads its 24 meter
    /// readings back (`render spots-from-image`) and shows it, instead of rendering; `image`
    /// is then unused and `target_de` sets only the reference white's accuracy. Left out of
    /// the options' record when None, so earlier runs' stages stay re-usable.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub external_image: Option<PathBuf>,
}

/// The simulation's time limit in the experiment (s): no refinement starts after it.
pub const MAX_RENDER_SECONDS: f64 = 600.0;

impl SimulationOptions {
    /// The stage's options as `metamer experiment` and the lab ask for them: no refinement
    /// after [`MAX_RENDER_SECONDS`], and a camera image of `image_size` pixels a side at
    /// `image_spp` samples per pixel, none when `image_size` is 0.
    pub fn new(
        target_de: f64,
        seed: u64,
        image_size: usize,
        image_spp: u64,
        external_image: Option<PathBuf>,
    ) -> SimulationOptions {
        SimulationOptions {
            target_de,
            seed,
            max_seconds: MAX_RENDER_SECONDS,
            image: (image_size > 0).then_some(ImageSpec {
                size: image_size,
                spp: image_spp,
            }),
            external_image,
        }
    }
}

/// The simulation stage's checks before the experiment's first reading: another renderer's
/// image (`external_image`) must be an image metamer reads, of the aspect ratio of the
/// scene's camera (`camera`: width and height in pixels) and outside the stage's
/// directory `stage_dir`, where the stage writes its own copy over it. A scene without a
/// camera (None) is refused by the read-back itself.
pub(super) fn preflight(
    opts: &SimulationOptions,
    camera: Option<[usize; 2]>,
    stage_dir: &Path,
) -> Result<(), ExperimentError> {
    let Some(file) = &opts.external_image else {
        return Ok(());
    };
    if let (Ok(dir), Ok(f)) = (
        std::fs::canonicalize(stage_dir),
        std::fs::canonicalize(file),
    ) {
        if f.starts_with(dir) {
            return Err(ExperimentError::ImageInStage {
                file: file.clone(),
                dir: stage_dir.to_path_buf(),
            });
        }
    }
    let image = crate::image::read_xyz_image(file)?;
    let Some([camera_width, camera_height]) = camera else {
        return Ok(());
    };
    if image.width * camera_height != image.height * camera_width {
        return Err(crate::render::spot::cone::ReadBackError::Aspect {
            file: file.clone(),
            width: image.width,
            height: image.height,
            camera_width,
            camera_height,
        }
        .into());
    }
    Ok(())
}

/// Where the simulation's readings came from, as `simulation.json` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SimulationMethod {
    /// The deterministic radiosity solver: each reading's uncertainty is a bound.
    #[serde(rename = "radiosity")]
    Radiosity,
    /// The spectral path tracer: a 95 % half-width.
    #[serde(rename = "path tracer")]
    PathTracer,
    /// Another renderer's image read back (`--simulation-image`): a 95 % half-width from
    /// the pixels' spread.
    #[serde(rename = "external image")]
    ExternalImage,
}

impl SimulationMethod {
    /// The name `simulation.json` and the report give it.
    pub fn name(self) -> &'static str {
        match self {
            SimulationMethod::Radiosity => "radiosity",
            SimulationMethod::PathTracer => "path tracer",
            SimulationMethod::ExternalImage => crate::render::job::spots_from_image::METHOD,
        }
    }
}

impl std::fmt::Display for SimulationMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageSpec {
    pub size: usize,
    /// Samples per pixel of the path tracer (the radiosity image takes one ray per pixel:
    /// it has no noise to average).
    pub spp: u64,
}

/// Where a patch lies in the image and what the image shows there.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImagePatch {
    pub patch: usize,
    /// The meter's aim (the patch's centre) as fractions of the image's width and height
    /// from its top-left corner, as rendered (not mirrored).
    pub x: f64,
    pub y: f64,
    /// The radius of the meter's spot as a fraction of the image's height.
    pub radius: f64,
    /// Pixels inside the spot.
    pub pixels: usize,
    /// The image's mean over the spot (solid-angle weighted), cd/m².
    #[serde(rename = "XYZ")]
    pub xyz: Xyz,
    /// ΔE*ab of that mean against the patch's spot reading (the scene's reference white).
    pub de_vs_spot: f64,
}

/// What `simulation/simulation.json` holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(into = "SummaryFile", from = "SummaryFile")]
pub struct SimulationSummary {
    pub method: SimulationMethod,
    /// The scene's reference white (a perfect diffuser in place of patch 19), cd/m².
    pub white: Xyz,
    pub converged: bool,
    pub seconds: f64,
    /// The rendered readings. The file keeps each one's patch, XYZ and ΔE*ab
    /// (`de_uncertainty`, see [`SimulationOptions::target_de`]); read back, its CIELAB is
    /// computed against `white` as the renderers compute it, and its kind of uncertainty
    /// follows `method` (a bound for `radiosity`, else a 95 % half-width) without the
    /// sampling or regularity, which the file does not record.
    pub spots: Vec<RenderedReading>,
    /// `image.exr` when an image was rendered.
    pub image: Option<String>,
    /// How the image was rendered (`radiosity`, `path tracer`).
    pub image_method: Option<String>,
    /// The patches' spots in the image, when an image was rendered.
    pub image_patches: Vec<ImagePatch>,
    /// Where the readings came from when metamer did not render them.
    pub source: Option<ExternalSource>,
}

/// An external renderer's image the simulation's readings were read back from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExternalSource {
    /// The image as given.
    pub image: PathBuf,
    /// SHA-256 of its bytes when read.
    pub sha256: String,
    /// "external renderer".
    pub renderer: String,
}

/// `simulation.json` as written: field names, order and the old type names in serde's
/// messages are the file's, so files of earlier runs read and new ones are the same bytes.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(rename = "SimulationSummary")]
struct SummaryFile {
    method: SimulationMethod,
    white: Xyz,
    converged: bool,
    seconds: f64,
    spots: Vec<SpotFile>,
    image: Option<String>,
    #[serde(default)]
    image_method: Option<String>,
    #[serde(default)]
    image_patches: Vec<ImagePatch>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    source: Option<ExternalSource>,
}

/// One reading as `simulation.json` keeps it.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(rename = "SimSpot")]
struct SpotFile {
    patch: usize,
    #[serde(rename = "XYZ")]
    xyz: Xyz,
    de_uncertainty: f64,
}

impl From<SimulationSummary> for SummaryFile {
    fn from(s: SimulationSummary) -> Self {
        let spots = s.spots.iter().map(|r| SpotFile {
            patch: r.patch,
            xyz: r.xyz,
            de_uncertainty: r.uncertainty.de_ab(),
        });
        SummaryFile {
            method: s.method,
            white: s.white,
            converged: s.converged,
            seconds: s.seconds,
            spots: spots.collect(),
            image: s.image,
            image_method: s.image_method,
            image_patches: s.image_patches,
            source: s.source,
        }
    }
}

impl From<SummaryFile> for SimulationSummary {
    fn from(f: SummaryFile) -> Self {
        let uncertainty = |de| match f.method {
            SimulationMethod::Radiosity => Uncertainty::Bound { de, regular: None },
            SimulationMethod::PathTracer | SimulationMethod::ExternalImage => {
                Uncertainty::HalfWidth95 { de, sampling: None }
            }
        };
        let spots = f
            .spots
            .iter()
            .map(|s| RenderedReading::new(s.patch, s.xyz, f.white, uncertainty(s.de_uncertainty)))
            .collect();
        SimulationSummary {
            method: f.method,
            white: f.white,
            converged: f.converged,
            seconds: f.seconds,
            spots,
            image: f.image,
            image_method: f.image_method,
            image_patches: f.image_patches,
            source: f.source,
        }
    }
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
    // The same entry as `metamer render spots`, with the stage's options; `auto` picks the
    // solver, and its reason is not a stage note.
    let request = SpotsRequest {
        scene: Some(scene_file.to_path_buf()),
        method: Method::Auto,
        target_de: opts.target_de,
        white: None,
        max_seconds: opts.max_seconds,
        seed: opts.seed,
    };
    let report = spots::run(&request, &|e| match e {
        RenderEvent::Level(l) => progress(Progress::Note(format!(
            "radiosity level {}: {} elements, {:.2} s",
            l.level, l.elements, l.seconds
        ))),
        RenderEvent::Spots(p) => progress(Progress::Note(format!(
            "path tracing: worst 95 % half-width {:.3} ΔE*ab",
            p.worst_de
        ))),
        _ => {}
    })
    .map_err(from_render)?;
    let scene = &report.scene;
    let method = match report.readings {
        Readings::Radiosity { .. } => SimulationMethod::Radiosity,
        Readings::PathTracer(_) => SimulationMethod::PathTracer,
    };
    let (white, converged) = (report.readings.white(), report.readings.converged());
    let spots = report.readings.patches().to_vec();
    if let Some(bad) = spots.iter().find(|s| !s.xyz.iter().all(|v| v.is_finite())) {
        return Err(ExperimentError::NotFinite {
            what: format!("the rendered reading of patch {}", bad.patch),
        });
    }
    if let Some(bad) = spots.iter().find(|s| {
        let de = s.uncertainty.de_ab();
        !(de.is_finite() && de >= 0.0)
    }) {
        return Err(ExperimentError::NotFinite {
            what: format!("the render's uncertainty of patch {}", bad.patch),
        });
    }
    std::fs::create_dir_all(dir).map_err(|source| ExperimentError::Io {
        file: dir.to_path_buf(),
        source,
    })?;
    write_readings(&dir.join(SPOTS_FILE), &as_readings(&spots))?;
    let mut files = vec![SPOTS_FILE, SUMMARY_FILE];
    let mut image_patches = Vec::new();
    let image = match opts.image {
        Some(spec) => {
            progress(Progress::Note(match method {
                SimulationMethod::Radiosity => format!(
                    "rendering the {0}×{0} image from the radiosity solution",
                    spec.size
                ),
                _ => format!(
                    "rendering the {0}×{0} image at {1} samples per pixel",
                    spec.size, spec.spp
                ),
            }));
            let img = render_image(&report, spec, opts.seed)?;
            image_patches = patches_in_image(scene, &img, &spots, white)?;
            // The stage directory is the stage's own: a re-run replaces its files.
            write_xyz_image(&dir.join(IMAGE_FILE), &img, &OutputPolicy::new(true))?;
            files.push(IMAGE_FILE);
            Some(IMAGE_FILE.to_string())
        }
        None => {
            // An image of an earlier run with other options is not this run's.
            remove_stale(&dir.join(IMAGE_FILE))?;
            None
        }
    };
    let summary = SimulationSummary {
        method,
        white,
        converged,
        seconds: start.elapsed().as_secs_f64(),
        spots,
        image_method: image.as_ref().map(|_| method.name().to_string()),
        image,
        image_patches,
        source: None,
    };
    let text = serde_json::to_string_pretty(&summary).map_err(ExperimentError::Json)?;
    super::cache::write_atomic(&dir.join(SUMMARY_FILE), text.as_bytes())?;
    Ok((summary, files))
}

/// The camera's image: from the radiosity solution the readings came from, one ray per
/// pixel (it has no noise to average), or by the path tracer at the spec's samples per
/// pixel. Unlike `metamer render image`, which solves afresh at ⌊√spp⌋² rays per pixel.
fn render_image(
    report: &SpotsReport,
    spec: ImageSpec,
    seed: u64,
) -> Result<XyzImage, ExperimentError> {
    let light = match &report.readings {
        Readings::Radiosity {
            solution, options, ..
        } => RadiosityLight::Solved {
            levels: solution,
            options,
        },
        // Not used by the path tracer.
        Readings::PathTracer(_) => RadiosityLight::Solve { level: 3 },
    };
    let film = Film {
        width: spec.size,
        height: spec.size,
        spp: spec.spp,
        seed,
        light,
        subpixels: 1,
    };
    image::render(&report.scene, report.resolved.method, &film, &|_| {}).map_err(from_render)
}

/// The stage's error for a render job's: the same error the stage reported when it called
/// The stage's readings of rendered patches. The render's own uncertainty goes with its
/// readings, so `metamer validate` given the file counts it as the experiment's validation
/// does.
pub(super) fn as_readings(spots: &[RenderedReading]) -> Vec<(usize, PatchReading)> {
    spots
        .iter()
        .map(|s| {
            let u_lab = render_lab_sigma(s.uncertainty);
            (s.patch, PatchReading::rendered(s.xyz, u_lab))
        })
        .collect()
}

/// the renderers itself.
pub(super) fn from_render(e: RenderError) -> ExperimentError {
    match e {
        RenderError::Scene(e) => e.into(),
        RenderError::Spot(e) => e.into(),
        RenderError::Radiosity(e) => e.into(),
        RenderError::Image(e) => e.into(),
        RenderError::ImageIo(e) => e.into(),
        other => ExperimentError::Option {
            what: "simulation",
            message: other.to_string(),
        },
    }
}

/// Each patch's spot in `img`: where the meter aims, and the image's mean there against the
/// spot reading.
pub(super) fn patches_in_image(
    scene: &Scene,
    img: &XyzImage,
    spots: &[RenderedReading],
    white: Xyz,
) -> Result<Vec<ImagePatch>, ExperimentError> {
    let cam = scene
        .camera
        .ok_or(crate::render::spot::SpotError::NoCamera)?;
    let frame = Frame::of(&cam, img.width, img.height);
    let w = white;
    let mut out = Vec::with_capacity(spots.len());
    for s in spots {
        let aim = patch_aim(scene, s.patch)?;
        let (cx, cy) = frame
            .project(aim.axis)
            .ok_or_else(|| ExperimentError::BadFile {
                file: std::path::PathBuf::from(IMAGE_FILE),
                message: format!("patch {} is behind the camera", s.patch),
            })?;
        let (xyz, pixels) =
            spot_mean(img, &frame, &aim).ok_or_else(|| ExperimentError::Option {
                what: "image size",
                message: format!(
                    "a {}×{} image has no pixel inside patch {}'s 1° spot; render a larger one",
                    img.width, img.height, s.patch
                ),
            })?;
        let de = delta_e76(Xyz::from(xyz).to_lab(w), s.xyz.to_lab(w));
        out.push(ImagePatch {
            patch: s.patch,
            x: cx / img.width as f64,
            y: cy / img.height as f64,
            radius: (aim.acceptance_deg.to_radians() / 2.0).tan() / (2.0 * frame.half_h),
            pixels,
            xyz: xyz.into(),
            de_vs_spot: de,
        });
    }
    Ok(out)
}

fn remove_stale(path: &Path) -> Result<(), ExperimentError> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(ExperimentError::Io {
            file: path.to_path_buf(),
            source: e,
        }),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The start of a `simulation.json` written by an earlier version (a lab run's, cut to
    /// two spots and one image patch).
    const EARLIER: &str = r#"{
  "method": "radiosity",
  "white": [
    14.752569875088737,
    15.4187196485702,
    15.810067120402415
  ],
  "converged": true,
  "seconds": 32.753173086,
  "spots": [
    {
      "patch": 1,
      "XYZ": [
        1.5783418452126645,
        1.4400834689409334,
        0.882098113629156
      ],
      "de_uncertainty": 0.0028757631715769874
    },
    {
      "patch": 2,
      "XYZ": [
        5.532494095587725,
        5.100170977107341,
        3.3444075847054937
      ],
      "de_uncertainty": 0.010348447574333602
    }
  ],
  "image": "image.exr",
  "image_method": "radiosity",
  "image_patches": [
    {
      "patch": 1,
      "x": 0.2912743551336303,
      "y": 0.0903687556485967,
      "radius": 0.0316280169639935,
      "pixels": 3308,
      "XYZ": [
        1.5782964125838364,
        1.4400410561349812,
        0.8820685059457193
      ],
      "de_vs_spot": 0.000520376134755653
    }
  ]
}"#;

    #[test]
    fn an_earlier_summary_reads_as_readings_and_writes_back_the_same_bytes() {
        let s: SimulationSummary = serde_json::from_str(EARLIER).unwrap();
        assert_eq!(serde_json::to_string_pretty(&s).unwrap(), EARLIER);
        let r = &s.spots[1];
        assert_eq!((r.patch, r.xyz[1]), (2, 5.100170977107341));
        assert_eq!(
            r.uncertainty,
            Uncertainty::Bound {
                de: 0.010348447574333602,
                regular: None
            }
        );
        let lab = r.xyz.to_lab(s.white);
        assert_eq!(r.lab, lab.to_array());
        assert_eq!(s.image_patches.len(), 1);
    }

    #[test]
    fn a_path_traced_summary_without_the_image_fields_reads_as_half_widths() {
        let text = r#"{"method":"path tracer","white":[17.4,15.6,4.2],"converged":false,
            "seconds":21.1,"spots":[{"patch":7,"XYZ":[2.26,1.62,0.24],"de_uncertainty":0.5}],
            "image":null}"#;
        let s: SimulationSummary = serde_json::from_str(text).unwrap();
        assert_eq!(
            s.spots[0].uncertainty,
            Uncertainty::HalfWidth95 {
                de: 0.5,
                sampling: None
            }
        );
        assert_eq!((s.image_method, s.image_patches.len()), (None, 0));
        let e = serde_json::from_str::<SimulationSummary>(r#"{"method":"radiosity"}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing field `white`"), "{e}");
    }
}
