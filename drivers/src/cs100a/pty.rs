//! The emulator on a pseudo-terminal: the emulator answers on the master side, and anything
//! that opens [`PtyEmulator::path`] — the real `serialport` backend included — talks to it
//! as to a meter on a serial port.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;

use serialport::SerialPort;

use super::emulator::Cs100aEmulator;
use crate::link::serial::PortLink;
use crate::link::LineSettings;
use crate::DriverError;

/// A running emulator on a pty; dropping it stops the emulator.
pub struct PtyEmulator {
    path: String,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    // Keeps the slave side open: with no slave open a pty master's reads fail (EIO on
    // Linux), so the emulator would see a hang-up before the client has even opened it.
    _slave: serialport::TTYPort,
}

impl PtyEmulator {
    /// Starts `emulator` on a new pseudo-terminal.
    pub fn start(emulator: Cs100aEmulator) -> Result<PtyEmulator, DriverError> {
        let (master, slave) = serialport::TTYPort::pair().map_err(|e| {
            DriverError::Simulation(format!("cannot create a pseudo-terminal: {e}"))
        })?;
        let path = slave
            .name()
            .ok_or_else(|| DriverError::Simulation("the pseudo-terminal has no name".into()))?;
        let link = PortLink::from_port(Box::new(master), "pty master", LineSettings::CS100A);
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::Builder::new()
            .name("cs100a-pty-emulator".into())
            .spawn(move || emulator.serve(link, &flag))
            .map_err(|e| DriverError::Simulation(format!("cannot start the emulator: {e}")))?;
        Ok(PtyEmulator {
            path,
            stop,
            thread: Some(thread),
            _slave: slave,
        })
    }

    /// The device path to open (`/dev/pts/N`).
    pub fn path(&self) -> &str {
        &self.path
    }
}

impl Drop for PtyEmulator {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
