//! Replay: a transcript plays the device, and the real driver runs against it byte for
//! byte. Whatever the driver writes must be exactly what the transcript's host events say;
//! a difference is an error naming the transcript line, what was expected and what was
//! written. Timeouts are events, not waits, so replays run at full speed.

use std::path::Path;
use std::time::Duration;

use metamer_protocols::transcript::{self, show_bytes, Dir, Event, EventKind, Header};

use super::{find_end, LineSettings, LinkError, SerialLink};
use crate::DriverError;

/// A transcript read from a file: the header and each event with its line number.
#[derive(Clone, Debug)]
pub struct Transcript {
    pub file: String,
    pub header: Header,
    pub events: Vec<(usize, Event)>,
}

impl Transcript {
    /// Reads and parses a transcript file.
    pub fn load(path: &Path) -> Result<Transcript, DriverError> {
        let file = path.display().to_string();
        let text = metamer_color::text::read_text(path).map_err(|source| DriverError::File {
            file: file.clone(),
            source,
        })?;
        Transcript::parse(&file, &text)
    }

    /// Parses transcript text; `file` names it in errors.
    pub fn parse(file: &str, text: &str) -> Result<Transcript, DriverError> {
        let err = |line: usize, message: String| DriverError::Transcript {
            file: file.to_string(),
            line,
            message,
        };
        let mut lines = metamer_color::text::strip_bom(text)
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l))
            .filter(|(_, l)| !l.trim().is_empty());
        let (n, first) = lines
            .next()
            .ok_or_else(|| err(1, "the file is empty; line 1 must be the header".into()))?;
        let header = transcript::parse_header(first).map_err(|e| err(n, e.to_string()))?;
        let events = lines
            .map(|(n, l)| {
                transcript::parse_event(l)
                    .map(|e| (n, e))
                    .map_err(|e| err(n, e.to_string()))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Transcript {
            file: file.to_string(),
            header,
            events,
        })
    }

    /// The serial line settings the header records, if it has them.
    pub fn line_settings(&self) -> Option<LineSettings> {
        self.header
            .settings
            .as_ref()
            .and_then(|v| serde_json::from_value(v.clone()).ok())
    }
}

/// A serial link that plays a transcript.
pub struct ReplaySerial {
    t: Transcript,
    /// Index of the next event to play.
    next: usize,
    /// Bytes of the current host event already matched.
    matched: usize,
    /// Device bytes delivered but not yet read.
    buffer: Vec<u8>,
    disconnected: bool,
    settings: LineSettings,
}

impl ReplaySerial {
    /// Replays `t`, which must be a serial transcript.
    pub fn new(t: Transcript) -> Result<ReplaySerial, DriverError> {
        if t.header.transport != "serial" {
            return Err(DriverError::Transcript {
                file: t.file.clone(),
                line: 1,
                message: format!(
                    "this is a {} transcript; a serial link cannot replay it",
                    t.header.transport
                ),
            });
        }
        let settings = t.line_settings().unwrap_or(LineSettings::CS100A);
        Ok(ReplaySerial {
            t,
            next: 0,
            matched: 0,
            buffer: Vec::new(),
            disconnected: false,
            settings,
        })
    }

    /// Opens and replays a transcript file.
    pub fn open(path: &Path) -> Result<ReplaySerial, DriverError> {
        ReplaySerial::new(Transcript::load(path)?)
    }

    /// The transcript being replayed.
    pub fn transcript(&self) -> &Transcript {
        &self.t
    }

    /// Checks that the driver played the whole transcript: an event left over means the
    /// driver stopped short of what the device session contained.
    pub fn finish(&self) -> Result<(), LinkError> {
        match self.t.events.get(self.next) {
            None => Ok(()),
            Some((line, event)) => Err(LinkError::Replay(format!(
                "transcript {} line {line}: the driver stopped, but the transcript goes on with {}",
                self.t.file,
                describe(&event.kind)
            ))),
        }
    }

    fn line_of_next(&self) -> usize {
        self.t
            .events
            .get(self.next)
            .map(|(n, _)| *n)
            .unwrap_or_else(|| self.t.events.last().map(|(n, _)| n + 1).unwrap_or(2))
    }
}

fn describe(kind: &EventKind) -> String {
    match kind {
        EventKind::Bytes {
            dir: Dir::Host,
            bytes,
        } => format!("the host sending {}", show_bytes(bytes)),
        EventKind::Bytes {
            dir: Dir::Device,
            bytes,
        } => format!("the device sending {}", show_bytes(bytes)),
        EventKind::Timeout => "a device timeout".into(),
        EventKind::Disconnect => "a disconnect".into(),
        other => format!("a USB event {other:?}"),
    }
}

impl SerialLink for ReplaySerial {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        if self.disconnected {
            return Err(LinkError::Disconnected {
                received: Vec::new(),
            });
        }
        let mut rest = bytes;
        while !rest.is_empty() {
            let line = self.line_of_next();
            let expected = match self.t.events.get(self.next).map(|(_, e)| &e.kind) {
                Some(EventKind::Bytes {
                    dir: Dir::Host,
                    bytes,
                }) => bytes.clone(),
                Some(other) => {
                    return Err(LinkError::Replay(format!(
                        "transcript {} line {line}: expected {}, but the driver wrote {}",
                        self.t.file,
                        describe(other),
                        show_bytes(bytes)
                    )))
                }
                None => {
                    return Err(LinkError::Replay(format!(
                        "transcript {} ended at line {line}, but the driver wrote {}",
                        self.t.file,
                        show_bytes(bytes)
                    )))
                }
            };
            let want = &expected[self.matched..];
            let n = want.len().min(rest.len());
            if want[..n] != rest[..n] {
                return Err(LinkError::Replay(format!(
                    "transcript {} line {line}: expected the host to send {}, but the driver wrote {}",
                    self.t.file,
                    show_bytes(&expected),
                    show_bytes(bytes)
                )));
            }
            self.matched += n;
            rest = &rest[n..];
            if self.matched == expected.len() {
                self.next += 1;
                self.matched = 0;
            }
        }
        Ok(())
    }

    fn read_until(&mut self, terminator: &[u8], timeout: Duration) -> Result<Vec<u8>, LinkError> {
        loop {
            if let Some(end) = find_end(&self.buffer, terminator) {
                return Ok(self.buffer.drain(..end).collect());
            }
            if self.disconnected {
                return Err(LinkError::Disconnected {
                    received: std::mem::take(&mut self.buffer),
                });
            }
            let line = self.line_of_next();
            if self.matched != 0 {
                return Err(LinkError::Replay(format!(
                    "transcript {} line {line}: the driver waited for a reply after writing only \
                     part of the host bytes on that line",
                    self.t.file
                )));
            }
            match self.t.events.get(self.next).map(|(_, e)| &e.kind) {
                Some(EventKind::Bytes {
                    dir: Dir::Device,
                    bytes,
                }) => {
                    self.buffer.extend_from_slice(bytes);
                    self.next += 1;
                }
                Some(EventKind::Timeout) => {
                    self.next += 1;
                    return Err(LinkError::Timeout {
                        timeout_ms: timeout.as_millis() as u64,
                        received: std::mem::take(&mut self.buffer),
                    });
                }
                Some(EventKind::Disconnect) => {
                    self.next += 1;
                    self.disconnected = true;
                }
                Some(other) => {
                    return Err(LinkError::Replay(format!(
                        "transcript {} line {line}: the driver waited for a reply, but the \
                         transcript expects {} first",
                        self.t.file,
                        describe(other)
                    )))
                }
                None => {
                    return Err(LinkError::Replay(format!(
                        "transcript {} ended at line {line} while the driver waited for a reply \
                         (received {} so far)",
                        self.t.file,
                        show_bytes(&self.buffer)
                    )))
                }
            }
        }
    }

    fn discard_input(&mut self) -> Result<(), LinkError> {
        // Only bytes already delivered are stale; later device events belong to later reads.
        self.buffer.clear();
        Ok(())
    }

    fn settings(&self) -> LineSettings {
        self.settings
    }

    fn set_settings(&mut self, settings: LineSettings) -> Result<(), LinkError> {
        if settings != self.settings {
            return Err(LinkError::Replay(format!(
                "transcript {} was recorded at {:?}; the driver asked for {:?}",
                self.t.file, self.settings, settings
            )));
        }
        Ok(())
    }

    fn describe(&self) -> String {
        crate::spec::words::replay_connection(&self.t.file)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = r#"{"format":"metamer-transcript/1","instrument":"cs100a","transport":"serial","settings":{"baud":4800,"data_bits":7,"parity":"even","stop_bits":2},"origin":"synthesized from the protocol documentation","description":"test"}"#;

    fn replay(events: &str) -> ReplaySerial {
        let text = format!("{HEADER}\n{events}");
        ReplaySerial::new(Transcript::parse("t.jsonl", &text).unwrap()).unwrap()
    }

    const T: Duration = Duration::from_secs(5);

    #[test]
    fn plays_a_session_and_joins_split_replies() {
        let mut r = replay(
            "{\"dir\":\"host\",\"data\":\"MES\\r\\n\"}\n\
             {\"dir\":\"device\",\"data\":\"OK00,  12\"}\n\
             {\"dir\":\"device\",\"data\":\"3.4, .3127, .3290\\r\\n\"}\n",
        );
        assert_eq!(r.settings(), LineSettings::CS100A);
        r.write_all(b"ME").unwrap();
        r.write_all(b"S\r\n").unwrap();
        assert_eq!(
            r.read_until(b"\r\n", T).unwrap(),
            b"OK00,  123.4, .3127, .3290\r\n"
        );
        r.finish().unwrap();
    }

    #[test]
    fn a_wrong_write_names_line_expected_and_written() {
        let mut r = replay("{\"dir\":\"host\",\"data\":\"MDS,04\\r\\n\"}\n");
        let e = r.write_all(b"MDS,07\r\n").unwrap_err().to_string();
        assert_eq!(
            e,
            "transcript t.jsonl line 2: expected the host to send \"MDS,04\\r\\n\", but the driver \
             wrote \"MDS,07\\r\\n\""
        );
    }

    #[test]
    fn timeouts_disconnects_and_the_end_are_reported() {
        let mut r = replay(
            "{\"dir\":\"host\",\"data\":\"MES\\r\\n\"}\n\
             {\"dir\":\"device\",\"timeout\":true}\n\
             {\"dir\":\"host\",\"data\":\"MES\\r\\n\"}\n\
             {\"dir\":\"device\",\"data\":\"OK0\"}\n\
             {\"dir\":\"device\",\"disconnect\":true}\n",
        );
        r.write_all(b"MES\r\n").unwrap();
        assert!(matches!(
            r.read_until(b"\r\n", T),
            Err(LinkError::Timeout { received, .. }) if received.is_empty()
        ));
        assert!(r.finish().is_err());
        r.write_all(b"MES\r\n").unwrap();
        assert!(matches!(
            r.read_until(b"\r\n", T),
            Err(LinkError::Disconnected { received }) if received == b"OK0"
        ));
        r.finish().unwrap();
        assert!(matches!(
            r.write_all(b"MES\r\n"),
            Err(LinkError::Disconnected { .. })
        ));
    }

    #[test]
    fn reading_past_the_end_names_the_line() {
        let mut r = replay("{\"dir\":\"host\",\"data\":\"MES\\r\\n\"}\n");
        r.write_all(b"MES\r\n").unwrap();
        let e = r.read_until(b"\r\n", T).unwrap_err().to_string();
        assert!(e.contains("t.jsonl ended at line 3"), "{e}");
        let e = r.write_all(b"CLE\r\n").unwrap_err().to_string();
        assert!(e.contains("ended at line 3") && e.contains("CLE"), "{e}");
    }

    #[test]
    fn bad_transcript_lines_are_located() {
        let text = format!("{HEADER}\n{{\"dir\":\"host\"}}\n");
        let e = Transcript::parse("t.jsonl", &text).unwrap_err().to_string();
        assert!(e.starts_with("transcript t.jsonl line 2:"), "{e}");
    }
}
