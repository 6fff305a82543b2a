//! Instrument drivers and their links.
//!
//! A driver is generic over its link (serial, USB, HID), and every link has a real backend,
//! a replay backend that feeds recorded transcripts through the same driver code byte for
//! byte, a record backend, and in-process pairs for emulated devices. Above the drivers sits
//! one [`Instrument`] trait. Devices are chosen by one string, read by [`Spec`];
//! the models and how each is opened are rows of the [`registry`].

pub mod budget;
pub mod cs100a;
pub mod describe;
pub mod devices;
pub mod i1pro;

mod error;
pub mod instrument;
pub mod link;
mod mode;
pub mod noise;
mod open;
mod permissions;
pub mod registry;
pub mod simulated;
pub mod spec;
pub mod world;

pub use budget::{TimeBudget, TimeQuery};
pub use cs100a::Cs100aError;
pub use cs100a::Speed;
pub use error::DriverError;
pub use i1pro::I1ProError;
pub use instrument::{
    CalibrationCondition, CalibrationNeed, CalibrationOutcome, Capabilities, Flag, Forwarding,
    Instrument, InstrumentInfo, MeasureMode, ModeInfo, OptionInfo, OptionValues, Reading, Request,
};
pub use open::{OpenOptions, SimSettings, TIME_SCALE_ENV};
pub use permissions::{SERIAL_PERMISSION_FIX, USB_PERMISSION_FIX};
pub use registry::time_budget;
pub use spec::{
    check_spec, is_physical, open_instrument, open_instrument_with, Spec, MAX_TIME_SCALE,
};
pub use world::{Light, SharedWorld, View, World, DEFAULT_STIMULUS_XYZ};
