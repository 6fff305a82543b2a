//! The bundled spectral path tracer for the validation box (issue 4).
//!
//! It renders exactly the scene of `shared/validation-box.md`: rectangles with Lambertian
//! spectral reflectance and a tiled spectral emitter, traced with hero wavelengths and
//! projected on the CIE 1931 observer with K_m = 683 lm/W (paper Eq. 8), so its output is
//! absolute XYZ in cd/m². Spot mode simulates the 1° meter; image mode is the paper's
//! idealised film (Eq. 2–3).

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
pub mod image;
pub mod image_io;
pub mod probes;
pub mod radiosity;
