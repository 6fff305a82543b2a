//! Instrument drivers and their links.
//!
//! A driver is generic over its link (serial, USB, HID), and every link has a real backend,
//! a replay backend that feeds recorded transcripts through the same driver code byte for
//! byte, a record backend, and in-process pairs for emulated devices. Above the drivers sits
//! one [`Instrument`] trait. Devices are chosen by one string (see [`open_instrument`]).

mod error;
pub mod instrument;

pub use error::DriverError;
pub use instrument::{
    CalibrationCondition, CalibrationOutcome, Capabilities, Flag, Instrument, InstrumentInfo,
    MeasureMode, Reading, ReadingSpectrum, Request, SharedStimulus, Speed, Stimulus,
};
