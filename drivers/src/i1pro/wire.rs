//! The i1Pro's USB exchanges: each vendor request as a control transfer, the EEPROM read and
//! the measurements whose readings arrive on the bulk endpoint. Everything above this file
//! speaks in typed requests and raw readings.

use std::time::Duration;

use metamer_protocols::i1pro::commands::{
    flags, flags_e, MeasParams, MeasParamsE, Setup, EEPROM_READ_TIMEOUT_S, EP_DATA_IN,
};
use metamer_protocols::i1pro::readings::{self, RawReading};
use metamer_protocols::i1pro::replies::ClockMode;
use metamer_protocols::i1pro::timing::{self, readings_timeout_s, ClockUnit};
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

/// After SetClockMode the host waits this long before the next request (ArgyllCMS's
/// 10 ms), seconds.
pub const CLOCK_MODE_SETTLE_S: f64 = 0.01;

/// Rev A–D firmware before 301 has one fixed clock: 68 µs, 130 to the sub-clock.
pub const CLOCK_BEFORE_301: ClockUnit = ClockUnit {
    clock_s: timing::CLOCK_US_BEFORE_301 as f64 * 1e-6,
    divider: timing::SUB_CLOCK_DIVIDER_BEFORE_301 as u32,
};

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
    /// The unit's usable clock modes, mode 1 first: one on Rev E and on firmware before
    /// 301, as many as GetClockMode reports (less those in "subtract mode") after.
    pub modes: Vec<ClockChoice>,
    /// Index in `modes` of the mode in force.
    current: usize,
    /// Firmware revision, for the timeout rule of firmware 200–399.
    pub firmware: u16,
    /// The integration time of the previous shot (firmware 200–399 measures it first).
    previous_s: f64,
    /// Wait out the instrument's settling times (a real unit); replays and the emulator
    /// answer when they are ready.
    pub settle: bool,
}

/// One clock mode the driver may select.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClockChoice {
    /// The number SetClockMode selects it by; None where the clock cannot be changed.
    pub number: Option<u8>,
    pub unit: ClockUnit,
}

/// An integration time as the instrument will run it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntegrationPlan {
    /// Index in [`Wire::modes`].
    pub mode: usize,
    pub clocks: u64,
    /// `clocks` × the mode's clock period.
    pub integration_s: f64,
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
            modes: vec![ClockChoice {
                number: None,
                unit: CLOCK_BEFORE_301,
            }],
            current: 0,
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

    /// A unit whose clock cannot be changed (Rev E, and firmware before 301).
    pub fn fixed_clock(&mut self, unit: ClockUnit) {
        self.modes = vec![ClockChoice { number: None, unit }];
        self.current = 0;
    }

    /// The most integration clocks a request carries: 16 bits on Rev A–D, 32 on Rev E.
    pub fn max_clocks(&self) -> u64 {
        match self.revision {
            Revision::AToD => u64::from(u16::MAX),
            Revision::E => u64::from(u32::MAX),
        }
    }

    /// The shortest integration time the unit's clock modes allow.
    pub fn shortest_s(&self) -> f64 {
        let units: Vec<ClockUnit> = self.modes.iter().map(|m| m.unit).collect();
        timing::shortest_s(&units).unwrap_or(CLOCK_BEFORE_301.shortest_s())
    }

    /// The clock mode and clock count that integrate `t`: the first mode in which `t` is at
    /// least one sub-clock (see [`timing::pick_mode`]). A time no mode can run is an error
    /// before anything is sent, never a request the unit would have to refuse.
    pub fn plan(&self, t: f64) -> Result<IntegrationPlan, I1ProError> {
        let units: Vec<ClockUnit> = self.modes.iter().map(|m| m.unit).collect();
        let (mode, clocks) =
            timing::pick_mode(&units, t, self.max_clocks()).ok_or(I1ProError::IntegrationTime {
                seconds: t,
                shortest_s: self.shortest_s(),
            })?;
        Ok(IntegrationPlan {
            mode,
            clocks,
            integration_s: clocks as f64 * units[mode].clock_s,
        })
    }

    /// Reads the clock modes of a Rev A–D unit with firmware ≥ 301: GetClockMode gives
    /// the number of modes; with more than one, each is selected in turn (SetClockMode) and
    /// read back, as ArgyllCMS does when it looks for the mode an integration time needs.
    /// The last one read stays in force. Modes in "subtract mode" (flag bit 0), which
    /// ArgyllCMS has never seen used and whose readings its pipeline refuses, are left out.
    pub fn read_clock_modes(&mut self) -> Result<(), DriverError> {
        let first = self.get_clock_mode()?;
        let mut found = Vec::new();
        if first.max <= 1 {
            found.push((first.current.max(1), first));
        } else {
            for number in 1..=first.max {
                found.push((number, self.set_clock_mode(number)?));
            }
        }
        let modes: Vec<ClockChoice> = found
            .iter()
            .filter(|(_, c)| !c.subtract_mode())
            .map(|(number, c)| ClockChoice {
                number: (first.max > 1).then_some(*number),
                unit: ClockUnit {
                    clock_s: c.clock_s(),
                    divider: u32::from(c.sub_clock_divider),
                },
            })
            .collect();
        if modes.is_empty() {
            return Err(I1ProError::ClockModes {
                problem: "every clock mode is in subtract mode, which no known driver reads".into(),
            }
            .into());
        }
        self.current = modes.len() - 1;
        self.modes = modes;
        Ok(())
    }

    fn get_clock_mode(&mut self) -> Result<ClockMode, DriverError> {
        let c = ClockMode::parse(&self.request(Request::GetClockMode)?).map_err(|source| {
            I1ProError::Reply {
                request: "get clock mode",
                source,
            }
        })?;
        if c.clock_us == 0 || c.sub_clock_divider == 0 {
            return Err(I1ProError::ClockModes {
                problem: format!(
                    "mode {} reports a clock of {} µs and a divider of {}",
                    c.current, c.clock_us, c.sub_clock_divider
                ),
            }
            .into());
        }
        Ok(c)
    }

    /// Selects clock mode `number`, waits the 10 ms the unit needs and reads it back.
    fn set_clock_mode(&mut self, number: u8) -> Result<ClockMode, DriverError> {
        self.request(Request::SetClockMode(number))?;
        if self.settle {
            std::thread::sleep(Duration::from_secs_f64(CLOCK_MODE_SETTLE_S));
        }
        let c = self.get_clock_mode()?;
        if c.current != number {
            return Err(I1ProError::ClockModes {
                problem: format!(
                    "asked for clock mode {number}, the unit reports {}",
                    c.current
                ),
            }
            .into());
        }
        Ok(c)
    }

    /// Puts mode `index` in force if it is not.
    fn select(&mut self, index: usize) -> Result<(), DriverError> {
        if index == self.current {
            return Ok(());
        }
        let mode = self.modes[index];
        if let Some(number) = mode.number {
            let c = self.set_clock_mode(number)?;
            if u32::from(c.sub_clock_divider) != mode.unit.divider
                || (c.clock_s() - mode.unit.clock_s).abs() > 1e-12
            {
                return Err(I1ProError::ClockModes {
                    problem: format!(
                        "clock mode {number} now reports {} µs × {}, not what it reported when the unit was opened",
                        c.clock_us, c.sub_clock_divider
                    ),
                }
                .into());
            }
        }
        self.current = index;
        Ok(())
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
    ///
    /// The integration time picks the clock mode (see [`Wire::plan`]); a mode other than
    /// the one in force is selected first.
    pub fn shot(&mut self, shot: Shot) -> Result<Vec<RawReading>, DriverError> {
        let plan = self.plan(shot.integration_s)?;
        self.select(plan.mode)?;
        let int_clocks = plan.clocks;
        let lamp_clocks = if shot.lamp {
            timing::lamp_clocks(LAMP_WARMUP_S, self.modes[plan.mode].unit.sub_clock_s())
                .map_err(I1ProError::from)?
        } else {
            0
        };
        let lamp_s = if shot.lamp { LAMP_WARMUP_S } else { 0.0 };
        let previous = timing::measures_previous_too(self.firmware).then_some(self.previous_s);
        let timeout = readings_timeout_s(
            shot.readings as u32,
            plan.integration_s,
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
        self.previous_s = plan.integration_s;
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
