//! Konica Minolta CS-100A chroma meter, RS-232C command set: host-side encoding of commands
//! and parsing of replies, and the device side (parsing commands, encoding replies) for the
//! emulator. The facts, their sources and confidence tags ([C], [C2], [I]; KM-CS, PP, MC2, …)
//! are in `protocols/cs100a/README.md`, which also draws the reply's byte layout.
//!
//! Where a fact is only inferred ([I]) the parser accepts both readings of it and a comment
//! says so.

use std::fmt;

/// Every command and reply ends with CR LF (KM-CS p.10, [C]).
pub const TERMINATOR: &[u8] = b"\r\n";

/// Length of an `MES` reply in absolute mode: 26 characters + CR LF (MC2, MF, PGL; [C2]).
pub const MES_REPLY_LEN: usize = 28;

/// `MDS` parameters (MF, MC2, VB agree; [C2]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// `00`: Minolta factory calibration.
    Preset,
    /// `01`: user calibration.
    Variable,
    /// `04`: absolute Yxy readings.
    Absolute,
    /// `05`: colour difference against the stored target.
    Difference,
    /// `06`: FAST response (≈100 ms).
    Fast,
    /// `07`: SLOW response (≈400 ms).
    Slow,
}

impl Mode {
    /// The two-digit parameter sent after `MDS,`.
    pub fn code(self) -> u8 {
        match self {
            Mode::Preset => 0,
            Mode::Variable => 1,
            Mode::Absolute => 4,
            Mode::Difference => 5,
            Mode::Fast => 6,
            Mode::Slow => 7,
        }
    }

    /// The mode of a two-digit parameter; None for any the CS-100A does not have (the LS-100's
    /// 02, 03, 08, 09 included, which the meter answers with ER00 [I]).
    pub fn from_code(code: u8) -> Option<Mode> {
        Some(match code {
            0 => Mode::Preset,
            1 => Mode::Variable,
            4 => Mode::Absolute,
            5 => Mode::Difference,
            6 => Mode::Fast,
            7 => Mode::Slow,
            _ => return None,
        })
    }
}

/// A host command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Command {
    /// `MDS,nn`: set a mode.
    SetMode(Mode),
    /// `MES`: take a measurement.
    Measure,
    /// `CLE`: clear the meter's memory.
    Clear,
}

impl Command {
    /// The bytes sent on the wire, CR LF included.
    pub fn encode(self) -> Vec<u8> {
        let text = match self {
            Command::SetMode(mode) => format!("MDS,{:02}", mode.code()),
            Command::Measure => "MES".to_string(),
            Command::Clear => "CLE".to_string(),
        };
        let mut bytes = text.into_bytes();
        bytes.extend_from_slice(TERMINATOR);
        bytes
    }

    /// The command as it reads in messages (`MDS,04`).
    pub fn text(self) -> String {
        let bytes = self.encode();
        String::from_utf8_lossy(&bytes[..bytes.len() - TERMINATOR.len()]).into_owned()
    }
}

/// The 4-character check code that starts every reply (KM-CS p.10, [C]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Status {
    Ok00,
    Ok11,
    Ok12,
    Ok13,
    Er00,
    Er01,
    Er10,
    Er11,
    Er12,
    Er19,
    Er20,
    Er30,
}

impl Status {
    /// All twelve codes of the manual's list.
    pub const ALL: [Status; 12] = [
        Status::Ok00,
        Status::Ok11,
        Status::Ok12,
        Status::Ok13,
        Status::Er00,
        Status::Er01,
        Status::Er10,
        Status::Er11,
        Status::Er12,
        Status::Er19,
        Status::Er20,
        Status::Er30,
    ];

    /// The code as sent: `OK00`, `ER10`, …
    pub fn code(self) -> &'static str {
        match self {
            Status::Ok00 => "OK00",
            Status::Ok11 => "OK11",
            Status::Ok12 => "OK12",
            Status::Ok13 => "OK13",
            Status::Er00 => "ER00",
            Status::Er01 => "ER01",
            Status::Er10 => "ER10",
            Status::Er11 => "ER11",
            Status::Er12 => "ER12",
            Status::Er19 => "ER19",
            Status::Er20 => "ER20",
            Status::Er30 => "ER30",
        }
    }

    /// Parses a 4-byte code.
    pub fn from_code(code: &[u8]) -> Option<Status> {
        Status::ALL
            .into_iter()
            .find(|s| s.code().as_bytes() == code)
    }

    /// What the code means (KM-CS p.10, our wording) and, for errors, what to do.
    pub fn meaning(self) -> &'static str {
        match self {
            Status::Ok00 => "normal reading",
            Status::Ok11 => "chromaticity over the measuring range (display E0)",
            Status::Ok12 => "luminance over the display range (display E9)",
            Status::Ok13 => "luminance under the display range: low light (display flashes)",
            Status::Er00 => "command error: unknown command or parameter out of range",
            Status::Er01 => "setting error (display E)",
            Status::Er10 => {
                "luminance and chromaticity over the measuring range (display E0); \
                 aim at a dimmer target or fit an ND filter"
            }
            Status::Er11 => "memory value error (display E1)",
            Status::Er12 => {
                "luminance and chromaticity display ranges both over (display E9 and E8)"
            }
            Status::Er19 => "display range over (display E9)",
            Status::Er20 => "EEPROM error: the meter needs repair (display E2)",
            Status::Er30 => "battery exhausted (display B0): replace the batteries",
        }
    }

    /// OK codes carry data; ER codes do not.
    pub fn is_ok(self) -> bool {
        matches!(
            self,
            Status::Ok00 | Status::Ok11 | Status::Ok12 | Status::Ok13
        )
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.code(), self.meaning())
    }
}

/// A luminance and chromaticity as the meter reports them in absolute mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Yxy {
    /// Luminance in the unit set on the meter's body (cd/m² or fL; no unit is sent [I]).
    /// None when the meter sent its over-range placeholder (`-999999`, OK12).
    pub luminance: Option<f64>,
    /// CIE 1931 x and y; None when the meter could not measure them (OK11).
    pub x: Option<f64>,
    pub y: Option<f64>,
}

/// A parsed reply.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reply {
    /// An OK code with the three data fields of `MES`.
    Measurement { status: Status, value: Yxy },
    /// A code with no data: the acknowledgement of `MDS`/`CLE` (OK00) or any error.
    Code(Status),
}

/// Why a reply line could not be understood.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ReplyError {
    #[error("the reply does not end with CR LF")]
    NoTerminator,
    #[error(
        "byte {index} is 0x{byte:02X}, not plain ASCII: a parity or framing error on the line \
         (the port must be 4800 baud, 7 data bits, even parity, 2 stop bits) or electrical noise"
    )]
    NotAscii { index: usize, byte: u8 },
    #[error(
        "byte {index} is '?', the character a serial driver substitutes for one received with a \
         parity error (the port must be 4800 baud, 7 data bits, even parity, 2 stop bits)"
    )]
    ParitySubstitute { index: usize },
    #[error("'{0}' is not a CS-100A status code (OK00, OK11–OK13, ER00–ER30)")]
    UnknownStatus(String),
    #[error("{status} must come with Y, x, y but the reply has {fields} data field(s)")]
    MissingData { status: &'static str, fields: usize },
    #[error("{status} carries no data but the reply has {fields} data field(s)")]
    UnexpectedData { status: &'static str, fields: usize },
    #[error("field {field} '{text}' is not a number with a sign column")]
    BadNumber { field: &'static str, text: String },
}

/// Parses one reply line, CR LF included.
///
/// The layout is read by commas, not by fixed columns: the 28-byte form is only [C2], and
/// the luminance field's decimals vary with magnitude [I], so any field width is accepted.
pub fn parse_reply(line: &[u8]) -> Result<Reply, ReplyError> {
    let body = line
        .strip_suffix(TERMINATOR)
        .ok_or(ReplyError::NoTerminator)?;
    check_ascii(body)?;
    // Checked ASCII above, so this is lossless.
    let text = std::str::from_utf8(body).expect("ASCII is UTF-8");
    let mut fields = text.split(',');
    let code = fields.next().unwrap_or("");
    let status = Status::from_code(code.as_bytes())
        .ok_or_else(|| ReplyError::UnknownStatus(metamer_color::text::echo(code)))?;
    let data: Vec<&str> = fields.collect();
    if !status.is_ok() {
        if !data.is_empty() {
            return Err(ReplyError::UnexpectedData {
                status: status.code(),
                fields: data.len(),
            });
        }
        return Ok(Reply::Code(status));
    }
    match data.len() {
        // OK00 alone acknowledges MDS and CLE.
        0 => Ok(Reply::Code(status)),
        3 => {
            let luminance = parse_signed(data[0], "Y")?;
            let x = parse_signed(data[1], "x")?;
            let y = parse_signed(data[2], "y")?;
            // OK12's luminance may be the over-range placeholder -999999 (MC2 template, [C2]
            // unverified) or a real value above the display range ([I]); accept both.
            let luminance = if status == Status::Ok12 && luminance <= -999_999.0 {
                None
            } else {
                Some(luminance)
            };
            // OK11 sends x, y as .0000 (MC2, [C2]); a meter that sends its last values
            // instead ([I]) is tolerated by keeping any non-zero pair.
            let (x, y) = if status == Status::Ok11 && x == 0.0 && y == 0.0 {
                (None, None)
            } else {
                (Some(x), Some(y))
            };
            Ok(Reply::Measurement {
                status,
                value: Yxy { luminance, x, y },
            })
        }
        n => Err(ReplyError::MissingData {
            status: status.code(),
            fields: n,
        }),
    }
}

fn check_ascii(body: &[u8]) -> Result<(), ReplyError> {
    for (index, &byte) in body.iter().enumerate() {
        if byte == b'?' {
            return Err(ReplyError::ParitySubstitute { index });
        }
        // Linux substitutes NUL for a character received with a parity error (termios
        // without PARMRK), .NET '?' (VB strips them, [I]); neither belongs in a reply.
        if !(0x20..0x7f).contains(&byte) {
            return Err(ReplyError::NotAscii { index, byte });
        }
    }
    Ok(())
}

/// A field whose first character is a sign column: ' ' or '+' for positive (PGL example,
/// [C2]; '+' in MC2's template), '-' for negative ([I]).
fn parse_signed(field: &str, name: &'static str) -> Result<f64, ReplyError> {
    let bad = || ReplyError::BadNumber {
        field: name,
        text: metamer_color::text::echo(field),
    };
    let (sign, rest) = match field.as_bytes().first() {
        Some(b' ') | Some(b'+') => (1.0, &field[1..]),
        Some(b'-') => (-1.0, &field[1..]),
        _ => return Err(bad()),
    };
    let digits = rest.trim_start();
    if digits.is_empty()
        || !digits.bytes().all(|b| b.is_ascii_digit() || b == b'.')
        || digits.bytes().filter(|&b| b == b'.').count() > 1
        || !digits.bytes().any(|b| b.is_ascii_digit())
    {
        return Err(bad());
    }
    // Hundreds of digits parse to infinity; no meter sends them.
    digits
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .map(|v| sign * v)
        .ok_or_else(bad)
}

// ---- device side (the emulator) ----

/// Why a command line from the host is not understood; the meter answers ER00.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CommandError {
    #[error("command {0:?} is not one of MES, MDS,nn, CLE")]
    Unknown(String),
    #[error("MDS parameter {0:?} is not a CS-100A mode")]
    BadMode(String),
}

/// Parses a command line as the meter receives it (CR LF stripped or not).
pub fn parse_command(line: &[u8]) -> Result<Command, CommandError> {
    let body = line.strip_suffix(TERMINATOR).unwrap_or(line);
    let text = String::from_utf8_lossy(body);
    match text.as_ref() {
        "MES" => Ok(Command::Measure),
        "CLE" => Ok(Command::Clear),
        t => {
            if let Some(param) = t.strip_prefix("MDS,") {
                let mode = (param.len() == 2)
                    .then(|| param.parse::<u8>().ok())
                    .flatten()
                    .and_then(Mode::from_code);
                mode.map(Command::SetMode)
                    .ok_or_else(|| CommandError::BadMode(param.to_string()))
            } else {
                Err(CommandError::Unknown(t.to_string()))
            }
        }
    }
}

/// Encodes a code-only reply (`OK00\r\n`, `ER10\r\n`).
pub fn encode_code(status: Status) -> Vec<u8> {
    let mut bytes = status.code().as_bytes().to_vec();
    bytes.extend_from_slice(TERMINATOR);
    bytes
}

/// Encodes an `MES` reply in the 28-byte layout (MC2 columns, [C2]): Y in a 7-character
/// field (sign column + 6), x and y in 6 (sign column + `.dddd`). `luminance: None` sends
/// the OK12 placeholder `-999999`; `x`/`y: None` sends `.0000` as for OK11.
pub fn encode_measurement(status: Status, value: &Yxy) -> Vec<u8> {
    let lum = match value.luminance {
        None => "-999999".to_string(),
        Some(v) => {
            let sign = if v < 0.0 { '-' } else { ' ' };
            format!("{sign}{:>6}", format_luminance(v.abs()))
        }
    };
    let chroma = |v: Option<f64>| {
        let v = v.unwrap_or(0.0).clamp(-0.9999, 0.9999);
        let sign = if v < 0.0 { '-' } else { ' ' };
        let digits = format!("{:.4}", v.abs());
        // "0.3127" → ".3127": the meter sends no leading zero (MC2, PGL; [C2]).
        format!("{sign}{}", &digits[1..])
    };
    let text = format!(
        "{},{},{},{}\r\n",
        status.code(),
        lum,
        chroma(value.x),
        chroma(value.y)
    );
    text.into_bytes()
}

/// Four significant digits in at most six characters, as the examples show (`123.4`,
/// `10.73`, `0.523`); the exact rule is [I].
fn format_luminance(v: f64) -> String {
    let s = if v >= 999.95 {
        format!("{:.0}", v.min(999_999.0))
    } else if v >= 99.995 {
        format!("{v:.1}")
    } else if v >= 9.9995 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    };
    s
}

#[cfg(test)]
mod tests;
