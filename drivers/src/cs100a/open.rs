//! The CS-100A's three ways to be opened, named by its row in the driver registry: on a
//! serial port, on a replayed transcript, and as the emulator on an in-process pair.

use std::sync::Arc;

use super::emulator::{Cs100aEmulator, EmulatorConfig};
use super::{Cs100a, MODEL};
use crate::instrument::Instrument;
use crate::link::pair::pair;
use crate::link::record::RecordSerial;
use crate::link::replay::{ReplaySerial, Transcript};
use crate::link::serial::PortLink;
use crate::link::{LineSettings, SerialLink};
use crate::open::{OpenOptions, SimSettings};
use crate::simulated::Simulated;
use crate::spec::words::sim_connection;
use crate::world::{SharedWorld, DEFAULT_STIMULUS_XYZ};
use crate::DriverError;

/// A meter on the serial port `port` (`/dev/ttyUSB0`, `COM3`).
pub fn real(port: &str, options: &OpenOptions) -> Result<Box<dyn Instrument>, DriverError> {
    connect(PortLink::open(port, LineSettings::CS100A)?, options)
}

/// The driver run against a recorded session.
pub fn replay(
    transcript: Transcript,
    options: &OpenOptions,
) -> Result<Box<dyn Instrument>, DriverError> {
    connect(ReplaySerial::new(transcript)?, options)
}

/// The emulator answering from `options.stimulus` (default light if none).
pub fn sim(
    settings: &SimSettings,
    options: &OpenOptions,
) -> Result<Box<dyn Instrument>, DriverError> {
    let world = options
        .stimulus
        .clone()
        .unwrap_or_else(|| Arc::new(SharedWorld::new(DEFAULT_STIMULUS_XYZ)));
    let config = EmulatorConfig {
        seed: settings.seed,
        time_scale: settings.time_scale,
        noise: settings.noise,
    };
    let (host, device) = pair(LineSettings::CS100A, &sim_connection(MODEL));
    let emulator = Cs100aEmulator::new(world, config);
    let noise = emulator.noise_cursor();
    let pace = emulator.real_pace_clock();
    emulator.spawn(device);
    Ok(Simulated::wrap(
        connect(host, options)?,
        noise,
        pace,
        settings,
    ))
}

/// Puts the meter in absolute mode, recording the session when asked.
fn connect<L: SerialLink + 'static>(
    link: L,
    options: &OpenOptions,
) -> Result<Box<dyn Instrument>, DriverError> {
    match &options.record {
        Some(path) => {
            let description = format!("metamer session with the CS-100A on {}", link.describe());
            let rec = RecordSerial::create(link, path, MODEL, &description)?;
            let mut meter = Cs100a::new(rec);
            meter.connect()?;
            Ok(Box::new(meter))
        }
        None => {
            let mut meter = Cs100a::new(link);
            meter.connect()?;
            Ok(Box::new(meter))
        }
    }
}
