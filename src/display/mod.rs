//! Display characterization (issue 5): display models (paper Eq. 9 and richer), fitting,
//! reproduction of XYZ on a display, patch display backends and the `characterize` session.

pub mod gamut;

use serde::{Deserialize, Serialize};

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
