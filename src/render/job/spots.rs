//! The 24 simulated 1° meter readings of a scene to a ΔE*ab target: `metamer render spots`
//! and the experiment's simulation stage, one entry for both. Either solver gives each
//! patch as a [`RenderedReading`] whose uncertainty says which statement it is.
//!
//! ```
//! use metamer::render::job::spots::{run, SpotsRequest};
//! use metamer::render::job::RenderEvent;
//!
//! // The built-in validation box: `auto` takes the radiosity solver there (about a second).
//! let request = SpotsRequest { target_de: 0.2, ..SpotsRequest::default() };
//! let report = run(&request, &|event| {
//!     if let RenderEvent::Method(m) = event {
//!         if let Some(why) = m.fallback() {
//!             eprintln!("using the path tracer: {why}");
//!         }
//!     }
//! })?;
//! for r in report.readings.patches() {
//!     println!("patch {}: L* {:.2} ± {:.3} ΔE*ab", r.patch, r.lab[0], r.uncertainty.de_ab());
//! }
//! assert_eq!(report.readings.patches().len(), 24);
//! println!("{}", report.to_json()?);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::PathBuf;

use super::{check_white_request, load_scene, RenderError, RenderEvent};
use crate::color::Xyz;
use crate::render::method::{Method, Resolved, Solver};
use crate::render::radiosity::RadiosityResult;
use crate::render::radiosity::{render_spots_radiosity_solved, LastLevels, RadiosityOptions};
use crate::render::scene::Scene;
use crate::render::spot::{render_spots_with_progress, RenderedReading, SpotOptions, SpotResult};

/// What to render.
#[derive(Clone, Debug)]
pub struct SpotsRequest {
    /// The scene file; None is the validation box built into the program.
    pub scene: Option<PathBuf>,
    pub method: Method,
    /// Every patch's ΔE*ab uncertainty (radiosity: its bound; path tracer: its 95 %
    /// half-width) is driven below this.
    pub target_de: f64,
    /// Reference white X,Y,Z (None: a perfect white diffuser in place of patch 19).
    pub white: Option<Xyz>,
    /// Wall-clock limit (s): the readings so far are reported, marked not converged.
    pub max_seconds: f64,
    /// The path tracer's seed.
    pub seed: u64,
}

impl Default for SpotsRequest {
    fn default() -> Self {
        SpotsRequest {
            scene: None,
            method: Method::Auto,
            target_de: 0.1,
            white: None,
            max_seconds: 600.0,
            seed: 1,
        }
    }
}

/// The readings as the solver that made them gives them.
pub enum Readings {
    PathTracer(SpotResult),
    Radiosity {
        result: RadiosityResult,
        /// The solutions the readings came from, for an image of the same light.
        solution: LastLevels,
        /// The options they were solved with.
        options: RadiosityOptions,
    },
}

impl Readings {
    /// The 24 readings, each with the uncertainty its solver states.
    pub fn patches(&self) -> &[RenderedReading] {
        match self {
            Readings::PathTracer(r) => &r.patches,
            Readings::Radiosity { result, .. } => &result.patches,
        }
    }

    /// The reference white the readings' CIELAB is against.
    pub fn white(&self) -> Xyz {
        match self {
            Readings::PathTracer(r) => r.white,
            Readings::Radiosity { result, .. } => result.white,
        }
    }

    /// Every patch reached the target.
    pub fn converged(&self) -> bool {
        match self {
            Readings::PathTracer(r) => r.converged,
            Readings::Radiosity { result, .. } => result.converged,
        }
    }
}

/// The finished readings with the scene and method they came from.
pub struct SpotsReport {
    pub scene: Scene,
    pub resolved: Resolved,
    pub readings: Readings,
}

/// A result with the method that produced it, as `--json` prints it.
#[derive(serde::Serialize)]
struct Tagged<'a, T: serde::Serialize> {
    method: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    provenance: Option<&'a serde_json::Map<String, serde_json::Value>>,
    #[serde(flatten)]
    result: &'a T,
}

impl SpotsReport {
    /// "path" or "radiosity", as the JSON names the method.
    pub fn method_name(&self) -> &'static str {
        match self.readings {
            Readings::PathTracer(_) => "path",
            Readings::Radiosity { .. } => "radiosity",
        }
    }

    /// One JSON object: the method, the scene's provenance and the readings.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        let method = self.method_name();
        let provenance = self.scene.provenance.as_ref();
        match &self.readings {
            Readings::PathTracer(result) => serde_json::to_string(&Tagged {
                method,
                provenance,
                result,
            }),
            Readings::Radiosity { result, .. } => serde_json::to_string(&Tagged {
                method,
                provenance,
                result,
            }),
        }
    }
}

/// Checks the request, loads the scene, resolves the method (reported before the work
/// starts) and renders the readings. The checks run in a fixed order and the first
/// failure is the one reported.
pub fn run(
    request: &SpotsRequest,
    events: &dyn Fn(RenderEvent),
) -> Result<SpotsReport, RenderError> {
    check_white_request(request.target_de, request.max_seconds, request.white)?;
    let scene = load_scene(request.scene.as_deref(), events)?;
    let resolved = request.method.resolve(&scene)?;
    events(RenderEvent::Method(&resolved));
    let readings = match resolved.method {
        Solver::Radiosity => {
            let options = RadiosityOptions {
                target_de: request.target_de,
                white: request.white,
                max_seconds: request.max_seconds,
                ..RadiosityOptions::default()
            };
            let (result, solution) = render_spots_radiosity_solved(&scene, &options, &|l| {
                events(RenderEvent::Level(l))
            })?;
            Readings::Radiosity {
                result,
                solution,
                options,
            }
        }
        Solver::PathTracer => {
            let options = SpotOptions {
                target_de: request.target_de,
                white: request.white,
                max_seconds: request.max_seconds,
                seed: request.seed,
                ..SpotOptions::default()
            };
            Readings::PathTracer(render_spots_with_progress(&scene, &options, &|p| {
                events(RenderEvent::Spots(&p))
            })?)
        }
    };
    Ok(SpotsReport {
        scene,
        resolved,
        readings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refusal(request: SpotsRequest) -> RenderError {
        match run(&request, &|_| {
            panic!("no event before the request is checked")
        }) {
            Err(e) => e,
            Ok(_) => panic!("accepted"),
        }
    }

    #[test]
    fn the_first_bad_option_is_the_one_reported_before_the_scene_is_read() {
        let e = refusal(SpotsRequest {
            scene: Some("no such scene.json".into()),
            target_de: 0.0,
            max_seconds: 0.0,
            white: Some(Xyz::new(1.0, 0.0, 1.0)),
            ..SpotsRequest::default()
        });
        assert!(e.is_bad_request());
        assert!(matches!(e, RenderError::TargetDe), "{e}");
        let e = refusal(SpotsRequest {
            scene: Some("no such scene.json".into()),
            max_seconds: f64::NAN,
            white: Some(Xyz::new(1.0, 0.0, 1.0)),
            ..SpotsRequest::default()
        });
        assert!(matches!(e, RenderError::MaxSeconds), "{e}");
        let e = refusal(SpotsRequest {
            scene: Some("no such scene.json".into()),
            white: Some(Xyz::new(1.0, 0.0, 1.0)),
            ..SpotsRequest::default()
        });
        assert!(matches!(e, RenderError::White), "{e}");
        let e = refusal(SpotsRequest {
            scene: Some("no such scene.json".into()),
            ..SpotsRequest::default()
        });
        assert!(!e.is_bad_request());
        assert!(matches!(e, RenderError::Scene(_)), "{e}");
    }
}
