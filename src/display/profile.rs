//! A fitted display profile as a JSON document: model name and parameters, white and black
//! XYZ, residuals, diagnostics and the measurement file's SHA-256.

use crate::output::{OutputError, OutputPolicy};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::diagnostics::{Diagnostics, Residuals};
use super::model::{DisplayModel, Inverse, ModelKind, ModelParams};
use crate::color::Xyz;

/// The `format` value of profiles this version writes and reads.
pub const PROFILE_FORMAT: &str = "metamer-display-profile-1";

/// The measurements file a profile was fitted from: its path, SHA-256 and patch count.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FittedFrom {
    pub path: String,
    pub sha256: String,
    pub patches: usize,
}

/// A fitted model with everything needed to trust or reject it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Profile {
    pub format: String,
    pub model: ModelKind,
    pub parameters: ModelParams,
    /// The display white (measured when a white patch was), cd/m²; the CIELAB reference.
    pub white_xyz: Xyz,
    pub black_xyz: Xyz,
    pub residuals: Residuals,
    pub diagnostics: Diagnostics,
    pub input: Option<FittedFrom>,
}

/// Why a profile could not be saved or loaded.
#[derive(Debug, thiserror::Error)]
pub enum ProfileError {
    #[error("{file}: {source}")]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}:{line}:{column}: not a display profile: {message}")]
    Json {
        file: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{file}: format '{found}' is not '{PROFILE_FORMAT}'")]
    Format { file: PathBuf, found: String },
    #[error("{file}: inconsistent parameters: {message}")]
    Parameters { file: PathBuf, message: String },
    #[error("{0}")]
    Output(#[from] OutputError),
}

impl Profile {
    pub fn model(&self) -> &dyn DisplayModel {
        self.parameters.model()
    }

    pub fn diagnostics(&self) -> &Diagnostics {
        &self.diagnostics
    }

    /// Drive values 0–1 → absolute XYZ, cd/m².
    pub fn forward(&self, rgb: [f64; 3]) -> Xyz {
        self.model().forward(rgb)
    }

    /// XYZ → drive values, with out-of-gamut reported.
    pub fn inverse(&self, xyz: Xyz) -> Inverse {
        self.model().inverse(xyz)
    }

    /// Writes pretty JSON under the output policy `out` (atomically: an interrupted save
    /// never leaves a truncated profile behind).
    pub fn save(&self, path: &Path, out: &OutputPolicy) -> Result<(), ProfileError> {
        let text = serde_json::to_string_pretty(self).expect("a profile always serialises");
        Ok(out.write(path, (text + "\n").as_bytes())?)
    }

    pub fn load(path: &Path) -> Result<Profile, ProfileError> {
        let file = path.to_path_buf();
        let text = metamer_color::text::read_text(path).map_err(|source| ProfileError::Io {
            file: file.clone(),
            source,
        })?;
        let text = metamer_color::text::strip_bom(&text);
        let mut p: Profile = serde_json::from_str(text).map_err(|e| ProfileError::Json {
            file: file.clone(),
            line: e.line(),
            column: e.column(),
            message: metamer_color::text::echo_message(&e.to_string()),
        })?;
        if p.format != PROFILE_FORMAT {
            return Err(ProfileError::Format {
                file,
                found: metamer_color::text::echo(&p.format),
            });
        }
        // The white is the CIELAB reference of every colour reproduced: a zero or NaN white
        // makes every L*a*b* NaN.
        for (name, xyz) in [("white_xyz", p.white_xyz), ("black_xyz", p.black_xyz)] {
            metamer_color::check_xyz(xyz).map_err(|e| ProfileError::Parameters {
                file: file.clone(),
                message: format!("{name}: {e}"),
            })?;
        }
        if p.white_xyz[1] <= 0.0 {
            return Err(ProfileError::Parameters {
                file,
                message: format!(
                    "white_xyz {:?} has no luminance; the white must have Y > 0",
                    p.white_xyz.to_array()
                ),
            });
        }
        p.parameters
            .prepare(p.model)
            .map_err(|message| ProfileError::Parameters { file, message })?;
        Ok(p)
    }
}
