//! The i1Pro's three ways to be opened, named by its row in the driver registry: on USB, on
//! a replayed transcript, and as the emulator on the in-process USB pair.

use std::sync::Arc;

use metamer_protocols::i1pro::{Revision, VENDOR_ID};

use super::clock::{Clock, ManualClock, ScaledClock, SystemClock};
use super::emulator::{default_light, EmulatorConfig, I1ProEmulator};
use super::{I1Pro, MODEL};
use crate::instrument::Instrument;

use crate::link::replay::Transcript;
use crate::link::usb::{RecordUsb, ReplayUsb, UsbLink};
use crate::link::usb_pair::usb_pair;
use crate::link::usb_real::RusbLink;
use crate::noise::NoiseCursor;
use crate::open::{OpenOptions, SimSettings};
use crate::simulated::Simulated;
use crate::spec::words::sim_connection;
use crate::world::{SharedWorld, View, World};
use crate::DriverError;

/// USB product id of the i1Pro and i1Pro 2.
pub const PRODUCT_ID: u16 = 0x2000;

/// The i1Pro on USB; `serial` picks one of several (empty: the first found).
pub fn real(serial: &str, options: &OpenOptions) -> Result<Box<dyn Instrument>, DriverError> {
    let serial = (!serial.is_empty()).then_some(serial);
    let link = RusbLink::open(VENDOR_ID, PRODUCT_ID, serial, 0)?;
    connect(link, options, Arc::new(SystemClock::default()), true)
}

/// The driver run against a recorded session. Its clock never moves, so calibrations in the
/// transcript never expire on their own.
pub fn replay(
    transcript: Transcript,
    options: &OpenOptions,
) -> Result<Box<dyn Instrument>, DriverError> {
    connect(
        ReplayUsb::new(transcript)?,
        options,
        Arc::new(super::clock::ManualClock::new()),
        false,
    )
}

/// The emulator answering from `options.stimulus` (default: 100 cd/m² of LED-RGB1 as a
/// spectrum). Model options: `rev=d|e`, `diffuser=on|off`.
pub fn sim(
    settings: &SimSettings,
    options: &OpenOptions,
) -> Result<Box<dyn Instrument>, DriverError> {
    let mut config = EmulatorConfig {
        seed: settings.seed,
        noise: settings.noise,
        time_scale: settings.time_scale,
        ..EmulatorConfig::default()
    };
    for (key, value) in &settings.extra {
        let bad = |m: String| DriverError::Simulation(format!("{}: {m}", sim_connection(MODEL)));
        match (key.as_str(), value.as_str()) {
            ("rev", "d") => config.revision = Revision::AToD,
            ("rev", "e") => config.revision = Revision::E,
            ("rev", v) => return Err(bad(format!("rev={v:?}: expected d or e"))),
            ("diffuser", "on") => config.diffuser = true,
            ("diffuser", "off") => config.diffuser = false,
            ("diffuser", v) => return Err(bad(format!("diffuser={v:?}: expected on or off"))),
            (k, _) => {
                return Err(bad(format!(
                    "unknown option '{k}' (known: time_scale, seed, noise, rev, diffuser)"
                )))
            }
        }
    }
    let world = match &options.stimulus {
        Some(w) => w.clone(),
        None => Arc::new(SharedWorld::new(View::radiance(default_light())?)) as Arc<dyn World>,
    };
    let clock = Arc::new(ScaledClock::new(settings.time_scale));
    let (instrument, noise, pace) = sim_parts(world, config, options, clock)?;
    Ok(Simulated::wrap(instrument, noise, pace, settings))
}

/// The emulator with every setting given, for tests that inject faults or a clock.
pub fn sim_with(
    world: Arc<dyn World>,
    config: EmulatorConfig,
    options: &OpenOptions,
    clock: Arc<dyn Clock>,
) -> Result<Box<dyn Instrument>, DriverError> {
    sim_parts(world, config, options, clock).map(|(instrument, _, _)| instrument)
}

fn sim_parts(
    world: Arc<dyn World>,
    config: EmulatorConfig,
    options: &OpenOptions,
    clock: Arc<dyn Clock>,
) -> Result<(Box<dyn Instrument>, NoiseCursor, ManualClock), DriverError> {
    let device = I1ProEmulator::new(world, config).map_err(DriverError::Simulation)?;
    let noise = device.noise_cursor();
    let pace = device.real_pace_clock();
    let (host, _thread) = usb_pair(device, &sim_connection(MODEL));
    Ok((connect(host, options, clock, false)?, noise, pace))
}

/// Opens the driver on `link`, recording the session when asked; `settle` waits out a
/// real unit's power-up.
pub fn connect<L: UsbLink + 'static>(
    link: L,
    options: &OpenOptions,
    clock: Arc<dyn Clock>,
    settle: bool,
) -> Result<Box<dyn Instrument>, DriverError> {
    match &options.record {
        Some(path) => {
            let description = format!("metamer session with the i1Pro on {}", link.describe());
            let rec = RecordUsb::create(link, path, MODEL, "usb", &description)?;
            Ok(Box::new(I1Pro::open_with(rec, clock, settle)?))
        }
        None => Ok(Box::new(I1Pro::open_with(link, clock, settle)?)),
    }
}
