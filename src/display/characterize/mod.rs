//! The `characterize` session: plan the drive colours ([`plan`]), show and measure them on
//! the session engine with every reading journalled ([`run`]), average repeats and verify a
//! fitted display model on held-out colours ([`verify`], [`finish`]); [`request`] is the whole
//! job as one call, for the command and the experiment's display stage.

pub mod adaptive;
pub mod finish;
mod hands;
pub mod meter;
pub mod plan;
pub mod report;
pub mod request;
pub mod run;
pub mod verify;

pub use meter::{meter_sees, SimulatedMeterOnRealScreen};
pub use plan::{
    default_grid_steps, plan_advice, DriveStep, Plan, PlanError, PlanOptions, Purpose,
    DEFAULT_RAMP_STEPS,
};
pub use report::{write_report, Report, ReportError};
pub use request::{characterize, open_screen, Attend, Listener, Request, SimulatedMeter};
pub use run::{log_path, run, CharacterizeError, LogDetails, Options, Outcome, LOG_FILE};
pub use verify::{average, verify_held_out, AveragedPatch};
