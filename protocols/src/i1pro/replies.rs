//! Replies of the i1Pro's IN vendor requests: parsed from their bytes for the driver and
//! encoded for a simulated instrument.

/// A reply that does not have the documented form.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ReplyError {
    #[error("the {reply} reply has {got} bytes, expected {expected}")]
    Length {
        reply: &'static str,
        expected: usize,
        got: usize,
    },
    #[error(
        "unexpected Rev E measurement characteristics: clock {clock_us} µs, {shielded} shielded \
         and {cells} spectral cells, divider {divider} (known: 36 µs, 6, 128, 136)"
    )]
    UnexpectedMeasChar {
        clock_us: u32,
        shielded: u32,
        cells: u32,
        divider: u32,
    },
}

pub(super) fn exact<const N: usize>(
    reply: &'static str,
    bytes: &[u8],
) -> Result<[u8; N], ReplyError> {
    bytes.try_into().map_err(|_| ReplyError::Length {
        reply,
        expected: N,
        got: bytes.len(),
    })
}

/// Power state byte of [`Misc`] while the instrument is still in low power.
pub const POWER_LOW: u8 = 8;

/// Reply of 0xC9.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Misc {
    /// Firmware revision (e.g. 302 Rev B, 505 Rev D, 629 Rev E).
    pub firmware: u16,
    /// Meaning unknown (changes after each reading).
    pub unknown1: u16,
    /// Largest positive sensor value + 1: raw values at or above it are negative (Rev A–D).
    pub max_positive: u16,
    /// Meaning unknown (usually 1).
    pub unknown3: u8,
    /// Power state: [`POWER_LOW`] while in low power, 0 in high power.
    pub power: u8,
}

impl Misc {
    pub fn parse(reply: &[u8]) -> Result<Misc, ReplyError> {
        let b = exact::<8>("get misc (0xC9)", reply)?;
        Ok(Misc {
            firmware: u16::from_be_bytes([b[0], b[1]]),
            unknown1: u16::from_be_bytes([b[2], b[3]]),
            max_positive: u16::from_be_bytes([b[4], b[5]]),
            unknown3: b[6],
            power: b[7],
        })
    }

    pub fn encode(&self) -> [u8; 8] {
        let mut b = [0u8; 8];
        b[0..2].copy_from_slice(&self.firmware.to_be_bytes());
        b[2..4].copy_from_slice(&self.unknown1.to_be_bytes());
        b[4..6].copy_from_slice(&self.max_positive.to_be_bytes());
        b[6] = self.unknown3;
        b[7] = self.power;
        b
    }

    /// Whether the instrument has reached high power (the lamp and sensor are usable).
    pub fn high_power(&self) -> bool {
        self.power != POWER_LOW
    }

    /// Whether the firmware has clock modes (0xCF/0xD1).
    pub fn has_clock_modes(&self) -> bool {
        self.firmware >= 301
    }
}

/// Reply of 0xD1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClockMode {
    /// Highest selectable mode.
    pub max: u8,
    pub current: u8,
    pub unknown: u8,
    /// Integration clocks per sub-clock (the lamp's unit).
    pub sub_clock_divider: u8,
    /// Integration clock period, µs.
    pub clock_us: u8,
    /// Bit 0: subtract mode.
    pub flags: u8,
}

impl ClockMode {
    pub fn parse(reply: &[u8]) -> Result<ClockMode, ReplyError> {
        let b = exact::<6>("get clock mode (0xD1)", reply)?;
        Ok(ClockMode {
            max: b[0],
            current: b[1],
            unknown: b[2],
            sub_clock_divider: b[3],
            clock_us: b[4],
            flags: b[5],
        })
    }

    pub fn encode(&self) -> [u8; 6] {
        [
            self.max,
            self.current,
            self.unknown,
            self.sub_clock_divider,
            self.clock_us,
            self.flags,
        ]
    }

    /// Integration clock period, seconds.
    pub fn clock_s(&self) -> f64 {
        f64::from(self.clock_us) * 1e-6
    }

    /// One sub-clock, seconds: the shortest integration in this mode.
    pub fn sub_clock_s(&self) -> f64 {
        self.clock_s() * f64::from(self.sub_clock_divider)
    }

    pub fn subtract_mode(&self) -> bool {
        self.flags & 1 != 0
    }
}

/// Reply of 0xD5 (Rev E).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeasChar {
    pub clock_us: u32,
    pub shielded: u32,
    pub cells: u32,
    pub divider: u32,
}

impl MeasChar {
    /// The only characteristics known to occur: 36 µs, 6 shielded, 128 cells, divider 136.
    pub const KNOWN: MeasChar = MeasChar {
        clock_us: 36,
        shielded: 6,
        cells: 128,
        divider: 136,
    };

    /// Parses the 16 bytes; any values other than [`MeasChar::KNOWN`] are an error, because
    /// the reading layout and timing depend on them.
    pub fn parse(reply: &[u8]) -> Result<MeasChar, ReplyError> {
        let b = exact::<16>("measurement characteristics (0xD5)", reply)?;
        let w = |i: usize| u32::from_be_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
        let m = MeasChar {
            clock_us: w(0),
            shielded: w(4),
            cells: w(8),
            divider: w(12),
        };
        if m != MeasChar::KNOWN {
            return Err(ReplyError::UnexpectedMeasChar {
                clock_us: m.clock_us,
                shielded: m.shielded,
                cells: m.cells,
                divider: m.divider,
            });
        }
        Ok(m)
    }

    pub fn encode(&self) -> [u8; 16] {
        let mut b = [0u8; 16];
        for (i, v) in [self.clock_us, self.shielded, self.cells, self.divider]
            .into_iter()
            .enumerate()
        {
            b[4 * i..4 * i + 4].copy_from_slice(&v.to_be_bytes());
        }
        b
    }

    pub fn clock_s(&self) -> f64 {
        f64::from(self.clock_us) * 1e-6
    }
}

/// Reply of 0xD9: EEPROM size in bytes.
pub fn parse_eeprom_size(reply: &[u8]) -> Result<u32, ReplyError> {
    Ok(u32::from_be_bytes(exact::<4>("EEPROM size (0xD9)", reply)?))
}

/// Reply of 0xD2: the chip id.
pub fn parse_chip_id(reply: &[u8]) -> Result<[u8; 8], ReplyError> {
    exact::<8>("chip id (0xD2)", reply)
}

/// Reply of 0xD8: UV LED voltage before and after (raw units).
pub fn parse_uv_volts(reply: &[u8]) -> Result<(u16, u16), ReplyError> {
    let b = exact::<4>("UV LED volts (0xD8)", reply)?;
    Ok((
        u16::from_be_bytes([b[0], b[1]]),
        u16::from_be_bytes([b[2], b[3]]),
    ))
}

#[cfg(test)]
mod tests;
