//! The colour core, which lives in the `metamer-color` crate so the instrument drivers
//! compute XYZ with the same code and the same CIE tables; re-exported here so the library
//! keeps one `color` path.

pub use metamer_color::*;
