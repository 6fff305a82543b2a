//! Why a fall-off cannot be fitted.

use std::path::PathBuf;

use super::half::{HalfPlane, Plane};
use super::models::LdcModel;
use crate::light::cgamma::CGammaError;

/// Why the fall-off cannot be fitted.
#[derive(Debug, thiserror::Error)]
pub enum LdcError {
    #[error("{file}: cannot read: {source}")]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}:{line}: {message}")]
    Csv {
        file: PathBuf,
        line: usize,
        message: String,
    },
    #[error("the {plane} plane has no readings")]
    EmptyPlane { plane: Plane },
    #[error("the {plane} plane has {angles} angles but {readings} readings")]
    LengthMismatch {
        plane: Plane,
        angles: usize,
        readings: usize,
    },
    #[error("the {plane} plane: angle {angle}° is not within (−90°, 90°) (the light is seen from the front)")]
    AngleOutOfRange { plane: Plane, angle: f64 },
    #[error("the {plane} plane: angle {angle}° after {previous}°: angles must increase strictly (no repeats)")]
    AnglesNotIncreasing {
        plane: Plane,
        previous: f64,
        angle: f64,
    },
    #[error("the {plane} plane at {angle}°: luminance {value:?} must be finite, ≥ 0 and at most 1e10 (brighter than the sun's disc)")]
    BadLuminance {
        plane: Plane,
        angle: f64,
        value: f64,
    },
    #[error("the {plane} plane has no reading at 0° (the normal), which the distribution is relative to")]
    NoNormalReading { plane: Plane },
    #[error(
        "the {plane} plane reads 0 at the normal: the distribution cannot be made relative to it"
    )]
    ZeroNormalReading { plane: Plane },
    #[error(
        "half-plane {half}: {got} angle(s) off the normal, the {model} model needs at least {need}"
    )]
    TooFewAngles {
        half: HalfPlane,
        model: LdcModel,
        got: usize,
        need: usize,
    },
    #[error(
        "the {plane} plane: {got} angle(s) off the normal, the {model} model needs at least {need}"
    )]
    TooFewPlaneAngles {
        plane: Plane,
        model: LdcModel,
        got: usize,
        need: usize,
    },
    #[error("the {plane} plane at {angle}°: the reading {value:e} is {ratio:.3e} times the normal luminance {normal:e}; a distribution relative to the normal takes at most {max} times it (is the 0° reading right?)")]
    FarAboveNormal {
        plane: Plane,
        angle: f64,
        value: f64,
        normal: f64,
        ratio: f64,
        max: f64,
    },
    #[error("the two planes' readings along the normal, {horizontal:e} (horizontal) and {vertical:e} (vertical), differ by a factor of {ratio:.3}: both look along the same direction, so one of them is wrong")]
    NormalsDisagree {
        horizontal: f64,
        vertical: f64,
        ratio: f64,
    },
    #[error("{what} is {value}: the fit has no finite value there")]
    NotFinite { what: String, value: f64 },
    #[error("no model could be cross-validated: every half-plane needs at least 2 angles off the normal")]
    NothingToChoose,
    #[error("cannot draw the chart: {message}")]
    Chart { message: String },
    #[error("the fitted distribution is not a valid C-γ table: {0}")]
    Table(#[from] CGammaError),
}
