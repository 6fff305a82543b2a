//! Record: wraps any serial link and writes every exchange to a transcript that the replay
//! backend plays back. Each event is flushed as it happens, so a crash or a pulled cable
//! still leaves a transcript of everything up to the failure.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::time::{Duration, Instant};

use metamer_protocols::transcript::{self, Dir, Event, EventKind, Header};

use super::{LineSettings, LinkError, SerialLink};
use crate::DriverError;

/// A transcript being written, one flushed line per event.
pub struct TranscriptWriter {
    out: BufWriter<File>,
    file: String,
    start: Instant,
}

impl TranscriptWriter {
    /// Creates `path` and writes the header. An existing file is not overwritten: a
    /// recording is evidence, and losing one by a repeated command line would be a loss.
    pub fn create(path: &Path, header: &Header) -> Result<TranscriptWriter, DriverError> {
        let file = path.display().to_string();
        let f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)
            .map_err(|source| DriverError::File {
                file: file.clone(),
                source,
            })?;
        let mut w = TranscriptWriter {
            out: BufWriter::new(f),
            file,
            start: Instant::now(),
        };
        let line = serde_json::to_string(header).expect("a header serializes");
        w.line(&line).map_err(DriverError::Link)?;
        Ok(w)
    }

    /// Appends an event stamped with the time since the header was written.
    pub fn event(&mut self, kind: EventKind) -> Result<(), LinkError> {
        let mut event = Event::new(kind);
        event.t_ms = Some(self.start.elapsed().as_secs_f64() * 1e3);
        let line = transcript::event_line(&event);
        self.line(&line)
    }

    fn line(&mut self, line: &str) -> Result<(), LinkError> {
        let r = writeln!(self.out, "{line}").and_then(|()| self.out.flush());
        r.map_err(|source| LinkError::Record {
            file: self.file.clone(),
            source,
        })
    }
}

/// A serial link that records everything passing through `inner`.
pub struct RecordSerial<L: SerialLink> {
    inner: L,
    writer: TranscriptWriter,
}

impl<L: SerialLink> RecordSerial<L> {
    /// Records `inner` to a new file at `path`.
    pub fn create(
        inner: L,
        path: &Path,
        instrument: &str,
        description: &str,
    ) -> Result<RecordSerial<L>, DriverError> {
        let header = Header {
            format: transcript::FORMAT.into(),
            instrument: instrument.into(),
            transport: "serial".into(),
            settings: Some(serde_json::to_value(inner.settings()).expect("settings serialize")),
            origin: transcript::ORIGIN_RECORDED.into(),
            description: description.into(),
            expect: None,
        };
        let writer = TranscriptWriter::create(path, &header)?;
        Ok(RecordSerial { inner, writer })
    }

    /// The wrapped link.
    pub fn inner(&self) -> &L {
        &self.inner
    }
}

impl<L: SerialLink> SerialLink for RecordSerial<L> {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        let r = self.inner.write_all(bytes);
        // What the host sent is recorded even if the device is gone, so the transcript
        // shows the command that met the disconnect.
        self.writer.event(EventKind::Bytes {
            dir: Dir::Host,
            bytes: bytes.to_vec(),
        })?;
        if let Err(LinkError::Disconnected { .. }) = &r {
            self.writer.event(EventKind::Disconnect)?;
        }
        r
    }

    fn read_until(&mut self, terminator: &[u8], timeout: Duration) -> Result<Vec<u8>, LinkError> {
        let r = self.inner.read_until(terminator, timeout);
        let device = |bytes: &[u8]| EventKind::Bytes {
            dir: Dir::Device,
            bytes: bytes.to_vec(),
        };
        match &r {
            Ok(line) => self.writer.event(device(line))?,
            Err(LinkError::Timeout { received, .. }) => {
                if !received.is_empty() {
                    self.writer.event(device(received))?;
                }
                self.writer.event(EventKind::Timeout)?;
            }
            Err(LinkError::Disconnected { received }) => {
                if !received.is_empty() {
                    self.writer.event(device(received))?;
                }
                self.writer.event(EventKind::Disconnect)?;
            }
            Err(_) => {}
        }
        r
    }

    fn discard_input(&mut self) -> Result<(), LinkError> {
        self.inner.discard_input()
    }

    fn settings(&self) -> LineSettings {
        self.inner.settings()
    }

    fn set_settings(&mut self, settings: LineSettings) -> Result<(), LinkError> {
        self.inner.set_settings(settings)
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::pair::pair;
    use crate::link::replay::ReplaySerial;

    #[test]
    fn a_recording_replays_the_same_exchange() {
        let dir = std::env::temp_dir().join(format!("metamer-record-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("rec.jsonl");
        let _ = std::fs::remove_file(&path);
        let (host, mut dev) = pair(LineSettings::CS100A, "sim");
        let mut rec = RecordSerial::create(host, &path, "cs100a", "unit test").unwrap();
        let t = Duration::from_millis(200);
        rec.write_all(b"MES\r\n").unwrap();
        assert_eq!(dev.read_until(b"\r\n", t).unwrap(), b"MES\r\n");
        dev.write_all(b"OK00,  123.4, .3127, .3290\r\n").unwrap();
        let line = rec.read_until(b"\r\n", t).unwrap();
        rec.write_all(b"MES\r\n").unwrap();
        dev.write_all(b"OK\xff").unwrap();
        assert!(rec.read_until(b"\r\n", Duration::from_millis(20)).is_err());
        drop(rec);

        // A second recording to the same path must not clobber the first.
        let (host2, _dev2) = pair(LineSettings::CS100A, "sim");
        assert!(RecordSerial::create(host2, &path, "cs100a", "again").is_err());

        let mut replay = ReplaySerial::open(&path).unwrap();
        assert_eq!(replay.transcript().header.origin, "recorded");
        replay.write_all(b"MES\r\n").unwrap();
        assert_eq!(replay.read_until(b"\r\n", t).unwrap(), line);
        replay.write_all(b"MES\r\n").unwrap();
        match replay.read_until(b"\r\n", t) {
            Err(LinkError::Timeout { received, .. }) => assert_eq!(received, b"OK\xff"),
            other => panic!("{other:?}"),
        }
        replay.finish().unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains(r#""hex":"4f4bff""#), "{text}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
