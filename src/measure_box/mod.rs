//! Measuring the validation box: the guided, resumable session that reads the light's
//! tiles, its fall-off, the materials and the ColorChecker spots through the `Instrument`
//! trait on the session engine, and turns the readings into the measured scene.
//!
//! [`plan`] says what is measured (the plan file, the stages as session plans), [`run`]
//! takes the stages, [`stats`] reduces repeats and flags outliers, [`falloff`] makes the
//! light's distribution, [`scene`] writes the box as a scene file, [`assemble`] puts the
//! measured scene and its provenance together, and [`compare`] renders it against the box's
//! spot readings. [`setup`] opens the rig a session measures with: the real box, or the
//! simulated truth box and its operator ([`simulated_box`]); [`spot_rule`] ends a spot's
//! repeats by the plan's rule; [`adaptive`] reads the tiles and the fall-off in rounds
//! until what is not read cannot move the spots.

pub mod adaptive;
pub mod assemble;
pub mod compare;
pub mod falloff;
pub mod job;
pub mod plan;
pub mod run;
pub mod scene;
pub mod setup;
pub mod simulated_box;
pub mod spot_rule;
pub mod stats;

pub use assemble::{BoxDetails, Summary};
pub use plan::{BoxPlan, BoxPlanError, BoxStage, BoxStep, Geometry, Plane, Target};
pub use run::{run, BoxOptions, Instruments, MeasureBoxError, Outcome};
