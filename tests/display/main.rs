//! Display models: fits against analytic and simulated displays, `fit`/`reproduce`, ICC
//! profiles read back by other colour management systems. One module per topic;
//! tests/README.md lists them.

#[path = "../support/mod.rs"]
mod support;

mod adaptive_plan;
mod display_fit;
mod display_reproduce;
mod icc_profile;
mod icc_readers;
mod icc_resave;
mod ramp_fit;
mod rig_display_white;
mod scattered_fit;
