//! `metamer render spots-from-image`: the 24 meter readings taken from an image of the
//! scene's camera that another renderer made, instead of traced, so its renderer can be
//! validated as metamer's own are. Each patch's reading is the image's mean over the
//! meter's cone — the aim at the patch centre from the camera's optical centre and the
//! scene's acceptance angle, exactly as `render spots` aims — weighted by the solid angle
//! of each pixel's part inside it, with a 95 % half-width of ΔE*ab from the pixels' spread
//! (see [`crate::render::spot::cone`] for both and what the half-width assumes).
//!
//! The image is read as `render image` writes it: absolute XYZ in cd/m², rows from the
//! top, not mirrored, the camera's vertical field of view at whatever size; its aspect
//! ratio must be the camera's, since the horizontal field of view follows it.
//!
//! CIELAB needs a white the image does not show. The readings' Lab is against the scene's
//! reference white by `render spots`' rule (a perfect white diffuser in place of patch 19,
//! traced by the path tracer to a third of the target) or a white given. Only the XYZ and
//! its uncertainty go on to `validate`, which computes every CIELAB against one white for
//! all sides (the display's or the box's), so this white changes no comparison: it serves
//! the printed Lab and the check of the image's units.
//!
//! A white traced to the time limit before its target is still used, with a warning (a
//! [`RenderEvent::Warning`], and in the report's `warnings` and `white_trace` in the JSON):
//! the readings' XYZ and their standard errors do not depend on it, so refusing would
//! throw away a read-back for a figure the comparison does not use, but the printed CIELAB
//! and each reading's ΔE95 do, and an operator must not take them for the target's.
//!
//! Units: the image is read as [`crate::image`] interprets its header (an OpenEXR
//! `whiteLuminance` scales the values to cd/m², an RGB file without chromaticities is
//! BT.709, a crop of the camera's frame is refused). An image in another unit than cd/m²
//! (W/(sr·m²) is 683 times smaller) cannot be told in general from a renderer that is
//! wrong. What is checked: no cone may be all zero, and patch 19, the chart's white, must
//! read between a tenth and ten times the white diffuser. A smaller factor is left to the
//! validation to find.
//!
//! ```
//! use metamer::render::job::spots_from_image::{run, SpotsFromImageRequest};
//! # let dir = std::env::temp_dir().join(format!("metamer-doc-sfi-{}", std::process::id()));
//! # std::fs::create_dir_all(&dir)?;
//! # let image = dir.join("box.exr");
//! # metamer::render::job::image::run(&metamer::render::job::image::ImageRequest {
//! #     method: metamer::render::method::Method::Radiosity,
//! #     level: 2,
//! #     width: Some(128),
//! #     height: Some(128),
//! #     ..metamer::render::job::image::ImageRequest::new(1, image.clone())
//! # }, &|_| {})?;
//! // An image of the scene's camera by any renderer, as absolute XYZ.
//! let request = SpotsFromImageRequest {
//!     target_de: 0.5,
//!     ..SpotsFromImageRequest::new(image, None) // None: the built-in validation box
//! };
//! let report = run(&request, &|_| {})?;
//! for r in &report.patches {
//!     println!("patch {}: Y {:.3} ± {:.3} ΔE*ab", r.patch, r.xyz[1], r.uncertainty.de_ab());
//! }
//! assert_eq!(report.patches.len(), 24);
//! println!("{}", report.to_json()?);
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::{check_white_request, load_scene, RenderError, RenderEvent};
use crate::color::Xyz;
use crate::image::{read_xyz_image, XyzImage};
use crate::render::image::Frame;
use crate::render::scene::Scene;
use crate::render::spot::cone::{cone_mean, cone_pixels, ConeMean};
pub use crate::render::spot::cone::{ReadBackError, MIN_EFFECTIVE_PIXELS};
use crate::render::spot::{
    de_ci95_of, patch_aim, reference_white_traced, RenderedReading, Sampling, SpotOptions,
    TracedWhite, Uncertainty,
};

/// What the readings' JSON names as their method: `validate` shows it as the
/// instrument, "renderer (external image)".
pub const METHOD: &str = "external image";

/// What to read back.
#[derive(Clone, Debug)]
pub struct SpotsFromImageRequest {
    /// The image, `.exr` or `.pfm`.
    pub image: PathBuf,
    /// The scene the image is of; None is the built-in validation box.
    pub scene: Option<PathBuf>,
    /// Reference white X,Y,Z (None: the scene's, by `render spots`' rule).
    pub white: Option<Xyz>,
    /// The scene's white is traced to a third of this ΔE*ab, as `render spots` does.
    pub target_de: f64,
    /// Wall-clock limit (s) of tracing the white.
    pub max_seconds: f64,
    /// The path tracer's seed for the white.
    pub seed: u64,
}

impl SpotsFromImageRequest {
    /// `render spots`' defaults for the white.
    pub fn new(image: PathBuf, scene: Option<PathBuf>) -> Self {
        SpotsFromImageRequest {
            image,
            scene,
            white: None,
            target_de: 0.1,
            max_seconds: 600.0,
            seed: 1,
        }
    }
}

/// The readings taken from the image.
#[derive(Debug)]
pub struct SpotsFromImageReport {
    pub scene: Scene,
    pub image: PathBuf,
    /// SHA-256 of the image file, tying the readings to the bytes read.
    pub sha256: String,
    /// The image as read (XYZ in cd/m²), so a caller that shows or re-encodes it need not
    /// decode the file again.
    pub pixels: XyzImage,
    /// The white the readings' CIELAB is against.
    pub white: Xyz,
    /// How the white was traced (None: it was given).
    pub white_trace: Option<TracedWhite>,
    /// What the operator must know about these readings (a white cut short by the time
    /// limit); also sent as [`RenderEvent::Warning`] as it happens.
    pub warnings: Vec<String>,
    pub seconds: f64,
    /// Each with its 95 % half-width, its standard errors and the pixels in its cone as
    /// its samples.
    pub patches: Vec<RenderedReading>,
    /// Each patch's cone as the image covers it.
    pub cones: Vec<ConeMean>,
}

/// The image a reading came from, as the JSON names it.
#[derive(serde::Serialize)]
struct Source<'a> {
    file: &'a Path,
    sha256: &'a str,
    width: usize,
    height: usize,
    renderer: &'static str,
}

/// `render spots --json`'s shape, with the image in place of the solver's details.
#[derive(serde::Serialize)]
struct Json<'a> {
    method: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    provenance: Option<&'a serde_json::Map<String, serde_json::Value>>,
    image: Source<'a>,
    white: Xyz,
    #[serde(skip_serializing_if = "Option::is_none")]
    white_trace: Option<WhiteTrace<'a>>,
    warnings: &'a [String],
    seconds: f64,
    patches: &'a [RenderedReading],
}

/// A traced white as the JSON states it, with whether it reached its target.
#[derive(serde::Serialize)]
struct WhiteTrace<'a> {
    #[serde(flatten)]
    traced: &'a TracedWhite,
    reached: bool,
}

impl SpotsFromImageReport {
    /// One JSON object in the shape of `render spots --json` (`method`, `provenance`,
    /// `white`, `patches` with `XYZ`, `XYZ_stderr`, `de_ci95`, `samples`), plus `image`:
    /// the file, its digest and size. `validate --simulation` reads it.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string(&Json {
            method: METHOD,
            provenance: self.scene.provenance.as_ref(),
            image: Source {
                file: &self.image,
                sha256: &self.sha256,
                width: self.pixels.width,
                height: self.pixels.height,
                renderer: "external",
            },
            white: self.white,
            white_trace: self.white_trace.as_ref().map(|t| WhiteTrace {
                traced: t,
                reached: t.reached(),
            }),
            warnings: &self.warnings,
            seconds: self.seconds,
            patches: &self.patches,
        })
    }
}

/// Checks the request, loads the scene and the image, reads the 24 cones, finds the
/// white and checks the units. Nothing is written.
pub fn run(
    request: &SpotsFromImageRequest,
    events: &dyn Fn(RenderEvent),
) -> Result<SpotsFromImageReport, RenderError> {
    let start = Instant::now();
    check_white_request(request.target_de, request.max_seconds, request.white)?;
    let name = request
        .scene
        .as_ref()
        .map_or("the built-in scene".into(), |p| p.display().to_string());
    let scene = load_scene(request.scene.as_deref(), events)?;
    let camera = scene.camera.ok_or_else(|| RenderError::NoCamera {
        scene: name.clone(),
    })?;
    if scene.meter_acceptance_deg.is_none() {
        return Err(ReadBackError::NoMeter { scene: name }.into());
    }
    let file = request.image.clone();
    let image = read_xyz_image(&file)?;
    if image.width * camera.height != image.height * camera.width {
        return Err(ReadBackError::Aspect {
            file,
            width: image.width,
            height: image.height,
            camera_width: camera.width,
            camera_height: camera.height,
        }
        .into());
    }
    let cones = read_cones(&scene, &image, &file)?;
    let (white, traced) = match request.white {
        Some(w) => (w, None),
        None => {
            let t = reference_white_traced(
                &scene,
                &SpotOptions {
                    target_de: request.target_de,
                    max_seconds: request.max_seconds,
                    seed: request.seed,
                    ..SpotOptions::default()
                },
            )?;
            (t.xyz, Some(t))
        }
    };
    let mut warnings = Vec::new();
    if let Some(t) = traced.filter(|t| !t.reached()) {
        let w = short_white_warning(&t);
        events(RenderEvent::Warning(&w));
        warnings.push(w);
    }
    let (patch, ratio) = (cones[18].xyz[1], cones[18].xyz[1] / white[1]);
    if !(0.1..=10.0).contains(&ratio) {
        return Err(ReadBackError::Units {
            file,
            patch,
            white: white[1],
            ratio,
        }
        .into());
    }
    let patches = cones
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let uncertainty = Uncertainty::HalfWidth95 {
                de: de_ci95_of(c.xyz, c.cov_mean, white),
                sampling: Some(Sampling {
                    xyz_stderr: c.stderr(),
                    samples: c.pixels as u64,
                }),
            };
            RenderedReading::new(k + 1, c.xyz, white, uncertainty)
        })
        .collect();
    let sha256 = crate::digest::sha256_file(&file).map_err(|source| {
        RenderError::ImageIo(crate::image::ImageError::Io {
            file: file.clone(),
            source,
        })
    })?;
    Ok(SpotsFromImageReport {
        scene,
        pixels: image,
        image: file,
        sha256,
        white,
        white_trace: traced,
        warnings,
        seconds: start.elapsed().as_secs_f64(),
        patches,
        cones,
    })
}

/// What a white cut short by the time limit means for the readings, in words for the
/// operator.
fn short_white_warning(t: &TracedWhite) -> String {
    format!(
        "the reference white stopped at the time limit ({} s) with a ΔE*ab 95 % half-width of \
         {:.3}, above its target of {:.3} (a third of the ΔE*ab target): the readings' XYZ are \
         as read, but their CIELAB and ΔE95 carry the white's extra noise; give a measured \
         white, or more time or a larger ΔE*ab target",
        t.max_seconds, t.de_ci95, t.target_de
    )
}

/// The 24 cones' means, patch 1 first.
fn read_cones(scene: &Scene, image: &XyzImage, file: &Path) -> Result<Vec<ConeMean>, RenderError> {
    let camera = scene
        .camera
        .ok_or(crate::render::spot::SpotError::NoCamera)?;
    let frame = Frame::of(&camera, image.width, image.height);
    let mut out = Vec::with_capacity(24);
    for patch in 1..=24 {
        let aim = patch_aim(scene, patch)?;
        let cone_error = |error| ReadBackError::Cone {
            file: file.to_path_buf(),
            patch,
            error,
        };
        let pixels = cone_pixels(&frame, &aim).map_err(cone_error)?;
        let mean = cone_mean(image, &pixels).map_err(cone_error)?;
        if mean.effective < MIN_EFFECTIVE_PIXELS {
            return Err(ReadBackError::TooCoarse {
                file: file.to_path_buf(),
                patch,
                pixels: mean.pixels,
                effective: mean.effective,
            }
            .into());
        }
        if mean.xyz.iter().all(|v| v == 0.0) {
            return Err(ReadBackError::Dark {
                file: file.to_path_buf(),
                patch,
            }
            .into());
        }
        out.push(mean);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_bad_option_is_the_one_reported_before_anything_is_read() {
        let r = SpotsFromImageRequest {
            target_de: 0.0,
            white: Some(Xyz::new(1.0, 0.0, 1.0)),
            ..SpotsFromImageRequest::new("none.exr".into(), Some("none.json".into()))
        };
        let e = run(&r, &|_| panic!("no event")).unwrap_err();
        assert!(matches!(e, RenderError::TargetDe), "{e}");
        let r = SpotsFromImageRequest {
            white: Some(Xyz::new(1.0, 0.0, 1.0)),
            ..SpotsFromImageRequest::new("none.exr".into(), Some("none.json".into()))
        };
        let e = run(&r, &|_| panic!("no event")).unwrap_err();
        assert!(matches!(e, RenderError::White), "{e}");
    }
}
