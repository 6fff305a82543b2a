//! An in-process serial pair: two connected ends, one for the driver, one for an emulator
//! running on another thread. Dropping one end is a disconnect for the other.

use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::{find_end, LineSettings, LinkError, SerialLink};

/// One end of an in-process serial pair.
pub struct PairEnd {
    tx: Sender<Vec<u8>>,
    rx: Receiver<Vec<u8>>,
    buffer: Vec<u8>,
    settings: LineSettings,
    name: String,
    /// Shared by both ends: why the other end's thread panicked, if it did.
    panic: Arc<Mutex<Option<String>>>,
}

/// Two connected ends with the given line settings; `name` is what messages call the link.
pub fn pair(settings: LineSettings, name: &str) -> (PairEnd, PairEnd) {
    let (tx_a, rx_b) = mpsc::channel();
    let (tx_b, rx_a) = mpsc::channel();
    let panic = Arc::new(Mutex::new(None));
    let end = |tx, rx| PairEnd {
        tx,
        rx,
        buffer: Vec::new(),
        settings,
        name: name.to_string(),
        panic: Arc::clone(&panic),
    };
    (end(tx_a, rx_a), end(tx_b, rx_b))
}

impl PairEnd {
    /// A disconnect, or the other end's panic when that is why it went.
    fn gone(&self, received: Vec<u8>) -> LinkError {
        let panic = self.panic.lock().map(|p| p.clone()).unwrap_or(None);
        match panic {
            Some(message) => LinkError::PeerPanicked {
                link: self.name.clone(),
                message,
            },
            None => LinkError::Disconnected { received },
        }
    }
}

impl SerialLink for PairEnd {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.tx
            .send(bytes.to_vec())
            .map_err(|_| self.gone(Vec::new()))
    }

    fn read_until(&mut self, terminator: &[u8], timeout: Duration) -> Result<Vec<u8>, LinkError> {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some(end) = find_end(&self.buffer, terminator) {
                return Ok(self.buffer.drain(..end).collect());
            }
            let left = deadline.saturating_duration_since(Instant::now());
            match self.rx.recv_timeout(left) {
                Ok(bytes) => self.buffer.extend_from_slice(&bytes),
                Err(RecvTimeoutError::Timeout) => {
                    return Err(LinkError::Timeout {
                        timeout_ms: timeout.as_millis() as u64,
                        received: std::mem::take(&mut self.buffer),
                    })
                }
                Err(RecvTimeoutError::Disconnected) => {
                    let received = std::mem::take(&mut self.buffer);
                    return Err(self.gone(received));
                }
            }
        }
    }

    fn discard_input(&mut self) -> Result<(), LinkError> {
        self.buffer.clear();
        while let Ok(bytes) = self.rx.try_recv() {
            drop(bytes);
        }
        Ok(())
    }

    fn settings(&self) -> LineSettings {
        self.settings
    }

    fn set_settings(&mut self, settings: LineSettings) -> Result<(), LinkError> {
        self.settings = settings;
        Ok(())
    }

    fn describe(&self) -> String {
        self.name.clone()
    }

    fn report_panic(&mut self, message: &str) {
        if let Ok(mut slot) = self.panic.lock() {
            *slot = Some(message.to_string());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_cross_and_lines_split_at_the_terminator() {
        let (mut a, mut b) = pair(LineSettings::CS100A, "test");
        a.write_all(b"OK").unwrap();
        a.write_all(b"00\r\nER10\r\n").unwrap();
        let t = Duration::from_millis(100);
        assert_eq!(b.read_until(b"\r\n", t).unwrap(), b"OK00\r\n");
        assert_eq!(b.read_until(b"\r\n", t).unwrap(), b"ER10\r\n");
        a.write_all(b"OK0").unwrap();
        match b.read_until(b"\r\n", Duration::from_millis(10)) {
            Err(LinkError::Timeout { received, .. }) => assert_eq!(received, b"OK0"),
            other => panic!("{other:?}"),
        }
        a.write_all(b"OK").unwrap();
        drop(a);
        match b.read_until(b"\r\n", t) {
            Err(LinkError::Disconnected { received }) => assert_eq!(received, b"OK"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_panicked_peer_is_reported_as_a_panic_not_a_disconnect() {
        let (mut host, mut device) = pair(LineSettings::CS100A, "sim:test");
        device.report_panic("attempt to divide by zero");
        drop(device);
        let e = host
            .read_until(b"\r\n", Duration::from_millis(10))
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "the simulated device on sim:test failed: its thread panicked (attempt to divide by \
             zero); this is a bug in metamer's simulation, not a problem with a cable or an \
             instrument"
        );
        assert!(matches!(
            host.write_all(b"MES\r\n"),
            Err(LinkError::PeerPanicked { .. })
        ));
    }
}
