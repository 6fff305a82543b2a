//! Display characterization (issue 5): display models (paper Eq. 9 and richer), fitting,
//! reproduction of XYZ on a display, gamut mapping, patch display backends, the
//! `characterize` session and the patch-budget study.

use serde::{Deserialize, Serialize};

// Measurements, models and fitting.
pub mod diagnostics;
pub mod fit;
pub mod measurements;
pub mod model;
pub mod profile;

// Using a profile.
pub mod gamut;
pub mod reproduce;

// Showing and measuring patches.
pub mod characterize;

// Speed against accuracy.
pub mod budget;

pub use diagnostics::{Diagnostics, Noise, Residuals};
pub use fit::{fit_profile, fit_profile_with, FitError, FitOptions};
pub use measurements::{read_measurement_file, read_measurements, write_ti3, MeasurementsError};
pub use model::{DisplayModel, Inverse, ModelKind};
pub use profile::{Profile, ProfileError};

/// One measured patch: drive values 0–1 per channel and the XYZ measured, cd/m².
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Patch {
    pub rgb: [f64; 3],
    pub xyz: [f64; 3],
}
