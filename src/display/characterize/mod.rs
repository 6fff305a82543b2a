//! The `characterize` session (issue 5 item 5): plan the patches ([`plan`]), show and
//! measure them with every reading appended to a durable log ([`log`], [`session`]),
//! average repeats and verify a fitted display model on held-out patches ([`verify`]).

pub mod finish;
pub mod log;
pub mod plan;
pub mod report;
pub mod session;
pub mod verify;

pub use log::{LogError, LOG_FILE};
pub use plan::{
    default_grid_steps, Plan, PlanError, PlanOptions, PlannedPatch, Purpose, DEFAULT_RAMP_STEPS,
};
pub use report::{write_report, Report, ReportError};
pub use session::{MeasureOptions, Measured, Progress, Session, SessionError};
pub use verify::{average, verify, AveragedPatch, Verification};
