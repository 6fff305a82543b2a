//! The renderers of the validation box and of rooms like it: a spectral path tracer (the
//! general method) and a deterministic radiosity solver for convex Lambertian enclosures
//! (`radiosity`, the fast one).
//!
//! They render the scene of `docs/validation-box.md`: rectangles with Lambertian spectral
//! reflectance and a tiled spectral emitter. The path tracer uses hero wavelengths; both
//! project on the CIE 1931 observer with K_m = 683 lm/W (paper Eq. 8), so their output is
//! absolute XYZ in cd/m². Spot mode simulates the 1° meter; image mode is the paper's
//! idealised film (Eq. 2–3), rendered by either (`radiosity::image`: the solution seen
//! from the camera, noise-free).

pub mod geometry;
pub mod integrator;
pub mod scene;
pub mod spectral;
pub mod spot;

pub use integrator::{Strategy, Tracer, Wavelengths};
pub use scene::{Scene, SceneError};
pub use spot::{
    reference_white, render_spots, render_spots_with_progress, SpotOptions, SpotProgress,
    SpotResult,
};
pub mod convergence;
pub mod deadline;
pub mod image;
pub mod job;
pub mod method;
pub mod probes;
pub mod radiosity;
