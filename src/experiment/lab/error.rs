//! Why a lab run failed.

use std::path::PathBuf;

use crate::experiment::RequestError;
use crate::output::OutputError;

/// Why a lab run failed.
#[derive(Debug, thiserror::Error)]
pub enum LabError {
    #[error(transparent)]
    Request(#[from] RequestError),
    #[error("{}: not the validation stage's result: {message}", file.display())]
    BadResult { file: PathBuf, message: String },
    #[error("{0}")]
    Output(#[from] OutputError),
}
