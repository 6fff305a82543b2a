//! One engine for every guided measurement session (display characterization, reading the
//! validation box): a plan of steps ([`plan`]), a durable resumable journal ([`journal`]) of
//! what was measured ([`record`]), and a runner that takes each step the journal lacks
//! ([`runner`]; calibrate, prepare, settle, measure: [`step`]),
//! what it will cost and what it took ([`budget`]),
//! with the operator ([`operator`]) and who answers for it ([`attendance`]), the readings a placement should repeat ([`repeats`]),
//! the screen ([`screen`]), progress ([`progress`]) and
//! Ctrl-C ([`interrupt`]) as small parts a caller supplies or picks.

pub mod attendance;
pub mod budget;
pub mod interrupt;
pub mod journal;
pub mod operator;
pub mod plan;
pub mod progress;
pub mod record;
pub mod repeats;
pub mod runner;
pub mod screen;
pub mod step;

pub use attendance::{attendance, Attendance, NobodyAtTheRig};
pub use budget::{Cost, CostReport, Meter, PLACEMENT_S};
pub use interrupt::on_ctrl_c;
pub use journal::{
    duplicates_path, reading_problem, refuse_existing, torn_path, CalibrationRecord, Header,
    Journal, JournalEntry, JournalError,
};
pub use operator::{
    Answer, Operator, OperatorError, PlacementReadings, Recheck, ScriptedOperator,
    TerminalOperator, Unattended,
};
pub use plan::{placements, Prepare, SessionPlan, Step};
pub use progress::{
    pace_note, BarProgress, Heartbeat, NoProgress, ProgressSink, StageOf, StepProgress,
};
pub use record::{Entry, InstrumentRecord, SessionHeader, SessionJournal};
pub use runner::{
    patch_so_far, RunEnd, RunOptions, Session, SessionError, SettingDiffers, Stopping,
};
pub use screen::{MeterAim, Placement, Screen, ScreenError};
pub use step::{Rig, StepFailure, AIM_AT_SCREEN_AGAIN};
