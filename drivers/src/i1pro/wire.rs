//! The i1Pro's USB exchanges: each vendor request as a control transfer, the EEPROM read and
//! the measurements whose readings arrive on the bulk endpoint. Everything above this file
//! speaks in typed requests and raw readings.

use std::time::Duration;

use metamer_protocols::i1pro::commands::{
    flags, flags_e, MeasParams, MeasParamsE, Setup, EEPROM_READ_TIMEOUT_S, EP_DATA_IN,
};
use metamer_protocols::i1pro::readings::{self, RawReading};
use metamer_protocols::i1pro::timing::{self, readings_timeout_s};
use metamer_protocols::i1pro::{Request, Revision, Transfer};
use metamer_protocols::transcript::TransferKind;

use super::error::{I1ProError, TransferError};
use crate::link::usb::{ControlSetup, UsbLink};
use crate::link::LinkError;
use crate::DriverError;

/// Control transfers time out after 2 s (the codec's constant).
const CONTROL_TIMEOUT: Duration = Duration::from_secs(2);

/// The lamp is lit this long before a reflective reading integrates, seconds.
pub const LAMP_WARMUP_S: f64 = 0.2;

/// One measurement to take: `readings` readings of `integration_s` each.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shot {
    pub integration_s: f64,
    pub readings: usize,
    pub lamp: bool,
}

/// The link with what the transfers need to know about the unit.
pub struct Wire<L> {
    pub link: L,
    pub revision: Revision,
    /// GetMisc's "largest positive value + 1" (Rev A–D sign limit).
    pub max_positive: u16,
    /// Integration clock period, seconds.
    pub clock_s: f64,
    /// Lamp clock period (integration clock × divider), seconds.
    pub sub_clock_s: f64,
    /// Firmware revision, for the timeout rule of firmware 200–399.
    pub firmware: u16,
    /// The integration time of the previous shot (firmware 200–399 measures it first).
    previous_s: f64,
    /// Wait out the instrument's settling times (a real unit); replays and the emulator
    /// answer when they are ready.
    pub settle: bool,
}

fn setup(s: Setup) -> ControlSetup {
    ControlSetup {
        request_type: s.request_type,
        request: s.request,
        value: s.value,
        index: s.index,
    }
}

impl<L: UsbLink> Wire<L> {
    /// A link to a unit of `revision` whose details are not known yet.
    pub fn new(link: L, revision: Revision) -> Wire<L> {
        Wire {
            link,
            revision,
            max_positive: u16::MAX,
            clock_s: f64::from(timing::CLOCK_US_BEFORE_301) * 1e-6,
            sub_clock_s: f64::from(timing::CLOCK_US_BEFORE_301)
                * 1e-6
                * f64::from(timing::SUB_CLOCK_DIVIDER_BEFORE_301),
            firmware: 0,
            previous_s: 0.0,
            settle: false,
        }
    }

    fn failed(&self, request: &'static str, source: LinkError) -> DriverError {
        match source {
            LinkError::Disconnected { received } => DriverError::Disconnected {
                port: self.link.describe(),
                command: request.to_string(),
                received: metamer_protocols::transcript::show_bytes(&received),
            },
            LinkError::Replay(_) | LinkError::Record { .. } => DriverError::Link(source),
            source => DriverError::I1Pro(I1ProError::Transfer(TransferError {
                device: self.link.describe(),
                request,
                source,
            })),
        }
    }

    /// Sends one request; the reply's bytes for IN requests, empty for OUT.
    pub fn request(&mut self, r: Request) -> Result<Vec<u8>, DriverError> {
        let name = r.name();
        let transfer = r.encode(self.revision).map_err(I1ProError::from)?;
        let result = match &transfer {
            Transfer::Out { setup: s, data } => self
                .link
                .control_out(setup(*s), data, CONTROL_TIMEOUT)
                .map(|()| Vec::new()),
            Transfer::In { setup: s, length } => {
                self.link
                    .control_in(setup(*s), usize::from(*length), CONTROL_TIMEOUT)
            }
        };
        result.map_err(|e| self.failed(name, e))
    }

    /// Reads `length` bytes from the EEPROM at `address`; a short read is an error.
    pub fn read_eeprom(&mut self, address: u32, length: u16) -> Result<Vec<u8>, DriverError> {
        self.request(Request::ReadEeprom { address, length })?;
        let want = usize::from(length);
        let bytes = self
            .link
            .read(
                TransferKind::Bulk,
                EP_DATA_IN,
                want,
                Duration::from_secs_f64(EEPROM_READ_TIMEOUT_S),
            )
            .map_err(|e| self.failed("read EEPROM", e))?;
        if bytes.len() != want {
            return Err(I1ProError::ShortRead {
                what: "the EEPROM",
                got: bytes.len(),
                expected: want,
            }
            .into());
        }
        Ok(bytes)
    }

    /// Takes one shot and returns its raw readings.
    ///
    /// The trigger/read race: the instrument starts sending its readings as soon as it has
    /// integrated, and a Rev A unit gives up if no bulk read is waiting for them within
    /// about 40 ms of the trigger. ArgyllCMS therefore posts an asynchronous bulk read
    /// before it triggers. Our links are blocking, so the read is issued as the very next
    /// call after the trigger returns, with nothing in between (no logging, no allocation
    /// beyond the buffer): that is microseconds after the trigger, far inside the window,
    /// and the read's own timeout covers the whole integration. The order on the wire is
    /// therefore trigger, then read, and transcripts record it so.
    pub fn shot(&mut self, shot: Shot) -> Result<Vec<RawReading>, DriverError> {
        let int_clocks = timing::clocks(
            "integration time",
            shot.integration_s,
            self.clock_s,
            match self.revision {
                Revision::AToD => u64::from(u16::MAX),
                Revision::E => u64::from(u32::MAX),
            },
        )
        .map_err(I1ProError::from)?;
        let lamp_clocks = if shot.lamp {
            timing::lamp_clocks(LAMP_WARMUP_S, self.sub_clock_s).map_err(I1ProError::from)?
        } else {
            0
        };
        let lamp_s = if shot.lamp { LAMP_WARMUP_S } else { 0.0 };
        let previous = timing::measures_previous_too(self.firmware).then_some(self.previous_s);
        let timeout = readings_timeout_s(
            shot.readings as u32,
            shot.integration_s,
            shot.lamp.then_some(lamp_s),
            previous,
        );
        let n = u16::try_from(shot.readings).unwrap_or(u16::MAX);
        let trigger = match self.revision {
            Revision::AToD => {
                let mut f = flags::NORMAL_GAIN;
                if !shot.lamp {
                    f |= flags::LAMP_OFF;
                }
                self.request(Request::SetMeasParams(MeasParams {
                    int_clocks: int_clocks as u16,
                    lamp_clocks: lamp_clocks as u16,
                    readings: n,
                    flags: f,
                }))?;
                Request::Trigger
            }
            Revision::E => Request::MeasureE(MeasParamsE {
                int_clocks: int_clocks as u32,
                lamp_clocks: lamp_clocks as u32,
                readings: u32::from(n),
                flags: if shot.lamp { flags_e::LAMP } else { 0 },
            }),
        };
        let want = shot.readings * self.revision.bytes_per_reading();
        self.request(trigger)?;
        let got = self.link.read(
            TransferKind::Bulk,
            EP_DATA_IN,
            want,
            crate::link::duration_s(timeout),
        );
        let bytes = got.map_err(|e| self.failed("read measurement", e))?;
        self.previous_s = shot.integration_s;
        if bytes.len() != want {
            return Err(I1ProError::ShortRead {
                what: "a measurement",
                got: bytes.len(),
                expected: want,
            }
            .into());
        }
        Ok(
            readings::parse(&bytes, self.revision, shot.readings, self.max_positive)
                .map_err(I1ProError::from)?,
        )
    }
}
