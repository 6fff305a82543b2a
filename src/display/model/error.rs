//! Why a display model could not be fitted: the error of every model's fit and of the fit
//! as a whole.

use std::path::PathBuf;

use super::kind::ModelKind;

/// Why a model could not be fitted.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    #[error("no patches to fit")]
    NoSamples,
    #[error("patch {index} (r,g,b = {rgb:?}) has a value that is not a finite number in range")]
    BadSample { index: usize, rgb: [f64; 3] },
    #[error("{model} needs {what}; the measurements have none")]
    Missing { model: ModelKind, what: String },
    #[error(
        "the primaries are (nearly) linearly dependent: the condition number of M (columns: \
         full-on red, green, blue minus black) is {condition:.3e}, above {limit:.0e}; check that \
         the three primaries were measured on the right patches and are above the black level"
    )]
    SingularPrimaries { condition: f64, limit: f64 },
    #[error("{model}: {message}")]
    Failed { model: ModelKind, message: String },
    #[error("{file}: cannot read for its hash: {source}")]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
}
