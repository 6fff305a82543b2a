//! Each `metamer render` command's whole job as one library call: the request is checked,
//! the scene loaded, the method resolved ([`super::method`]), the work done and its files
//! written here, so the command line only parses, calls and prints — and a program using
//! the library does exactly what the command does.
//!
//! Work that takes seconds or more reports as it goes through a [`RenderEvent`] callback
//! rather than only in the returned report: a caller shows the method's fallback reason
//! and the scene's warnings before a later step can fail, and a report returned at the end
//! would lose them on error.

pub mod convergence;
pub mod image;
pub mod probes;
pub mod spots;
pub mod spots_from_image;

use std::path::{Path, PathBuf};

use crate::color::Xyz;
use crate::image::ImageError;
use crate::numeric_csv::CsvError;
use crate::output::OutputError;
use crate::render::convergence::ConvergenceError;
use crate::render::image::ImageRenderError;
use crate::render::method::{Resolved, Solver};
use crate::render::probes::ProbeError;
use crate::render::radiosity::probes::ProbeProgress;
use crate::render::radiosity::{Level, RadiosityError};
use crate::render::scene::{PathError, Scene, SceneError};
use crate::render::spot::cone::ReadBackError;
use crate::render::spot::{SpotError, SpotProgress};

/// Why a render job did not finish. Wrapped errors show as they do on their own (their
/// messages already name the file and what to do), so wrapping adds no text.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The request itself is wrong (from here to [`RenderError::PreviewIsImage`]: an option
    /// out of range, two outputs the same file): the caller can fix it by asking
    /// differently; the command line calls it a usage error.
    ///
    /// The ΔE*ab target of a traced reading (the white's, or the spots'): not above 0.
    #[error("the ΔE*ab target must be > 0")]
    TargetDe,
    #[error("the time limit must be > 0")]
    MaxSeconds,
    #[error("the given reference white must be finite with Y > 0")]
    White,
    /// The convergence chart's time budget per strategy.
    #[error("{0}")]
    Seconds(String),
    #[error("the samples per pixel must be ≥ 1")]
    Spp,
    #[error("the image's width and height must be ≥ 1")]
    Size,
    #[error("the preview {} is the same file as the image {}", preview.display(), image.display())]
    PreviewIsImage { preview: PathBuf, image: PathBuf },
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The built-in scene did not build (a defect of the program, not of the request).
    #[error(transparent)]
    Builtin(#[from] PathError),
    #[error(transparent)]
    Spot(#[from] SpotError),
    #[error(transparent)]
    Radiosity(#[from] RadiosityError),
    #[error(transparent)]
    Image(#[from] ImageRenderError),
    #[error(transparent)]
    ImageIo(#[from] ImageError),
    /// An image that cannot be read back as the meter's readings.
    #[error(transparent)]
    ReadBack(#[from] ReadBackError),
    #[error(transparent)]
    Convergence(#[from] ConvergenceError),
    #[error(transparent)]
    Csv(#[from] CsvError),
    /// Not transparent: the output error stays in the source chain, where a caller looks
    /// for it to tell whether forcing would lift the refusal.
    #[error("{0}")]
    Output(#[from] OutputError),
    #[error("{scene}: the scene has no camera")]
    NoCamera { scene: String },
    #[error("{}:{line}: the normal is zero", file.display())]
    ZeroNormal { file: PathBuf, line: usize },
    /// The probes failed; named by the points file. The probe error is in the message and
    /// deliberately not a source, so it is shown once, as the command always showed it.
    #[error("{}: {error}", file.display())]
    Probes { file: PathBuf, error: ProbeError },
}

impl RenderError {
    /// Whether the request, not the data or the machine, is at fault.
    pub fn is_bad_request(&self) -> bool {
        matches!(
            self,
            RenderError::TargetDe
                | RenderError::MaxSeconds
                | RenderError::White
                | RenderError::Seconds(_)
                | RenderError::Spp
                | RenderError::Size
                | RenderError::PreviewIsImage { .. }
        )
    }
}

/// What a job reports while it works.
#[derive(Debug)]
pub enum RenderEvent<'a> {
    /// The scene loaded with a warning (the file is usable but probably not as meant).
    SceneWarning(&'a str),
    /// The method resolved, before the work starts.
    Method(&'a Resolved),
    /// The radiosity solver finished a mesh level of the spot readings.
    Level(&'a Level),
    /// The path tracer's spot readings moved towards their target.
    Spots(&'a SpotProgress),
    /// An image of this size is about to be rendered.
    ImageSize { width: usize, height: usize },
    /// The path tracer finished this many more rows of an image.
    Rows(usize),
    /// Probe progress.
    Probe(ProbeProgress<'a>),
    /// The image file is written (the preview, if any, is still to come).
    ImageWritten(&'a ImageReport),
    /// The preview is written.
    PreviewWritten(&'a Path),
    /// A line of a long run's log (the convergence chart's strategies and levels).
    Log(&'a str),
    /// Something about the result the caller must show the user (the report carries it
    /// too): a reference white cut short by the time limit.
    Warning(&'a str),
}

/// A written image (of [`image::run`]).
#[derive(Clone, Debug)]
pub struct ImageReport {
    pub width: usize,
    pub height: usize,
    pub spp: u64,
    pub method: Solver,
    /// Rendering time, not counting the files.
    pub seconds: f64,
    pub output: PathBuf,
    /// The preview, once written.
    pub preview: Option<PathBuf>,
}

/// The checks a request that may trace a reference white shares, in the order reported:
/// the white's precision and time limit, then a given white.
pub(crate) fn check_white_request(
    target_de: f64,
    max_seconds: f64,
    white: Option<Xyz>,
) -> Result<(), RenderError> {
    if target_de.is_nan() || target_de <= 0.0 {
        return Err(RenderError::TargetDe);
    }
    if max_seconds.is_nan() || max_seconds <= 0.0 {
        return Err(RenderError::MaxSeconds);
    }
    if let Some(w) = white {
        if !(w.iter().all(|x| x.is_finite()) && w[1] > 0.0) {
            return Err(RenderError::White);
        }
    }
    Ok(())
}

/// The scene at `path` (or the built-in box it names, see [`Scene::builtin_named`]), or the
/// default built-in box; its warnings go to `events`.
pub fn load_scene(path: Option<&Path>, events: &dyn Fn(RenderEvent)) -> Result<Scene, RenderError> {
    let scene = match path {
        Some(p) => match Scene::builtin_named(p) {
            Some(name) => Scene::builtin(name)?,
            None => Scene::load(p)?,
        },
        None => Scene::builtin(crate::render::scene::builtin::NAMES[0])?,
    };
    for w in &scene.warnings {
        events(RenderEvent::SceneWarning(w));
    }
    Ok(scene)
}
