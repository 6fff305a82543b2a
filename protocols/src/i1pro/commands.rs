//! The i1Pro's vendor requests on endpoint 0: each request as a typed value that encodes to
//! the setup fields and data stage of one control transfer (and decodes back, for a simulated
//! instrument), and the replies of the IN requests parsed from and encoded to their bytes.

use super::replies::{exact, ReplyError};
use super::Revision;

/// bmRequestType of host → device requests: OUT, vendor, device recipient.
pub const REQUEST_TYPE_OUT: u8 = 0x40;
/// bmRequestType of device → host requests: IN, vendor, device recipient.
pub const REQUEST_TYPE_IN: u8 = 0xC0;
/// Bulk IN endpoint of EEPROM contents and readings.
pub const EP_DATA_IN: u8 = 0x82;
/// IN endpoint whose 1-byte transfer completes when the button is pressed.
pub const EP_SWITCH_IN: u8 = 0x84;
/// Control transfers are given this long (seconds) before the host gives up.
pub const CONTROL_TIMEOUT_S: f64 = 2.0;
/// An EEPROM bulk read is given this long (seconds).
pub const EEPROM_READ_TIMEOUT_S: f64 = 5.0;

/// bRequest codes.
pub mod code {
    pub const TRIGGER: u8 = 0xC0;
    pub const SET_MEAS_PARAMS: u8 = 0xC1;
    pub const GET_MEAS_PARAMS: u8 = 0xC2;
    pub const READ_EEPROM: u8 = 0xC4;
    pub const GET_MISC: u8 = 0xC9;
    pub const RESET: u8 = 0xCA;
    pub const SET_CLOCK_MODE: u8 = 0xCF;
    pub const END_SWITCH_READ: u8 = 0xD0;
    pub const GET_CLOCK_MODE: u8 = 0xD1;
    pub const GET_CHIP_ID: u8 = 0xD2;
    pub const MEASURE_E: u8 = 0xD4;
    pub const GET_MEAS_CHAR: u8 = 0xD5;
    pub const STOP_RULER: u8 = 0xD7;
    pub const GET_UV_VOLTS: u8 = 0xD8;
    pub const GET_EEPROM_SIZE: u8 = 0xD9;
}

/// Reset masks seen in use: 0x1F is the normal reset, 0x01 the one sent while waiting for the
/// instrument to reach high power.
pub const RESET_NORMAL: u8 = 0x1F;
pub const RESET_POWER: u8 = 0x01;

/// The fixed data stage of "end the pending switch read" (sent with wValue 3).
pub const END_SWITCH_READ_DATA: [u8; 8] = [0xFF, 0xFF, 0xFF, 0xFF, 0xFC, 0xEE, 0x12, 0x00];

/// A control transfer's setup fields other than wLength.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Setup {
    pub request_type: u8,
    pub request: u8,
    pub value: u16,
    pub index: u16,
}

impl Setup {
    fn out(request: u8) -> Setup {
        Setup {
            request_type: REQUEST_TYPE_OUT,
            request,
            value: 0,
            index: 0,
        }
    }

    fn input(request: u8) -> Setup {
        Setup {
            request_type: REQUEST_TYPE_IN,
            request,
            value: 0,
            index: 0,
        }
    }
}

/// One control transfer as the host issues it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Transfer {
    /// Host → device with this data stage (possibly empty).
    Out { setup: Setup, data: Vec<u8> },
    /// Device → host; the device answers with exactly `length` bytes.
    In { setup: Setup, length: u16 },
}

impl Transfer {
    pub fn setup(&self) -> Setup {
        match self {
            Transfer::Out { setup, .. } | Transfer::In { setup, .. } => *setup,
        }
    }
}

/// Rev A–D measurement flags (the flags byte of [`MeasParams`]).
pub mod flags {
    /// Keep measuring until the host stops reading (scan mode).
    pub const SCAN: u8 = 0x01;
    /// Lamp off during the measurement.
    pub const LAMP_OFF: u8 = 0x02;
    /// Normal gain; clear means high gain.
    pub const NORMAL_GAIN: u8 = 0x04;
}

/// Rev E measurement flags (the 16-bit flags of [`MeasParamsE`]); Rev E has no high gain.
pub mod flags_e {
    pub const SCAN: u16 = 0x0001;
    pub const RULER_START: u16 = 0x0004;
    pub const RULER_END: u16 = 0x0008;
    pub const LAMP: u16 = 0x0100;
    pub const UV_LED: u16 = 0x0200;
    /// Wavelength-reference LED (both LED bits).
    pub const WAVELENGTH_LED: u16 = 0x0300;
}

/// Rev A–D measurement parameters (set with 0xC1, read back with 0xC2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeasParams {
    /// Integration time in integration clocks.
    pub int_clocks: u16,
    /// Lamp warm-up in sub-clocks (integration clock × divider).
    pub lamp_clocks: u16,
    /// Readings to take.
    pub readings: u16,
    /// [`flags`] bits.
    pub flags: u8,
}

impl MeasParams {
    /// The 8 bytes of 0xC1 (and of the 0xC2 reply): three u16, flags, a zero byte.
    pub fn encode(&self) -> [u8; 8] {
        let mut b = [0u8; 8];
        b[0..2].copy_from_slice(&self.int_clocks.to_be_bytes());
        b[2..4].copy_from_slice(&self.lamp_clocks.to_be_bytes());
        b[4..6].copy_from_slice(&self.readings.to_be_bytes());
        b[6] = self.flags;
        b
    }

    /// Parses the 8-byte reply of 0xC2 (the last byte carries nothing known).
    pub fn parse(reply: &[u8]) -> Result<MeasParams, ReplyError> {
        let b = exact::<8>("measurement parameters (0xC2)", reply)?;
        Ok(MeasParams {
            int_clocks: u16::from_be_bytes([b[0], b[1]]),
            lamp_clocks: u16::from_be_bytes([b[2], b[3]]),
            readings: u16::from_be_bytes([b[4], b[5]]),
            flags: b[6],
        })
    }
}

/// Rev E combined parameters and trigger (0xD4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeasParamsE {
    pub int_clocks: u32,
    pub lamp_clocks: u32,
    pub readings: u32,
    /// [`flags_e`] bits.
    pub flags: u16,
}

impl MeasParamsE {
    /// The 14 bytes of 0xD4: three u32 and the u16 flags.
    pub fn encode(&self) -> [u8; 14] {
        let mut b = [0u8; 14];
        b[0..4].copy_from_slice(&self.int_clocks.to_be_bytes());
        b[4..8].copy_from_slice(&self.lamp_clocks.to_be_bytes());
        b[8..12].copy_from_slice(&self.readings.to_be_bytes());
        b[12..14].copy_from_slice(&self.flags.to_be_bytes());
        b
    }

    pub fn parse(data: &[u8]) -> Result<MeasParamsE, ReplyError> {
        let b = exact::<14>("Rev E measure request (0xD4)", data)?;
        Ok(MeasParamsE {
            int_clocks: u32::from_be_bytes([b[0], b[1], b[2], b[3]]),
            lamp_clocks: u32::from_be_bytes([b[4], b[5], b[6], b[7]]),
            readings: u32::from_be_bytes([b[8], b[9], b[10], b[11]]),
            flags: u16::from_be_bytes([b[12], b[13]]),
        })
    }
}

/// Every vendor request the driver uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Request {
    /// 0xCA: reset with a mask ([`RESET_NORMAL`], [`RESET_POWER`]); the host then waits 100 ms.
    Reset { mask: u8 },
    /// 0xC9: firmware revision, maximum positive sensor value, power state ([`Misc`]).
    GetMisc,
    /// 0xC4: start an EEPROM read; exactly `length` bytes follow on [`EP_DATA_IN`].
    ReadEeprom { address: u32, length: u16 },
    /// 0xC2: read back the Rev A–D measurement parameters.
    GetMeasParams,
    /// 0xC1: Rev A–D measurement parameters.
    SetMeasParams(MeasParams),
    /// 0xC0: Rev A–D trigger; readings follow on [`EP_DATA_IN`].
    Trigger,
    /// 0xCF: select clock mode 1..=max (firmware ≥ 301); the host then waits 10 ms.
    SetClockMode(u8),
    /// 0xD1: the current clock mode ([`ClockMode`], firmware ≥ 301).
    GetClockMode,
    /// 0xD0 with wValue 3: end a pending read of the button endpoint.
    EndSwitchRead,
    /// 0xD9: Rev E EEPROM size.
    GetEepromSize,
    /// 0xD2: chip id (Rev D and E); zeros until the EEPROM was read.
    GetChipId,
    /// 0xD5: Rev E measurement characteristics ([`MeasChar`]).
    GetMeasChar,
    /// 0xD4: Rev E parameters and trigger in one; readings follow on [`EP_DATA_IN`].
    MeasureE(MeasParamsE),
    /// 0xD8: Rev E UV LED voltages before/after.
    GetUvVolts,
    /// 0xD7: Rev E stop the ruler.
    StopRuler,
}

impl Request {
    /// A short name for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Request::Reset { .. } => "reset",
            Request::GetMisc => "get misc",
            Request::ReadEeprom { .. } => "read EEPROM",
            Request::GetMeasParams => "get measurement parameters",
            Request::SetMeasParams(_) => "set measurement parameters",
            Request::Trigger => "trigger measurement",
            Request::SetClockMode(_) => "set clock mode",
            Request::GetClockMode => "get clock mode",
            Request::EndSwitchRead => "end switch read",
            Request::GetEepromSize => "get EEPROM size",
            Request::GetChipId => "get chip id",
            Request::GetMeasChar => "get measurement characteristics",
            Request::MeasureE(_) => "Rev E measure",
            Request::GetUvVolts => "get UV LED volts",
            Request::StopRuler => "stop ruler",
        }
    }

    /// Which revisions understand the request; `None` = both.
    fn only(&self) -> Option<Revision> {
        match self {
            Request::SetMeasParams(_) | Request::Trigger => Some(Revision::AToD),
            Request::GetEepromSize
            | Request::GetMeasChar
            | Request::MeasureE(_)
            | Request::GetUvVolts
            | Request::StopRuler => Some(Revision::E),
            _ => None,
        }
    }

    /// The control transfer for `revision`.
    pub fn encode(&self, revision: Revision) -> Result<Transfer, ControlRequestError> {
        if let Some(only) = self.only() {
            if only != revision {
                return Err(ControlRequestError::WrongRevision {
                    request: self.name(),
                    revision,
                });
            }
        }
        let out = |request: u8, data: Vec<u8>| Transfer::Out {
            setup: Setup::out(request),
            data,
        };
        let input = |request: u8, length: u16| Transfer::In {
            setup: Setup::input(request),
            length,
        };
        Ok(match *self {
            Request::Reset { mask } => match revision {
                Revision::AToD => out(code::RESET, vec![mask]),
                // The second byte's meaning is unknown; zero is what works.
                Revision::E => out(code::RESET, vec![mask, 0]),
            },
            Request::GetMisc => input(code::GET_MISC, 8),
            Request::ReadEeprom { address, length } => {
                let mut d = address.to_be_bytes().to_vec();
                d.extend_from_slice(&length.to_be_bytes());
                if revision == Revision::AToD {
                    d.extend_from_slice(&[0, 0]);
                }
                out(code::READ_EEPROM, d)
            }
            Request::GetMeasParams => input(code::GET_MEAS_PARAMS, 8),
            Request::SetMeasParams(p) => out(code::SET_MEAS_PARAMS, p.encode().to_vec()),
            Request::Trigger => out(code::TRIGGER, Vec::new()),
            Request::SetClockMode(mode) => out(code::SET_CLOCK_MODE, vec![mode]),
            Request::GetClockMode => input(code::GET_CLOCK_MODE, 6),
            Request::EndSwitchRead => Transfer::Out {
                setup: Setup {
                    value: 3,
                    ..Setup::out(code::END_SWITCH_READ)
                },
                data: END_SWITCH_READ_DATA.to_vec(),
            },
            Request::GetEepromSize => input(code::GET_EEPROM_SIZE, 4),
            Request::GetChipId => input(code::GET_CHIP_ID, 8),
            Request::GetMeasChar => input(code::GET_MEAS_CHAR, 16),
            Request::MeasureE(p) => out(code::MEASURE_E, p.encode().to_vec()),
            Request::GetUvVolts => input(code::GET_UV_VOLTS, 4),
            Request::StopRuler => out(code::STOP_RULER, vec![0, 0]),
        })
    }

    /// The request a transfer carries, as a simulated instrument of `revision` sees it; the
    /// inverse of [`Request::encode`].
    pub fn decode(transfer: &Transfer, revision: Revision) -> Result<Request, ControlRequestError> {
        let setup = transfer.setup();
        let unknown = || ControlRequestError::Unknown {
            request_type: setup.request_type,
            request: setup.request,
        };
        let request = match transfer {
            Transfer::Out { setup, data } => {
                if setup.request_type != REQUEST_TYPE_OUT {
                    return Err(unknown());
                }
                let d = data.as_slice();
                match setup.request {
                    code::RESET => match (revision, d) {
                        (Revision::AToD, [mask]) | (Revision::E, [mask, _]) => {
                            Request::Reset { mask: *mask }
                        }
                        _ => return Err(bad_data("reset", d)),
                    },
                    code::READ_EEPROM => {
                        let want = if revision == Revision::AToD { 8 } else { 6 };
                        if d.len() != want {
                            return Err(bad_data("read EEPROM", d));
                        }
                        Request::ReadEeprom {
                            address: u32::from_be_bytes([d[0], d[1], d[2], d[3]]),
                            length: u16::from_be_bytes([d[4], d[5]]),
                        }
                    }
                    code::SET_MEAS_PARAMS => Request::SetMeasParams(
                        MeasParams::parse(d)
                            .map_err(|_| bad_data("set measurement parameters", d))?,
                    ),
                    code::TRIGGER if d.is_empty() => Request::Trigger,
                    code::SET_CLOCK_MODE => match d {
                        [mode] => Request::SetClockMode(*mode),
                        _ => return Err(bad_data("set clock mode", d)),
                    },
                    code::END_SWITCH_READ => Request::EndSwitchRead,
                    code::MEASURE_E => Request::MeasureE(
                        MeasParamsE::parse(d).map_err(|_| bad_data("Rev E measure", d))?,
                    ),
                    code::STOP_RULER => Request::StopRuler,
                    _ => return Err(unknown()),
                }
            }
            Transfer::In { setup, .. } => {
                if setup.request_type != REQUEST_TYPE_IN {
                    return Err(unknown());
                }
                match setup.request {
                    code::GET_MISC => Request::GetMisc,
                    code::GET_MEAS_PARAMS => Request::GetMeasParams,
                    code::GET_CLOCK_MODE => Request::GetClockMode,
                    code::GET_EEPROM_SIZE => Request::GetEepromSize,
                    code::GET_CHIP_ID => Request::GetChipId,
                    code::GET_MEAS_CHAR => Request::GetMeasChar,
                    code::GET_UV_VOLTS => Request::GetUvVolts,
                    _ => return Err(unknown()),
                }
            }
        };
        if let Some(only) = request.only() {
            if only != revision {
                return Err(ControlRequestError::WrongRevision {
                    request: request.name(),
                    revision,
                });
            }
        }
        Ok(request)
    }
}

fn bad_data(request: &'static str, data: &[u8]) -> ControlRequestError {
    ControlRequestError::BadData {
        request,
        data: data.to_vec(),
    }
}

/// A USB control request of the i1Pro that cannot be encoded or decoded.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ControlRequestError {
    #[error("the {request} request does not exist on a Rev {revision:?} i1Pro")]
    WrongRevision {
        request: &'static str,
        revision: Revision,
    },
    #[error("unknown i1Pro request: bmRequestType {request_type:#04x}, bRequest {request:#04x}")]
    Unknown { request_type: u8, request: u8 },
    #[error("the {request} request carries malformed data {data:02x?}")]
    BadData {
        request: &'static str,
        data: Vec<u8>,
    },
}

#[cfg(test)]
mod tests;
