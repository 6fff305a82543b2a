//! The light source's angular distribution: the C-γ table every part of the chain shares
//! (the fit writes it, scenes carry it, the renderers evaluate it, IES/LDT files hold it).

pub mod cgamma;
pub mod chart;
pub mod fit;
pub mod ies;
pub mod job;
pub mod ldt;
mod numbers;
pub mod photometry;

pub use cgamma::{CGammaError, CGammaTable};
pub use fit::{fit, Falloff, LdcError, LdcFit, LdcModel, ModelChoice, PlaneData};
pub use photometry::{flux_lm, Panel, Photometry, PhotometryError};
