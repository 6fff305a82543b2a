//! The convergence chart of a scene written to a directory: `metamer render convergence`
//! in one call (the computation itself is [`crate::render::convergence`]).
//!
//! ```no_run
//! use metamer::render::job::convergence::{run, ConvergenceRequest};
//! use metamer::render::job::RenderEvent;
//!
//! let request = ConvergenceRequest::new("charts".into());
//! run(&request, &|event| {
//!     if let RenderEvent::Log(line) = event {
//!         eprintln!("{line}");
//!     }
//! })?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::PathBuf;

use super::{load_scene, RenderError, RenderEvent};
use crate::color::Xyz;
use crate::output::OutputPolicy;
use crate::render::convergence::{self, Point, CSV_FILE, SVG_FILE};

/// What to chart.
#[derive(Clone, Debug)]
pub struct ConvergenceRequest {
    /// The scene file; None is the built-in validation box.
    pub scene: Option<PathBuf>,
    /// The directory of `convergence.csv` and `convergence.svg`.
    pub output: PathBuf,
    /// Confidence target of the reference run.
    pub reference_de: f64,
    /// Time budget per strategy (s).
    pub seconds: f64,
    pub seed: u64,
    /// Replace the chart's files if they exist.
    pub force: bool,
}

impl ConvergenceRequest {
    /// The command's defaults, into `output`.
    pub fn new(output: PathBuf) -> Self {
        ConvergenceRequest {
            scene: None,
            output,
            reference_de: 0.05,
            seconds: 20.0,
            seed: 1,
            force: false,
        }
    }
}

/// The chart's points and where they went.
#[derive(Clone, Debug)]
pub struct ConvergenceReport {
    pub points: Vec<Point>,
    /// The reference run's white.
    pub white: Xyz,
    pub csv: PathBuf,
    pub svg: PathBuf,
}

/// Checks the budget and the outputs first (the reference run alone takes tens of
/// seconds), then runs every strategy, logging as [`RenderEvent::Log`], and writes both
/// files.
pub fn run(
    request: &ConvergenceRequest,
    events: &dyn Fn(RenderEvent),
) -> Result<ConvergenceReport, RenderError> {
    let r = request;
    convergence::check_seconds(r.seconds).map_err(|e| RenderError::Seconds(e.to_string()))?;
    let mut out = OutputPolicy::new(r.force);
    if let Some(s) = &r.scene {
        out.input(s);
    }
    out.dir(&r.output)?;
    for f in [CSV_FILE, SVG_FILE] {
        out.check(&r.output.join(f))?;
    }
    let scene = load_scene(r.scene.as_deref(), events)?;
    let (points, white) = convergence::run(&scene, r.reference_de, r.seconds, r.seed, &|m| {
        events(RenderEvent::Log(m))
    })?;
    convergence::write(&r.output, &points, &out)?;
    Ok(ConvergenceReport {
        points,
        white,
        csv: r.output.join(CSV_FILE),
        svg: r.output.join(SVG_FILE),
    })
}
