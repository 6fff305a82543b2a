//! The experiment: the paper's whole chain, stage by stage, on a real rig or the simulated
//! one — the box measured (`box/`), its scene simulated (`simulation/`), the display
//! characterized (`display/`), the simulation reproduced (`reproduction/`), shown and read
//! (`display-spots/`), and validated (`validation/`).
//!
//! Each stage writes into its own directory and records the hashes of what it read and
//! wrote ([`cache`]); a second run re-uses every stage whose inputs are unchanged and runs
//! exactly those downstream of a change. Measuring stages are journalled sessions and
//! resume after any interruption. [`Request::run`] is the whole experiment as one call;
//! [`lab`] is its preset for the simulated rig ([`lab::LabOptions::request`]).

pub mod budget;
pub mod cache;
pub mod display;
pub mod display_spots;
mod error;
pub mod external_image;
pub mod lab;
pub mod measure_box;
pub mod measuring;
mod options;
mod preflight;
mod products;
mod progress;
pub mod readings;
pub mod report_input;
pub mod reproduction;
mod request;
mod run;
pub mod simulation;
mod stage;
pub mod validate;

pub use error::ExperimentError;
pub use measuring::{Measures, MeasuringChoices, MeasuringPlan};
pub use options::{BoxSource, ExperimentOptions};
pub use progress::Progress;
pub use request::{BoxRequest, Outcome, Request, RequestError, DEFAULT_SPOT, MAX_IMAGE_SIZE};
pub use run::{run, StageOutcome};
pub use stage::Stage;
