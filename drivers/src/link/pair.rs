//! An in-process serial pair: two connected ends, one for the driver, one for an emulator
//! running on another thread. Dropping one end is a disconnect for the other.

use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

use super::{find_end, LineSettings, LinkError, SerialLink};

/// One end of an in-process serial pair.
pub struct PairEnd {
    tx: Sender<Vec<u8>>,
    rx: Receiver<Vec<u8>>,
    buffer: Vec<u8>,
    settings: LineSettings,
    name: String,
}

/// Two connected ends with the given line settings; `name` is what messages call the link.
pub fn pair(settings: LineSettings, name: &str) -> (PairEnd, PairEnd) {
    let (tx_a, rx_b) = mpsc::channel();
    let (tx_b, rx_a) = mpsc::channel();
    let end = |tx, rx| PairEnd {
        tx,
        rx,
        buffer: Vec::new(),
        settings,
        name: name.to_string(),
    };
    (end(tx_a, rx_a), end(tx_b, rx_b))
}

impl SerialLink for PairEnd {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.tx
            .send(bytes.to_vec())
            .map_err(|_| LinkError::Disconnected {
                received: Vec::new(),
            })
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
                    return Err(LinkError::Disconnected {
                        received: std::mem::take(&mut self.buffer),
                    })
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
}
