//! USB and HID links, declared for the i1Pro driver: the driver will be generic over
//! [`UsbLink`] / [`HidLink`] like the CS-100A is over `SerialLink`. Replay and record
//! backends use the same transcript format as serial links (`control_in`, `bulk_out`, …
//! events; HID reports are `host`/`device` byte events whose first byte is the report id).

use std::path::Path;
use std::time::Duration;

use metamer_protocols::transcript::{self, show_bytes, Dir, EventKind, Header, TransferKind};

use super::record::TranscriptWriter;
use super::replay::Transcript;
use super::LinkError;
use crate::DriverError;

/// A USB control transfer's setup fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ControlSetup {
    pub request_type: u8,
    pub request: u8,
    pub value: u16,
    pub index: u16,
}

/// A claimed USB interface.
pub trait UsbLink: Send {
    /// Control transfer device → host; returns at most `len` bytes.
    fn control_in(
        &mut self,
        setup: ControlSetup,
        len: usize,
        timeout: Duration,
    ) -> Result<Vec<u8>, LinkError>;
    /// Control transfer host → device.
    fn control_out(
        &mut self,
        setup: ControlSetup,
        data: &[u8],
        timeout: Duration,
    ) -> Result<(), LinkError>;
    /// Bulk or interrupt read of at most `len` bytes from `endpoint`.
    fn read(
        &mut self,
        kind: TransferKind,
        endpoint: u8,
        len: usize,
        timeout: Duration,
    ) -> Result<Vec<u8>, LinkError>;
    /// Bulk or interrupt write to `endpoint`.
    fn write(
        &mut self,
        kind: TransferKind,
        endpoint: u8,
        data: &[u8],
        timeout: Duration,
    ) -> Result<(), LinkError>;
    /// For messages: `usb:0765:d094`, `replay:FILE`.
    fn describe(&self) -> String;
}

/// An opened HID device.
pub trait HidLink: Send {
    /// Writes an output report (first byte: report id, 0 when the device uses none).
    fn write_report(&mut self, report: &[u8]) -> Result<(), LinkError>;
    /// Reads one input report of at most `len` bytes.
    fn read_report(&mut self, len: usize, timeout: Duration) -> Result<Vec<u8>, LinkError>;
    fn describe(&self) -> String;
}

/// Plays a USB or HID transcript.
pub struct ReplayUsb {
    t: Transcript,
    next: usize,
}

impl ReplayUsb {
    /// Replays `t` (transport `usb` or `hid`).
    pub fn new(t: Transcript) -> Result<ReplayUsb, DriverError> {
        if t.header.transport != "usb" && t.header.transport != "hid" {
            return Err(DriverError::Transcript {
                file: t.file.clone(),
                line: 1,
                message: format!(
                    "this is a {} transcript; a USB or HID link cannot replay it",
                    t.header.transport
                ),
            });
        }
        Ok(ReplayUsb { t, next: 0 })
    }

    /// Checks that the whole transcript was played.
    pub fn finish(&self) -> Result<(), LinkError> {
        match self.t.events.get(self.next) {
            None => Ok(()),
            // A device that went away ends its transcript; every transfer after it failed.
            Some((_, e))
                if e.kind == EventKind::Disconnect && self.next + 1 == self.t.events.len() =>
            {
                Ok(())
            }
            Some((line, e)) => Err(LinkError::Replay(format!(
                "transcript {} line {line}: the driver stopped, but the transcript goes on with {:?}",
                self.t.file, e.kind
            ))),
        }
    }

    /// Takes the next event if `check` accepts it; otherwise an error naming the line,
    /// the expected event and what the driver did.
    fn take(
        &mut self,
        did: &str,
        check: impl Fn(&EventKind) -> bool,
    ) -> Result<EventKind, LinkError> {
        match self.t.events.get(self.next) {
            Some((_, e)) if check(&e.kind) => {
                self.next += 1;
                Ok(e.kind.clone())
            }
            Some((_, e)) if e.kind == EventKind::Disconnect => Err(LinkError::Disconnected {
                received: Vec::new(),
            }),
            Some((_, e)) if e.kind == EventKind::Timeout => {
                self.next += 1;
                Err(LinkError::Timeout {
                    timeout_ms: 0,
                    received: Vec::new(),
                })
            }
            Some((line, e)) => Err(LinkError::Replay(format!(
                "transcript {} line {line}: expected {:?}, but the driver did {did}",
                self.t.file, e.kind
            ))),
            None => Err(LinkError::Replay(format!(
                "transcript {} ended, but the driver did {did}",
                self.t.file
            ))),
        }
    }
}

impl UsbLink for ReplayUsb {
    fn control_in(
        &mut self,
        setup: ControlSetup,
        len: usize,
        _timeout: Duration,
    ) -> Result<Vec<u8>, LinkError> {
        let did = format!("control_in {setup:?} of {len} bytes");
        match self.take(
            &did,
            |k| matches!(k, EventKind::Control { dir_in: true, .. } if control_matches(k, setup)),
        )? {
            EventKind::Control { bytes, .. } => Ok(bytes),
            _ => unreachable!("take checked the kind"),
        }
    }

    fn control_out(
        &mut self,
        setup: ControlSetup,
        data: &[u8],
        _timeout: Duration,
    ) -> Result<(), LinkError> {
        let did = format!("control_out {setup:?} with {}", show_bytes(data));
        self.take(&did, |k| {
            matches!(k, EventKind::Control { dir_in: false, bytes, .. } if bytes == data && control_matches(k, setup))
        })
        .map(|_| ())
    }

    fn read(
        &mut self,
        kind: TransferKind,
        endpoint: u8,
        len: usize,
        _timeout: Duration,
    ) -> Result<Vec<u8>, LinkError> {
        let did = format!("{kind:?} read of {len} bytes from endpoint 0x{endpoint:02x}");
        match self.take(&did, |k| {
            matches!(k, EventKind::Transfer { kind: tk, dir_in: true, endpoint: ep, .. } if *tk == kind && *ep == endpoint)
        })? {
            EventKind::Transfer { bytes, .. } => Ok(bytes),
            _ => unreachable!("take checked the kind"),
        }
    }

    fn write(
        &mut self,
        kind: TransferKind,
        endpoint: u8,
        data: &[u8],
        _timeout: Duration,
    ) -> Result<(), LinkError> {
        let did = format!(
            "{kind:?} write of {} to endpoint 0x{endpoint:02x}",
            show_bytes(data)
        );
        self.take(&did, |k| {
            matches!(k, EventKind::Transfer { kind: tk, dir_in: false, endpoint: ep, bytes } if *tk == kind && *ep == endpoint && bytes == data)
        })
        .map(|_| ())
    }

    fn describe(&self) -> String {
        crate::spec::words::replay_connection(&self.t.file)
    }
}

impl HidLink for ReplayUsb {
    fn write_report(&mut self, report: &[u8]) -> Result<(), LinkError> {
        let did = format!("HID write of {}", show_bytes(report));
        self.take(
            &did,
            |k| matches!(k, EventKind::Bytes { dir: Dir::Host, bytes } if bytes == report),
        )
        .map(|_| ())
    }

    fn read_report(&mut self, len: usize, _timeout: Duration) -> Result<Vec<u8>, LinkError> {
        let did = format!("HID read of {len} bytes");
        match self.take(&did, |k| {
            matches!(
                k,
                EventKind::Bytes {
                    dir: Dir::Device,
                    ..
                }
            )
        })? {
            EventKind::Bytes { bytes, .. } => Ok(bytes),
            _ => unreachable!("take checked the kind"),
        }
    }

    fn describe(&self) -> String {
        crate::spec::words::replay_connection(&self.t.file)
    }
}

fn control_matches(kind: &EventKind, s: ControlSetup) -> bool {
    matches!(kind, EventKind::Control { request_type, request, value, index, .. }
        if *request_type == s.request_type && *request == s.request && *value == s.value && *index == s.index)
}

/// Records a USB or HID link.
pub struct RecordUsb<L> {
    inner: L,
    writer: TranscriptWriter,
}

impl<L> RecordUsb<L> {
    /// Records `inner` to a new file; `transport` is `usb` or `hid`.
    pub fn create(
        inner: L,
        path: &Path,
        instrument: &str,
        transport: &str,
        description: &str,
    ) -> Result<RecordUsb<L>, DriverError> {
        let header = Header {
            format: transcript::FORMAT.into(),
            instrument: instrument.into(),
            transport: transport.into(),
            settings: None,
            origin: transcript::ORIGIN_RECORDED.into(),
            description: description.into(),
            expect: None,
        };
        Ok(RecordUsb {
            inner,
            writer: TranscriptWriter::create(path, &header)?,
        })
    }

    fn outcome<T>(
        &mut self,
        r: &Result<T, LinkError>,
        ok: impl FnOnce(&T) -> EventKind,
    ) -> Result<(), LinkError> {
        match r {
            Ok(v) => self.writer.event(ok(v)),
            Err(LinkError::Timeout { .. }) => self.writer.event(EventKind::Timeout),
            Err(LinkError::Disconnected { .. }) => self.writer.event(EventKind::Disconnect),
            Err(_) => Ok(()),
        }
    }
}

fn control(dir_in: bool, s: ControlSetup, bytes: Vec<u8>) -> EventKind {
    EventKind::Control {
        dir_in,
        request_type: s.request_type,
        request: s.request,
        value: s.value,
        index: s.index,
        bytes,
    }
}

impl<L: UsbLink> UsbLink for RecordUsb<L> {
    fn control_in(
        &mut self,
        setup: ControlSetup,
        len: usize,
        timeout: Duration,
    ) -> Result<Vec<u8>, LinkError> {
        let r = self.inner.control_in(setup, len, timeout);
        self.outcome(&r, |b| control(true, setup, b.clone()))?;
        r
    }

    fn control_out(
        &mut self,
        setup: ControlSetup,
        data: &[u8],
        timeout: Duration,
    ) -> Result<(), LinkError> {
        let r = self.inner.control_out(setup, data, timeout);
        self.outcome(&r, |_| control(false, setup, data.to_vec()))?;
        r
    }

    fn read(
        &mut self,
        kind: TransferKind,
        endpoint: u8,
        len: usize,
        timeout: Duration,
    ) -> Result<Vec<u8>, LinkError> {
        let r = self.inner.read(kind, endpoint, len, timeout);
        self.outcome(&r, |b| EventKind::Transfer {
            kind,
            dir_in: true,
            endpoint,
            bytes: b.clone(),
        })?;
        r
    }

    fn write(
        &mut self,
        kind: TransferKind,
        endpoint: u8,
        data: &[u8],
        timeout: Duration,
    ) -> Result<(), LinkError> {
        let r = self.inner.write(kind, endpoint, data, timeout);
        self.outcome(&r, |_| EventKind::Transfer {
            kind,
            dir_in: false,
            endpoint,
            bytes: data.to_vec(),
        })?;
        r
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }
}

impl<L: HidLink> HidLink for RecordUsb<L> {
    fn write_report(&mut self, report: &[u8]) -> Result<(), LinkError> {
        let r = self.inner.write_report(report);
        self.outcome(&r, |_| EventKind::Bytes {
            dir: Dir::Host,
            bytes: report.to_vec(),
        })?;
        r
    }

    fn read_report(&mut self, len: usize, timeout: Duration) -> Result<Vec<u8>, LinkError> {
        let r = self.inner.read_report(len, timeout);
        self.outcome(&r, |b| EventKind::Bytes {
            dir: Dir::Device,
            bytes: b.clone(),
        })?;
        r
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: Duration = Duration::from_millis(100);
    const SETUP: ControlSetup = ControlSetup {
        request_type: 0xc0,
        request: 0x09,
        value: 0,
        index: 0,
    };

    fn transcript(transport: &str, events: &str) -> Transcript {
        let text = format!(
            "{{\"format\":\"metamer-transcript/1\",\"instrument\":\"test\",\"transport\":\"{transport}\",\"origin\":\"synthesized from the protocol documentation\"}}\n{events}"
        );
        Transcript::parse("u.jsonl", &text).unwrap()
    }

    #[test]
    fn usb_replay_checks_every_field() {
        let t = transcript(
            "usb",
            "{\"dir\":\"control_in\",\"request_type\":192,\"request\":9,\"value\":0,\"index\":0,\"hex\":\"0102\"}\n\
             {\"dir\":\"bulk_out\",\"endpoint\":1,\"hex\":\"aa\"}\n\
             {\"dir\":\"bulk_in\",\"endpoint\":130,\"hex\":\"bbcc\"}\n",
        );
        let mut r = ReplayUsb::new(t.clone()).unwrap();
        assert_eq!(r.control_in(SETUP, 8, T).unwrap(), vec![1, 2]);
        let e = r
            .write(TransferKind::Bulk, 1, &[0xab], T)
            .unwrap_err()
            .to_string();
        assert!(e.contains("u.jsonl line 3") && e.contains("hex ab"), "{e}");
        r.write(TransferKind::Bulk, 1, &[0xaa], T).unwrap();
        assert!(r.finish().is_err());
        assert_eq!(
            r.read(TransferKind::Bulk, 0x82, 64, T).unwrap(),
            vec![0xbb, 0xcc]
        );
        r.finish().unwrap();
    }

    #[test]
    fn recorded_usb_and_hid_sessions_replay() {
        let dir = std::env::temp_dir().join(format!("metamer-usbrec-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let src = transcript(
            "usb",
            "{\"dir\":\"control_out\",\"request_type\":192,\"request\":9,\"value\":0,\"index\":0,\"hex\":\"05\"}\n\
             {\"dir\":\"interrupt_in\",\"endpoint\":129,\"hex\":\"07\"}\n",
        );
        let path = dir.join("usb.jsonl");
        let _ = std::fs::remove_file(&path);
        let mut rec =
            RecordUsb::create(ReplayUsb::new(src).unwrap(), &path, "test", "usb", "t").unwrap();
        rec.control_out(SETUP, &[5], T).unwrap();
        assert_eq!(
            rec.read(TransferKind::Interrupt, 0x81, 8, T).unwrap(),
            vec![7]
        );
        drop(rec);
        let mut again = ReplayUsb::new(Transcript::load(&path).unwrap()).unwrap();
        again.control_out(SETUP, &[5], T).unwrap();
        assert_eq!(
            again.read(TransferKind::Interrupt, 0x81, 8, T).unwrap(),
            vec![7]
        );
        again.finish().unwrap();

        let hid = transcript(
            "hid",
            "{\"dir\":\"host\",\"hex\":\"0001\"}\n{\"dir\":\"device\",\"hex\":\"00ff\"}\n{\"dir\":\"device\",\"timeout\":true}\n",
        );
        let hpath = dir.join("hid.jsonl");
        let _ = std::fs::remove_file(&hpath);
        let mut rec =
            RecordUsb::create(ReplayUsb::new(hid).unwrap(), &hpath, "test", "hid", "t").unwrap();
        rec.write_report(&[0, 1]).unwrap();
        assert_eq!(rec.read_report(64, T).unwrap(), vec![0, 0xff]);
        assert!(matches!(
            rec.read_report(64, T),
            Err(LinkError::Timeout { .. })
        ));
        drop(rec);
        let mut again = ReplayUsb::new(Transcript::load(&hpath).unwrap()).unwrap();
        again.write_report(&[0, 1]).unwrap();
        assert_eq!(again.read_report(64, T).unwrap(), vec![0, 0xff]);
        assert!(matches!(
            again.read_report(64, T),
            Err(LinkError::Timeout { .. })
        ));
        again.finish().unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
