//! Why an export failed: each error names the scene (its path or built-in name) and what
//! is wrong.

use std::path::PathBuf;

use crate::output::OutputError;
use crate::render::scene::{PathError, SceneError};

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A built-in scene did not build: a defect of the program.
    #[error("built-in scene {name}: {source}")]
    Builtin { name: String, source: PathError },
    #[error("{scene}: the scene has no camera, and an export needs one for the image")]
    NoCamera { scene: String },
    #[error("{scene}: emitter {emitter}: {what}")]
    Emitter {
        scene: String,
        emitter: usize,
        what: String,
    },
    /// The caller may ask to write into it anyway.
    #[error(
        "refusing to export into {}: the directory is not empty",
        dir.display()
    )]
    NotEmpty { dir: PathBuf },
    #[error("the samples per pixel must be at least 1")]
    BadSpp,
    #[error("{0}")]
    Output(#[from] OutputError),
    #[error("{scene}: measuring the Lambertian form's difference: {message}")]
    Difference { scene: String, message: String },
}
