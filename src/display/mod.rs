//! Display characterization (issue 5): display models (paper Eq. 9 and richer), fitting,
//! reproduction of XYZ on a display, patch display backends and the `characterize` session.

pub mod budget;
pub mod gamut;

use serde::{Deserialize, Serialize};

pub mod diagnostics;
pub mod fit;
pub mod measurements;
pub mod model;
pub mod patch_set;
pub mod profile;
pub mod reproduce;

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

pub mod characterize;
pub mod patch_display;
pub mod virtual_display;
pub mod window;

pub use patch_display::{DisplaySpec, PatchDisplay, PatchDisplayError};
pub use virtual_display::{Preset, VirtualDisplay, VirtualPanel};
