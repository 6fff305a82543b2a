//! The real serial backend (`serialport`), for USB-serial adapters, built-in ports and
//! pseudo-terminals alike.

use std::io::{Read, Write};
use std::time::{Duration, Instant};

use super::{find_end, LineSettings, LinkError, Parity, SerialLink};
use crate::DriverError;

/// A serial port opened with `serialport`.
pub struct PortLink {
    port: Box<dyn serialport::SerialPort>,
    name: String,
    buffer: Vec<u8>,
    settings: LineSettings,
}

impl PortLink {
    /// Opens `path` with `settings`; errors say how to fix permissions and busy ports.
    pub fn open(path: &str, settings: LineSettings) -> Result<PortLink, DriverError> {
        let builder = serialport::new(path, settings.baud)
            .data_bits(data_bits(settings.data_bits))
            .parity(parity(settings.parity))
            .stop_bits(stop_bits(settings.stop_bits))
            .flow_control(serialport::FlowControl::None)
            .timeout(Duration::from_millis(100));
        let port = builder.open().map_err(|e| open_error(path, e))?;
        let mut link = PortLink::from_port(port, path, settings);
        // The meter only sends while its CTS input (our RTS) is high (LS-100 manual [C];
        // VCC checks it for the CS-100A [C2]), so assert RTS and DTR. A pseudo-terminal has
        // no modem lines and refuses: that is harmless, so the result is ignored.
        let _ = link.port.write_request_to_send(true);
        let _ = link.port.write_data_terminal_ready(true);
        Ok(link)
    }

    /// Wraps a port opened elsewhere (the master side of a pseudo-terminal, for emulators).
    pub fn from_port(
        port: Box<dyn serialport::SerialPort>,
        name: &str,
        settings: LineSettings,
    ) -> PortLink {
        PortLink {
            port,
            name: name.to_string(),
            buffer: Vec::new(),
            settings,
        }
    }

    /// The line settings as the OS reports them now (to check that a port took 7E2).
    pub fn os_settings(&self) -> Result<LineSettings, LinkError> {
        let read = || -> serialport::Result<LineSettings> {
            Ok(LineSettings {
                baud: self.port.baud_rate()?,
                data_bits: match self.port.data_bits()? {
                    serialport::DataBits::Five => 5,
                    serialport::DataBits::Six => 6,
                    serialport::DataBits::Seven => 7,
                    serialport::DataBits::Eight => 8,
                },
                parity: match self.port.parity()? {
                    serialport::Parity::None => Parity::None,
                    serialport::Parity::Even => Parity::Even,
                    serialport::Parity::Odd => Parity::Odd,
                },
                stop_bits: match self.port.stop_bits()? {
                    serialport::StopBits::One => 1,
                    serialport::StopBits::Two => 2,
                },
            })
        };
        read().map_err(|e| self.io(e.into()))
    }

    /// An I/O failure as a link error: a hang-up (the adapter unplugged, the pty peer gone)
    /// is a disconnect, anything else an I/O error naming the port.
    fn io(&self, source: std::io::Error) -> LinkError {
        if is_disconnect(&source) {
            LinkError::Disconnected {
                received: Vec::new(),
            }
        } else {
            LinkError::Io {
                port: self.name.clone(),
                source,
            }
        }
    }
}

/// Maps an open failure to the error a user can act on.
pub fn open_error(path: &str, e: serialport::Error) -> DriverError {
    use serialport::ErrorKind;
    let port = path.to_string();
    match e.kind() {
        ErrorKind::Io(std::io::ErrorKind::PermissionDenied) => DriverError::PortPermission { port },
        ErrorKind::Io(std::io::ErrorKind::NotFound) => DriverError::PortNotFound { port },
        // serialport reports EBUSY (TIOCEXCL held by another process) as NoDevice.
        ErrorKind::NoDevice if std::path::Path::new(path).exists() => {
            DriverError::PortBusy { port }
        }
        ErrorKind::NoDevice => DriverError::PortNotFound { port },
        _ => DriverError::PortOpen {
            port,
            message: e.to_string(),
        },
    }
}

fn data_bits(n: u8) -> serialport::DataBits {
    match n {
        5 => serialport::DataBits::Five,
        6 => serialport::DataBits::Six,
        7 => serialport::DataBits::Seven,
        _ => serialport::DataBits::Eight,
    }
}

fn parity(p: Parity) -> serialport::Parity {
    match p {
        Parity::None => serialport::Parity::None,
        Parity::Even => serialport::Parity::Even,
        Parity::Odd => serialport::Parity::Odd,
    }
}

fn stop_bits(n: u8) -> serialport::StopBits {
    if n == 2 {
        serialport::StopBits::Two
    } else {
        serialport::StopBits::One
    }
}

fn is_disconnect(e: &std::io::Error) -> bool {
    // A vanished USB adapter or a closed pty peer shows up as POLLHUP (BrokenPipe), EIO
    // (Other) or ENXIO, depending on the driver.
    matches!(
        e.kind(),
        std::io::ErrorKind::BrokenPipe
            | std::io::ErrorKind::UnexpectedEof
            | std::io::ErrorKind::NotConnected
            | std::io::ErrorKind::Other
    ) || e.raw_os_error() == Some(libc_enxio())
}

const fn libc_enxio() -> i32 {
    6 // ENXIO on Linux and the BSDs.
}

impl SerialLink for PortLink {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        let r = self.port.write_all(bytes).and_then(|()| self.port.flush());
        r.map_err(|e| self.io(e))
    }

    fn read_until(&mut self, terminator: &[u8], timeout: Duration) -> Result<Vec<u8>, LinkError> {
        let deadline = Instant::now() + timeout;
        let mut chunk = [0u8; 256];
        loop {
            if let Some(end) = find_end(&self.buffer, terminator) {
                return Ok(self.buffer.drain(..end).collect());
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err(LinkError::Timeout {
                    timeout_ms: timeout.as_millis() as u64,
                    received: std::mem::take(&mut self.buffer),
                });
            }
            self.port.set_timeout(left).map_err(|e| self.io(e.into()))?;
            match self.port.read(&mut chunk) {
                Ok(0) => {
                    return Err(LinkError::Disconnected {
                        received: std::mem::take(&mut self.buffer),
                    })
                }
                Ok(n) => self.buffer.extend_from_slice(&chunk[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) if is_disconnect(&e) => {
                    return Err(LinkError::Disconnected {
                        received: std::mem::take(&mut self.buffer),
                    })
                }
                Err(e) => return Err(self.io(e)),
            }
        }
    }

    fn discard_input(&mut self) -> Result<(), LinkError> {
        self.buffer.clear();
        self.port
            .clear(serialport::ClearBuffer::Input)
            .map_err(|e| self.io(e.into()))
    }

    fn settings(&self) -> LineSettings {
        self.settings
    }

    fn set_settings(&mut self, settings: LineSettings) -> Result<(), LinkError> {
        let r = self
            .port
            .set_baud_rate(settings.baud)
            .and_then(|()| self.port.set_data_bits(data_bits(settings.data_bits)))
            .and_then(|()| self.port.set_parity(parity(settings.parity)))
            .and_then(|()| self.port.set_stop_bits(stop_bits(settings.stop_bits)));
        r.map_err(|e| self.io(e.into()))?;
        self.settings = settings;
        Ok(())
    }

    fn describe(&self) -> String {
        self.name.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_port_is_reported_as_missing() {
        let e = match PortLink::open("/dev/metamer-no-such-port", LineSettings::CS100A) {
            Err(e) => e,
            Ok(_) => panic!("opened a port that does not exist"),
        };
        assert!(matches!(e, DriverError::PortNotFound { .. }), "{e:?}");
        assert!(e.to_string().contains("metamer devices"));
    }

    #[test]
    fn permission_denied_names_the_fix() {
        let e = open_error(
            "/dev/ttyUSB0",
            serialport::Error::new(
                serialport::ErrorKind::Io(std::io::ErrorKind::PermissionDenied),
                "Permission denied",
            ),
        );
        let msg = e.to_string();
        assert!(msg.contains("/dev/ttyUSB0"), "{msg}");
        assert!(
            msg.contains("dialout") && msg.contains("60-metamer.rules"),
            "{msg}"
        );
    }
}
