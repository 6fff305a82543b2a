//! The light source's angular distribution: the C-γ table every part of the chain shares
//! (the fit writes it, scenes carry it, the renderers evaluate it, IES/LDT files hold it).

pub mod cgamma;

pub use cgamma::{CGammaError, CGammaTable};
