//! The one place that decides between the path tracer and the radiosity solver.
//!
//! Every caller that renders a scene either way (spot readings, images, probes, the
//! convergence chart, the experiment's simulation stage) resolves its [`Method`] here, so
//! `auto` means the same thing everywhere and says why it chose what it chose.

use std::fmt;

use super::radiosity::{qualifies, RadiosityError};
use super::scene::Scene;

/// How a caller asks for a scene to be rendered.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// The radiosity solver when the scene qualifies, else the path tracer.
    #[default]
    Auto,
    PathTracer,
    Radiosity,
}

/// The renderer a [`Method`] resolved to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Solver {
    PathTracer,
    Radiosity,
}

/// Why a [`Method`] resolved to its [`Solver`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Reason {
    /// The caller named the solver.
    Asked,
    /// `auto`: the scene is one the radiosity solver handles.
    Qualifies,
    /// `auto`: the radiosity solver cannot render the scene, for this reason.
    NotQualified(String),
}

impl fmt::Display for Reason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Reason::Asked => f.write_str("asked for"),
            Reason::Qualifies => f.write_str(
                "the scene is a convex enclosure of Lambertian rectangles the radiosity solver \
                 can mesh",
            ),
            Reason::NotQualified(why) => f.write_str(why),
        }
    }
}

/// A resolved method: the solver to use and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Resolved {
    pub method: Solver,
    pub reason: Reason,
}

impl Resolved {
    /// Why `auto` fell back to the path tracer, if it did: what a caller tells its user
    /// before the (slower) path tracer starts.
    pub fn fallback(&self) -> Option<&str> {
        match &self.reason {
            Reason::NotQualified(why) => Some(why),
            _ => None,
        }
    }

    pub fn is_radiosity(&self) -> bool {
        self.method == Solver::Radiosity
    }
}

impl Method {
    /// The solver for `scene`. Asking for radiosity on a scene it cannot render is an
    /// error (the reason why); `auto` falls back to the path tracer and keeps the reason.
    ///
    /// ```
    /// use metamer::render::method::{Method, Solver};
    /// use metamer::render::Scene;
    ///
    /// let scene = Scene::builtin("validation-box").unwrap();
    /// let resolved = Method::Auto.resolve(&scene).unwrap();
    /// assert_eq!(resolved.method, Solver::Radiosity);
    /// assert_eq!(resolved.fallback(), None);
    /// ```
    pub fn resolve(self, scene: &Scene) -> Result<Resolved, RadiosityError> {
        let (method, reason) = match self {
            Method::PathTracer => (Solver::PathTracer, Reason::Asked),
            Method::Radiosity => {
                qualifies(scene)?;
                (Solver::Radiosity, Reason::Asked)
            }
            Method::Auto => match qualifies(scene) {
                Ok(()) => (Solver::Radiosity, Reason::Qualifies),
                Err(why) => (Solver::PathTracer, Reason::NotQualified(why.to_string())),
            },
        };
        Ok(Resolved { method, reason })
    }
}
