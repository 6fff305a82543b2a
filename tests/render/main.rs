//! Rendering and lights: the radiosity solver and path tracer against analytic cases and
//! bounds, CIE 171 test cases, the light distribution fit and IES/EULUMDAT files. One
//! module per topic; tests/README.md lists them.

#[path = "../support/mod.rs"]
mod support;

mod cie171;
mod export_blender;
mod export_mitsuba;
mod export_names;
mod export_pbrt;
mod export_round_trip;
mod light_files;
mod light_fit;
mod radiosity;
mod radiosity_bound;
mod render_accuracy;
mod spots_from_image;
