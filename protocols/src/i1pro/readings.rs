//! Raw readings as they arrive on the bulk endpoint: per reading, Rev A–D send 128
//! big-endian u16 cells; Rev E sends 6 shielded cells and then the 128 spectral cells. The
//! byte count is checked so a short transfer is an error, never a wrong spectrum.

use super::{Revision, CELLS, SHIELDED_CELLS};

/// One reading's sensor values.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RawReading {
    /// Spectral cells. Rev A–D values at or above the maximum positive value are negative
    /// (the value − 65536); Rev E values are unsigned.
    pub cells: [i32; CELLS],
    /// Rev E's shielded (dark reference) cells; `None` on Rev A–D.
    pub shielded: Option<[u16; SHIELDED_CELLS]>,
}

/// A bulk transfer that is not a whole number of readings of the expected count.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ReadingError {
    #[error(
        "short read: {got} bytes arrived, {expected} expected for {readings} readings of \
         {per_reading} bytes"
    )]
    Short {
        got: usize,
        expected: usize,
        readings: usize,
        per_reading: usize,
    },
    #[error(
        "long read: {got} bytes arrived, {expected} expected for {readings} readings of \
         {per_reading} bytes"
    )]
    Long {
        got: usize,
        expected: usize,
        readings: usize,
        per_reading: usize,
    },
    #[error("{got} bytes are not a whole number of {per_reading}-byte readings")]
    Partial { got: usize, per_reading: usize },
    #[error("no readings: the transfer was empty")]
    Empty,
    #[error("a Rev {revision:?} reading {problem}")]
    Shape {
        revision: Revision,
        problem: &'static str,
    },
    #[error("cell {cell} holds {value}, which cannot be sent as a 16-bit sensor value")]
    OutOfRange { cell: usize, value: i32 },
}

/// Parses exactly `readings` readings. `max_positive` is GetMisc's maximum positive value + 1
/// (Rev A–D only; Rev E values are unsigned).
pub fn parse(
    bytes: &[u8],
    revision: Revision,
    readings: usize,
    max_positive: u16,
) -> Result<Vec<RawReading>, ReadingError> {
    let per_reading = revision.bytes_per_reading();
    let expected = readings.saturating_mul(per_reading);
    if bytes.len() != expected {
        let (got, readings) = (bytes.len(), readings);
        return Err(if got < expected {
            ReadingError::Short {
                got,
                expected,
                readings,
                per_reading,
            }
        } else {
            ReadingError::Long {
                got,
                expected,
                readings,
                per_reading,
            }
        });
    }
    Ok(bytes
        .chunks_exact(per_reading)
        .map(|c| parse_one(c, revision, max_positive))
        .collect())
}

/// Parses the readings of a scan, whose count the host does not know in advance: any whole,
/// non-zero number of readings.
pub fn parse_scan(
    bytes: &[u8],
    revision: Revision,
    max_positive: u16,
) -> Result<Vec<RawReading>, ReadingError> {
    let per_reading = revision.bytes_per_reading();
    if bytes.is_empty() {
        return Err(ReadingError::Empty);
    }
    if bytes.len() % per_reading != 0 {
        return Err(ReadingError::Partial {
            got: bytes.len(),
            per_reading,
        });
    }
    parse(bytes, revision, bytes.len() / per_reading, max_positive)
}

fn parse_one(chunk: &[u8], revision: Revision, max_positive: u16) -> RawReading {
    let values: Vec<u16> = chunk
        .chunks_exact(2)
        .map(|p| u16::from_be_bytes([p[0], p[1]]))
        .collect();
    let mut cells = [0i32; CELLS];
    match revision {
        Revision::AToD => {
            for (c, &v) in cells.iter_mut().zip(&values) {
                *c = signed(v, max_positive);
            }
            RawReading {
                cells,
                shielded: None,
            }
        }
        Revision::E => {
            let mut shielded = [0u16; SHIELDED_CELLS];
            shielded.copy_from_slice(&values[..SHIELDED_CELLS]);
            for (c, &v) in cells.iter_mut().zip(&values[SHIELDED_CELLS..]) {
                *c = i32::from(v);
            }
            RawReading {
                cells,
                shielded: Some(shielded),
            }
        }
    }
}

/// The Rev A–D sign rule: values at or above `max_positive` wrap to negative.
pub fn signed(value: u16, max_positive: u16) -> i32 {
    if value >= max_positive {
        i32::from(value) - 65536
    } else {
        i32::from(value)
    }
}

/// The bytes an instrument sends for `readings` (the inverse of [`parse`]); what a simulated
/// i1Pro writes to the bulk endpoint. Rev A–D cells may be negative down to
/// `max_positive − 65536` (sent as value + 65536) and positive up to `max_positive − 1`.
pub fn encode(
    readings: &[RawReading],
    revision: Revision,
    max_positive: u16,
) -> Result<Vec<u8>, ReadingError> {
    let mut out = Vec::with_capacity(readings.len() * revision.bytes_per_reading());
    for r in readings {
        match (revision, &r.shielded) {
            (Revision::E, Some(s)) => s.iter().for_each(|v| out.extend(v.to_be_bytes())),
            (Revision::E, None) => {
                return Err(ReadingError::Shape {
                    revision,
                    problem: "needs its 6 shielded cells",
                })
            }
            (Revision::AToD, Some(_)) => {
                return Err(ReadingError::Shape {
                    revision,
                    problem: "has no shielded cells",
                })
            }
            (Revision::AToD, None) => {}
        }
        let (low, high) = value_range(revision, max_positive);
        for (cell, &v) in r.cells.iter().enumerate() {
            if v < low || v > high {
                return Err(ReadingError::OutOfRange { cell, value: v });
            }
            out.extend(((v & 0xFFFF) as u16).to_be_bytes());
        }
    }
    Ok(out)
}

/// The cell values a reading can carry.
pub fn value_range(revision: Revision, max_positive: u16) -> (i32, i32) {
    match revision {
        Revision::AToD => (i32::from(max_positive) - 65536, i32::from(max_positive) - 1),
        Revision::E => (0, 65535),
    }
}

#[cfg(test)]
mod tests;
