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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::geometry::{Rect, Vec3};

    /// The validation box with a baffle inside: not convex, so no radiosity.
    fn baffled() -> Scene {
        let mut scene = Scene::builtin("validation-box").unwrap();
        let mut baffle = scene.surfaces[0].clone();
        baffle.name = "baffle".into();
        baffle.patch = None;
        baffle.rect = Rect::new(
            Vec3::new(0.2, 0.05, 0.2),
            Vec3::new(0.1, 0.0, 0.0),
            Vec3::new(0.0, 0.1, 0.0),
        );
        scene.surfaces.push(baffle);
        scene
    }

    #[test]
    fn auto_takes_radiosity_where_the_scene_qualifies() {
        let scene = Scene::builtin("validation-box").unwrap();
        let r = Method::Auto.resolve(&scene).unwrap();
        assert_eq!((r.method, r.reason), (Solver::Radiosity, Reason::Qualifies));
        let r = Method::PathTracer.resolve(&scene).unwrap();
        assert_eq!((r.method, r.reason), (Solver::PathTracer, Reason::Asked));
    }

    #[test]
    fn auto_falls_back_with_the_reason_radiosity_refuses() {
        let scene = baffled();
        let refusal = Method::Radiosity.resolve(&scene).unwrap_err().to_string();
        assert!(refusal.contains("not a convex enclosure"), "{refusal}");
        let r = Method::Auto.resolve(&scene).unwrap();
        assert_eq!(r.method, Solver::PathTracer);
        // The reason is the refusal's text, as `render spots` prints it.
        assert_eq!(r.fallback(), Some(refusal.as_str()));
        assert_eq!(r.reason.to_string(), refusal);
    }
}
