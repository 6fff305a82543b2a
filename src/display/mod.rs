//! Display characterization: display models (paper Eq. 9 and richer), fitting,
//! reproduction of XYZ on a display, gamut mapping, the `characterize` session and the
//! patch-budget study. The screens that show the colours are devices, in `rig`.

// Measurements, models and fitting.
pub mod additivity_noise;
pub mod diagnostics;
pub mod fit;
pub mod measurements;
pub mod mixture_advice;
pub mod model;
pub mod profile;
pub mod scattered;
pub mod select;
pub mod select_chart;
pub mod verify;

// Using a profile.
pub mod gamut;
pub mod icc;
pub mod reproduce;

// Measuring a display.
pub mod characterize;

// Speed against accuracy.
pub mod budget;

// Each command's job as one call.
pub mod job;

pub use diagnostics::{Diagnostics, Noise, Residuals};
pub use fit::{fit_profile, fit_profile_with, FitOptions};
pub use icc::{encode_icc, IccError, IccForward, IccProfile, IccVersion};
pub use measurements::{
    read_measurement_file, read_measurements, write_ti3, CalibrationEntry, Measurements,
    MeasurementsError, Spectra,
};
pub use model::{DisplayModel, FitError, Inverse, ModelKind, Sample};
pub use profile::{Profile, ProfileError};
pub use select::{select_model, Selection};
pub use verify::{verify_profile, Verification};
