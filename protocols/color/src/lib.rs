//! Colour science: sampled spectra, embedded CIE and ColorChecker tables, spectra to XYZ
//! (paper Eq. 8), XYZ ↔ xyY ↔ CIELAB ↔ LCh, and colour differences (ΔE*ab, CIEDE2000).

mod colorimetry;
mod coords;
mod delta_e;
mod describe;
mod error;
mod plausible;
mod spectrum;
mod spectrum_json;
mod sprague;
mod srgb;
mod table;
mod tables;
pub mod text;

pub use colorimetry::{
    illuminant_white, illuminant_white_over, luminance, radiance_to_xyz, reflectance_to_xyz,
    summation_range, CIE_END_NM, CIE_START_NM, END_NM, K_M, START_NM,
};
pub use coords::{Lab, Lch, XyY, Xyz, D65_XY};
pub use delta_e::{delta_e2000, delta_e76};
pub use describe::{describe, Description};
pub use error::ColorError;
pub use plausible::{check_xyz, check_yxy, plausible_spread, Implausible, MAX_CD_M2};
pub use spectrum::{Interpolation, Outside, Quantity, Spectrum};
pub use srgb::{srgb_encode, xyz_to_linear_srgb, XYZ_TO_LINEAR_SRGB};
pub use table::SpectralTable;
pub use tables::{
    colorchecker, observer, paper_white, ColorCheckerSet, Illuminant, Observer, ObserverKind,
    COLORCHECKER_NAMES,
};
