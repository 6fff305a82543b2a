//! Links: the byte pipes drivers talk through. A driver is generic over its link, so the
//! real port, a replayed transcript, a recording wrapper and an in-process emulator all run
//! the same driver code.

pub mod pair;
pub mod record;
pub mod replay;
pub mod serial;
pub mod usb;
pub mod usb_pair;
pub mod usb_real;

use std::time::Duration;

use serde::{Deserialize, Serialize};

/// Parity of a serial line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Parity {
    None,
    Even,
    Odd,
}

/// Serial line settings, in the shape transcript headers store them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct LineSettings {
    pub baud: u32,
    pub data_bits: u8,
    pub parity: Parity,
    pub stop_bits: u8,
}

impl LineSettings {
    /// The CS-100A's line: 4800 baud 7E2 (PP, MC2, VCC, MF, PGL agree; [C2]).
    pub const CS100A: LineSettings = LineSettings {
        baud: 4800,
        data_bits: 7,
        parity: Parity::Even,
        stop_bits: 2,
    };

    /// Time one character takes on the wire (start + data + parity + stop bits).
    pub fn char_time(&self) -> Duration {
        let bits = 1
            + self.data_bits as u32
            + u32::from(self.parity != Parity::None)
            + self.stop_bits as u32;
        Duration::from_secs_f64(bits as f64 / self.baud as f64)
    }
}

/// What can go wrong on a link. Timeouts and disconnects carry the bytes that did arrive,
/// so a driver can tell "silent" from "stopped half-way".
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    #[error(
        "no reply within {timeout_ms} ms (received {})",
        metamer_protocols::transcript::show_bytes(received)
    )]
    Timeout { timeout_ms: u64, received: Vec<u8> },
    #[error(
        "the device disconnected (received {} before it went)",
        metamer_protocols::transcript::show_bytes(received)
    )]
    Disconnected { received: Vec<u8> },
    /// The simulated device's thread panicked: a bug in the simulation, not a cable.
    #[error(
        "the simulated device on {link} failed: its thread panicked ({message}); this is a \
         bug in metamer's simulation, not a problem with a cable or an instrument"
    )]
    PeerPanicked { link: String, message: String },
    /// The device refused a USB transfer by stalling the endpoint (0x00 for control
    /// transfers): a request it does not support, or one it cannot take in its state.
    #[error("the device stalled endpoint 0x{endpoint:02x} (it refused the request)")]
    Stalled { endpoint: u8 },
    #[error("I/O error on {port}: {source}")]
    Io {
        port: String,
        #[source]
        source: std::io::Error,
    },
    /// The driver did something the transcript being replayed does not contain.
    #[error("{0}")]
    Replay(String),
    /// The recording file could not be written; the measurement itself is not affected.
    #[error("cannot write the recording {file}: {source}")]
    Record {
        file: String,
        #[source]
        source: std::io::Error,
    },
}

/// The message of a caught panic, for [`LinkError::PeerPanicked`].
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".to_string()
    }
}

/// Seconds as a `Duration` for any float: NaN and negatives are no time, and a value too
/// large to represent (a scaled delay, a timeout computed from a device's parameters) is the
/// longest `Duration`, where `Duration::from_secs_f64` would panic.
pub fn duration_s(seconds: f64) -> Duration {
    if seconds.is_nan() || seconds <= 0.0 {
        return Duration::ZERO;
    }
    Duration::try_from_secs_f64(seconds).unwrap_or(Duration::MAX)
}

/// A serial byte pipe with line-oriented reads.
pub trait SerialLink: Send {
    /// Writes all bytes and flushes them to the device.
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LinkError>;
    /// Reads until `terminator` has arrived and returns everything up to and including it;
    /// bytes after the terminator stay buffered for the next read. On timeout or disconnect
    /// the error carries what arrived.
    fn read_until(&mut self, terminator: &[u8], timeout: Duration) -> Result<Vec<u8>, LinkError>;
    /// Discards input that arrived but was not read (stale bytes of an earlier reply).
    fn discard_input(&mut self) -> Result<(), LinkError>;
    /// The line settings in force.
    fn settings(&self) -> LineSettings;
    /// Changes the line settings.
    fn set_settings(&mut self, settings: LineSettings) -> Result<(), LinkError>;
    /// Where the link goes, for messages: `/dev/ttyUSB0`, `replay:FILE`, `sim`.
    fn describe(&self) -> String;
    /// Called by a simulated device's thread whose serving code panicked, before the link is
    /// dropped, so the other end reports the panic instead of a disconnected cable. Links
    /// with no simulated peer ignore it.
    fn report_panic(&mut self, _message: &str) {}
}

impl<L: SerialLink + ?Sized> SerialLink for &mut L {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        (**self).write_all(bytes)
    }
    fn read_until(&mut self, terminator: &[u8], timeout: Duration) -> Result<Vec<u8>, LinkError> {
        (**self).read_until(terminator, timeout)
    }
    fn discard_input(&mut self) -> Result<(), LinkError> {
        (**self).discard_input()
    }
    fn settings(&self) -> LineSettings {
        (**self).settings()
    }
    fn set_settings(&mut self, settings: LineSettings) -> Result<(), LinkError> {
        (**self).set_settings(settings)
    }
    fn describe(&self) -> String {
        (**self).describe()
    }
    fn report_panic(&mut self, message: &str) {
        (**self).report_panic(message)
    }
}

impl<L: SerialLink + ?Sized> SerialLink for Box<L> {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        (**self).write_all(bytes)
    }
    fn read_until(&mut self, terminator: &[u8], timeout: Duration) -> Result<Vec<u8>, LinkError> {
        (**self).read_until(terminator, timeout)
    }
    fn discard_input(&mut self) -> Result<(), LinkError> {
        (**self).discard_input()
    }
    fn settings(&self) -> LineSettings {
        (**self).settings()
    }
    fn set_settings(&mut self, settings: LineSettings) -> Result<(), LinkError> {
        (**self).set_settings(settings)
    }
    fn describe(&self) -> String {
        (**self).describe()
    }
    fn report_panic(&mut self, message: &str) {
        (**self).report_panic(message)
    }
}

/// Finds `needle` in `haystack`; the index just past it.
pub(crate) fn find_end(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    if needle.is_empty() {
        return Some(0);
    }
    haystack
        .windows(needle.len())
        .position(|w| w == needle)
        .map(|i| i + needle.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn any_float_becomes_a_duration_without_panicking() {
        assert_eq!(duration_s(1.5), Duration::from_millis(1500));
        assert_eq!(duration_s(f64::NAN), Duration::ZERO);
        assert_eq!(duration_s(-3.0), Duration::ZERO);
        assert_eq!(duration_s(1e308), Duration::MAX);
        assert_eq!(duration_s(f64::INFINITY), Duration::MAX);
    }

    #[test]
    fn cs100a_character_takes_eleven_bit_times() {
        // 1 start + 7 data + 1 parity + 2 stop = 11 bits at 4800 baud (protocols/cs100a/README.md, "Line and framing").
        let t = LineSettings::CS100A.char_time().as_secs_f64();
        assert!((t - 11.0 / 4800.0).abs() < 1e-9);
    }

    #[test]
    fn find_end_returns_index_past_the_needle() {
        assert_eq!(find_end(b"OK00\r\nxx", b"\r\n"), Some(6));
        assert_eq!(find_end(b"OK00\r", b"\r\n"), None);
    }
}
