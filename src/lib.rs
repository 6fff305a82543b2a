//! metamer: prove that a rendering is colour-true.
//!
//! The library implements the chain of Bärz, Henrich and Müller, "Validating Photometric and
//! Colorimetric Consistency of Physically-Based Image Synthesis": instruments (in the
//! `metamer-drivers` crate), display characterization, the measured validation box, a
//! spectral path tracer, reproduction on the display and validation in CIELAB.
//! The `metamer` binary is a thin command line over this library.

pub mod calendar;
pub mod color;
pub mod digest;
pub mod display;
pub mod experiment;
pub mod export;
pub mod image;
pub mod light;
pub mod measure_box;
pub mod numeric_csv;
pub mod output;
pub mod plot;
pub mod render;
pub mod rig;
pub mod session;
pub mod spot;
pub mod validation;
