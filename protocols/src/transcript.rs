//! The transcript format (`metamer-transcript/1`): JSON Lines, a header then one event per
//! line, documented in `protocols/README.md`. Pure text ↔ value conversion; reading and
//! writing files is the drivers' job.

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

/// The format tag every header carries.
pub const FORMAT: &str = "metamer-transcript/1";

/// The `origin` of a transcript written by hand rather than recorded from a device.
pub const ORIGIN_SYNTHESIZED: &str = "synthesized from the protocol documentation";
/// The `origin` of a transcript written by the record backend.
pub const ORIGIN_RECORDED: &str = "recorded";

/// Line 1 of a transcript.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header {
    pub format: String,
    /// Short model name: `cs100a`, `i1pro`.
    pub instrument: String,
    /// `serial`, `usb` or `hid`.
    pub transport: String,
    /// Line settings of a serial transport (`baud`, `data_bits`, `parity`, `stop_bits`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settings: Option<Value>,
    /// `recorded` or `synthesized from the protocol documentation`.
    pub origin: String,
    #[serde(default)]
    pub description: String,
    /// What a test replaying this transcript must see (free form per instrument; the
    /// replay tests define it). Absent in plain recordings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expect: Option<Value>,
}

/// Who sent an event's bytes on a serial or HID link.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dir {
    /// Host → device.
    Host,
    /// Device → host.
    Device,
}

/// One event of a transcript.
#[derive(Clone, Debug, PartialEq)]
pub enum EventKind {
    /// Bytes on a serial link (or a HID report, whose first byte is the report id).
    Bytes { dir: Dir, bytes: Vec<u8> },
    /// The device stayed silent until the host's read timed out.
    Timeout,
    /// The device went away (cable pulled, USB unplugged).
    Disconnect,
    /// A USB control transfer; for `control_in` `bytes` is what the device returned.
    Control {
        dir_in: bool,
        request_type: u8,
        request: u8,
        value: u16,
        index: u16,
        bytes: Vec<u8>,
    },
    /// A USB bulk or interrupt transfer on `endpoint`.
    Transfer {
        kind: TransferKind,
        dir_in: bool,
        endpoint: u8,
        bytes: Vec<u8>,
    },
}

/// USB transfer types carried by [`EventKind::Transfer`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransferKind {
    Bulk,
    Interrupt,
}

/// An event with its optional time stamp and note.
#[derive(Clone, Debug, PartialEq)]
pub struct Event {
    pub kind: EventKind,
    /// Milliseconds since the transcript started.
    pub t_ms: Option<f64>,
    pub note: Option<String>,
}

impl Event {
    pub fn new(kind: EventKind) -> Event {
        Event {
            kind,
            t_ms: None,
            note: None,
        }
    }
}

/// Why a transcript line is not understood.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TranscriptError {
    #[error("not JSON: {0}")]
    Json(String),
    #[error("the header must say \"format\":\"{FORMAT}\" (found {0:?})")]
    Format(String),
    #[error("{0}")]
    Field(String),
}

/// Parses line 1.
pub fn parse_header(line: &str) -> Result<Header, TranscriptError> {
    let header: Header = serde_json::from_str(line)
        .map_err(|e| TranscriptError::Json(metamer_color::text::echo_message(&e.to_string())))?;
    if header.format != FORMAT {
        return Err(TranscriptError::Format(metamer_color::text::echo(
            &header.format,
        )));
    }
    Ok(header)
}

/// Parses one event line.
pub fn parse_event(line: &str) -> Result<Event, TranscriptError> {
    let value: Value = serde_json::from_str(line)
        .map_err(|e| TranscriptError::Json(metamer_color::text::echo_message(&e.to_string())))?;
    let obj = value
        .as_object()
        .ok_or_else(|| field_err("an event must be a JSON object"))?;
    let dir = obj
        .get("dir")
        .and_then(Value::as_str)
        .ok_or_else(|| field_err("an event needs \"dir\""))?;
    let flag = |k: &str| obj.get(k).and_then(Value::as_bool).unwrap_or(false);
    let kind = match dir {
        "host" | "device" => {
            let d = if dir == "host" {
                Dir::Host
            } else {
                Dir::Device
            };
            if flag("timeout") {
                if d == Dir::Host {
                    return Err(field_err("\"timeout\" belongs to a device event"));
                }
                EventKind::Timeout
            } else if flag("disconnect") {
                EventKind::Disconnect
            } else {
                EventKind::Bytes {
                    dir: d,
                    bytes: payload(obj)?,
                }
            }
        }
        "control_in" | "control_out" => EventKind::Control {
            dir_in: dir == "control_in",
            request_type: int_field(obj, "request_type")?,
            request: int_field(obj, "request")?,
            value: int_field(obj, "value")?,
            index: int_field(obj, "index")?,
            bytes: payload_or_empty(obj)?,
        },
        "bulk_in" | "bulk_out" | "interrupt_in" | "interrupt_out" => EventKind::Transfer {
            kind: if dir.starts_with("bulk") {
                TransferKind::Bulk
            } else {
                TransferKind::Interrupt
            },
            dir_in: dir.ends_with("_in"),
            endpoint: int_field(obj, "endpoint")?,
            bytes: payload_or_empty(obj)?,
        },
        other => {
            return Err(field_err(&format!(
                "unknown \"dir\" {:?} (host, device, control_in, control_out, bulk_in, \
                 bulk_out, interrupt_in, interrupt_out)",
                metamer_color::text::echo(other)
            )))
        }
    };
    let t_ms = obj.get("t_ms").and_then(Value::as_f64);
    let note = obj.get("note").and_then(Value::as_str).map(str::to_string);
    Ok(Event { kind, t_ms, note })
}

/// Writes one event as a JSON line (no trailing newline).
pub fn event_line(event: &Event) -> String {
    let mut obj = Map::new();
    match &event.kind {
        EventKind::Bytes { dir, bytes } => {
            let d = if *dir == Dir::Host { "host" } else { "device" };
            obj.insert("dir".into(), d.into());
            put_payload(&mut obj, bytes);
        }
        EventKind::Timeout => {
            obj.insert("dir".into(), "device".into());
            obj.insert("timeout".into(), true.into());
        }
        EventKind::Disconnect => {
            obj.insert("dir".into(), "device".into());
            obj.insert("disconnect".into(), true.into());
        }
        EventKind::Control {
            dir_in,
            request_type,
            request,
            value,
            index,
            bytes,
        } => {
            let d = if *dir_in { "control_in" } else { "control_out" };
            obj.insert("dir".into(), d.into());
            obj.insert("request_type".into(), (*request_type).into());
            obj.insert("request".into(), (*request).into());
            obj.insert("value".into(), (*value).into());
            obj.insert("index".into(), (*index).into());
            obj.insert("hex".into(), to_hex(bytes).into());
        }
        EventKind::Transfer {
            kind,
            dir_in,
            endpoint,
            bytes,
        } => {
            let d = match (kind, dir_in) {
                (TransferKind::Bulk, true) => "bulk_in",
                (TransferKind::Bulk, false) => "bulk_out",
                (TransferKind::Interrupt, true) => "interrupt_in",
                (TransferKind::Interrupt, false) => "interrupt_out",
            };
            obj.insert("dir".into(), d.into());
            obj.insert("endpoint".into(), (*endpoint).into());
            obj.insert("hex".into(), to_hex(bytes).into());
        }
    }
    if let Some(t) = event.t_ms {
        obj.insert("t_ms".into(), ((t * 10.0).round() / 10.0).into());
    }
    if let Some(n) = &event.note {
        obj.insert("note".into(), n.clone().into());
    }
    Value::Object(obj).to_string()
}

/// True when bytes read as text in a transcript: printable ASCII, CR, LF, TAB.
pub fn is_text(bytes: &[u8]) -> bool {
    bytes
        .iter()
        .all(|&b| (0x20..0x7f).contains(&b) || b == b'\r' || b == b'\n' || b == b'\t')
}

/// Bytes as lower-case hex without separators.
pub fn to_hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Parses hex (whitespace between byte pairs allowed).
pub fn from_hex(text: &str) -> Result<Vec<u8>, TranscriptError> {
    let digits: Vec<u8> = text.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
    if digits.len() % 2 != 0 {
        return Err(field_err("\"hex\" has an odd number of digits"));
    }
    digits
        .chunks(2)
        .map(|pair| {
            std::str::from_utf8(pair)
                .ok()
                .and_then(|s| u8::from_str_radix(s, 16).ok())
                .ok_or_else(|| {
                    field_err(&format!(
                        "\"hex\" has a non-hex digit pair {:?}",
                        metamer_color::text::echo(&String::from_utf8_lossy(pair))
                    ))
                })
        })
        .collect()
}

/// Shows bytes for a message: text as a quoted string with escapes, anything else as hex.
pub fn show_bytes(bytes: &[u8]) -> String {
    if is_text(bytes) {
        metamer_color::text::echo(&format!("{:?}", String::from_utf8_lossy(bytes)))
    } else if bytes.len() > SHOWN_HEX_BYTES {
        format!(
            "hex {}… ({} bytes in all)",
            to_hex(&bytes[..SHOWN_HEX_BYTES]),
            bytes.len()
        )
    } else {
        format!("hex {}", to_hex(bytes))
    }
}

/// Bytes shown in hex in a message: 40 bytes are 80 hex digits, the length of quoted text.
const SHOWN_HEX_BYTES: usize = 40;

fn put_payload(obj: &mut Map<String, Value>, bytes: &[u8]) {
    if is_text(bytes) {
        obj.insert(
            "data".into(),
            String::from_utf8_lossy(bytes).into_owned().into(),
        );
    } else {
        obj.insert("hex".into(), to_hex(bytes).into());
    }
}

fn payload(obj: &Map<String, Value>) -> Result<Vec<u8>, TranscriptError> {
    match (obj.get("data"), obj.get("hex")) {
        (Some(Value::String(s)), None) => {
            // JSON strings are Unicode; bytes beyond ASCII must be written as hex so a byte
            // is never silently re-encoded as UTF-8.
            if !s.is_ascii() {
                return Err(field_err(
                    "\"data\" must be ASCII; write other bytes as \"hex\"",
                ));
            }
            Ok(s.as_bytes().to_vec())
        }
        (None, Some(Value::String(h))) => from_hex(h),
        (Some(_), Some(_)) => Err(field_err("an event has \"data\" or \"hex\", not both")),
        _ => Err(field_err(
            "a host or device event needs \"data\" (a string), \"hex\", \"timeout\" or \"disconnect\"",
        )),
    }
}

fn payload_or_empty(obj: &Map<String, Value>) -> Result<Vec<u8>, TranscriptError> {
    if obj.contains_key("data") || obj.contains_key("hex") {
        payload(obj)
    } else {
        Ok(Vec::new())
    }
}

fn int_field<T: TryFrom<u64>>(obj: &Map<String, Value>, key: &str) -> Result<T, TranscriptError> {
    obj.get(key)
        .and_then(Value::as_u64)
        .and_then(|v| T::try_from(v).ok())
        .ok_or_else(|| field_err(&format!("\"{key}\" must be an integer in range")))
}

fn field_err(msg: &str) -> TranscriptError {
    TranscriptError::Field(msg.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serial_events_parse_with_escapes() {
        let e = parse_event(r#"{"dir":"host","data":"MES\r\n"}"#).unwrap();
        assert_eq!(
            e.kind,
            EventKind::Bytes {
                dir: Dir::Host,
                bytes: b"MES\r\n".to_vec()
            }
        );
        let e = parse_event(r#"{"dir":"device","hex":"4f 4b ff","t_ms":12.5,"note":"x"}"#).unwrap();
        assert_eq!(
            e.kind,
            EventKind::Bytes {
                dir: Dir::Device,
                bytes: vec![0x4f, 0x4b, 0xff]
            }
        );
        assert_eq!(e.t_ms, Some(12.5));
        assert_eq!(e.note.as_deref(), Some("x"));
        assert_eq!(
            parse_event(r#"{"dir":"device","timeout":true}"#)
                .unwrap()
                .kind,
            EventKind::Timeout
        );
        assert_eq!(
            parse_event(r#"{"dir":"device","disconnect":true}"#)
                .unwrap()
                .kind,
            EventKind::Disconnect
        );
    }

    #[test]
    fn usb_events_parse() {
        let e = parse_event(
            r#"{"dir":"control_in","request_type":192,"request":1,"value":0,"index":0,"hex":"0102"}"#,
        )
        .unwrap();
        assert_eq!(
            e.kind,
            EventKind::Control {
                dir_in: true,
                request_type: 192,
                request: 1,
                value: 0,
                index: 0,
                bytes: vec![1, 2]
            }
        );
        let e = parse_event(r#"{"dir":"bulk_out","endpoint":2,"hex":"ff"}"#).unwrap();
        assert_eq!(
            e.kind,
            EventKind::Transfer {
                kind: TransferKind::Bulk,
                dir_in: false,
                endpoint: 2,
                bytes: vec![255]
            }
        );
    }

    #[test]
    fn events_round_trip_through_lines() {
        let events = [
            EventKind::Bytes {
                dir: Dir::Host,
                bytes: b"MDS,04\r\n".to_vec(),
            },
            EventKind::Bytes {
                dir: Dir::Device,
                bytes: vec![0x4f, 0x00, 0xcf],
            },
            EventKind::Timeout,
            EventKind::Disconnect,
            EventKind::Control {
                dir_in: false,
                request_type: 0x40,
                request: 9,
                value: 0x0100,
                index: 0,
                bytes: vec![],
            },
            EventKind::Transfer {
                kind: TransferKind::Interrupt,
                dir_in: true,
                endpoint: 0x81,
                bytes: vec![7],
            },
        ];
        for kind in events {
            let line = event_line(&Event::new(kind.clone()));
            assert_eq!(parse_event(&line).unwrap().kind, kind, "{line}");
        }
        assert_eq!(
            event_line(&Event::new(EventKind::Bytes {
                dir: Dir::Device,
                bytes: b"OK00\r\n".to_vec()
            })),
            r#"{"data":"OK00\r\n","dir":"device"}"#
        );
    }

    #[test]
    fn bad_lines_are_explained() {
        assert!(matches!(
            parse_event(r#"{"dir":"sideways","data":"x"}"#),
            Err(TranscriptError::Field(m)) if m.contains("sideways")
        ));
        assert!(matches!(parse_event("{"), Err(TranscriptError::Json(_))));
        assert!(matches!(
            parse_event(r#"{"dir":"host","hex":"abc"}"#),
            Err(TranscriptError::Field(m)) if m.contains("odd")
        ));
        assert!(matches!(
            parse_event(r#"{"dir":"host","data":"é"}"#),
            Err(TranscriptError::Field(m)) if m.contains("ASCII")
        ));
        assert!(matches!(
            parse_header(r#"{"format":"other","instrument":"x","transport":"serial","origin":"recorded"}"#),
            Err(TranscriptError::Format(f)) if f == "other"
        ));
    }
}
