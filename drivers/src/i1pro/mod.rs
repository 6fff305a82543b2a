//! The X-Rite i1Pro (Rev A–D) and i1Pro 2 (Rev E) spectrophotometer on USB, behind
//! [`Instrument`]: emissive readings with an automatic or fixed integration time,
//! reflective readings with the dark and white-tile calibrations, and ambient readings
//! where the unit has the diffuser. The protocol and the raw → spectrum pipeline are the
//! codec's (`metamer_protocols::i1pro`); this module only sequences them on a
//! [`UsbLink`](crate::link::usb::UsbLink).
//!
//! Not done: the Rev E wavelength re-calibration with its LED (the factory mapping from the
//! EEPROM is used as it is), high gain, scans, and restoring calibrations from the EEPROM.

pub mod budget;
pub mod clock;
pub mod emulator;
mod engine;
pub mod error;
pub mod open;
pub mod synthetic;
mod wire;

use std::sync::Arc;

use metamer_color::{
    radiance_to_xyz, reflectance_to_xyz, Illuminant, ObserverKind, Outside, Quantity, Spectrum, Xyz,
};
use metamer_protocols::i1pro::calibration::AmbientTable;
use metamer_protocols::i1pro::pipeline::{self, AbsRaw};
use metamer_protocols::i1pro::replies::{MeasChar, Misc};
use metamer_protocols::i1pro::timing::ClockUnit;
use metamer_protocols::i1pro::{
    commands, eeprom, replies, wavelength, Calibration, Eeprom, GridSpectrum, Model, Request,
    Revision, BANDS, START_NM, STEP_NM,
};

pub use clock::{Clock, ManualClock, ScaledClock, SystemClock};
pub use error::I1ProError;

use self::engine::DarkPair;
use self::wire::Wire;
use crate::instrument::{
    now_s, CalibrationCondition, CalibrationNeed, CalibrationOutcome, Capabilities, Flag,
    Instrument, InstrumentInfo, MeasureMode, ModeInfo, OptionInfo, OptionValues, Reading,
};
use crate::link::usb::UsbLink;
use crate::DriverError;

/// The model name in readings, transcripts and `sim:i1pro`.
pub const MODEL: &str = "i1pro";
/// How long a dark calibration stays valid on Rev A–D, seconds.
pub const DARK_VALID_A_TO_D_S: f64 = 30.0 * 60.0;
/// How long a dark calibration stays valid on Rev E, seconds.
pub const DARK_VALID_E_S: f64 = 60.0 * 60.0;
/// How long a white calibration stays valid, seconds.
pub const WHITE_VALID_S: f64 = 60.0 * 60.0;

/// An i1Pro on any USB link (real, replayed, recorded or the emulator's).
pub struct I1Pro<L: UsbLink> {
    wire: Wire<L>,
    cal: Calibration,
    info: InstrumentInfo,
    clock: Arc<dyn Clock>,
    /// A fixed emissive integration time; None chooses it per reading.
    integration_s: Option<f64>,
    darks: Option<(DarkPair, f64)>,
    reflective_dark: Option<(AbsRaw, f64)>,
    /// What the EEPROM's ambient table holds, to say why a unit that claims the diffuser
    /// has no ambient mode.
    ambient_table: AmbientTable,
    /// Reflective calibration factors per band, and when they were made.
    white: Option<(GridSpectrum, f64)>,
}

fn revision_name(r: Revision) -> &'static str {
    match r {
        Revision::AToD => "Rev A–D",
        Revision::E => "Rev E (i1Pro 2)",
    }
}

impl<L: UsbLink> I1Pro<L> {
    /// Opens the unit: reads its firmware revision and power state (GetMisc), resets it,
    /// reads its clock, reads and parses its whole EEPROM. A unit with firmware 600 or later
    /// is taken as Rev E [I: the endpoint count that also tells it is not visible through
    /// the link]. `clock` judges calibration validity.
    pub fn open(link: L, clock: Arc<dyn Clock>) -> Result<I1Pro<L>, DriverError> {
        I1Pro::open_with(link, clock, false)
    }

    /// [`I1Pro::open`]; `settle` waits 100 ms between power polls, as a real unit needs.
    pub fn open_with(
        link: L,
        clock: Arc<dyn Clock>,
        settle: bool,
    ) -> Result<I1Pro<L>, DriverError> {
        let mut wire = Wire::new(link, Revision::AToD);
        wire.settle = settle;
        let misc =
            Misc::parse(&wire.request(Request::GetMisc)?).map_err(|e| reply("get misc", e))?;
        let revision = if misc.firmware >= 600 {
            Revision::E
        } else {
            Revision::AToD
        };
        wire.revision = revision;
        wire.firmware = misc.firmware;
        wire.max_positive = misc.max_positive;
        if !misc.high_power() {
            power_up(&mut wire)?;
        }
        wire.request(Request::Reset {
            mask: commands::RESET_NORMAL,
        })?;
        let size = match revision {
            Revision::E => {
                let m = MeasChar::parse(&wire.request(Request::GetMeasChar)?)
                    .map_err(|e| reply("get measurement characteristics", e))?;
                wire.fixed_clock(ClockUnit {
                    clock_s: m.clock_s(),
                    divider: m.divider,
                });
                let size = replies::parse_eeprom_size(&wire.request(Request::GetEepromSize)?)
                    .map_err(|e| reply("get EEPROM size", e))?;
                size as usize
            }
            Revision::AToD => {
                if misc.has_clock_modes() {
                    wire.read_clock_modes()?;
                } else {
                    wire.fixed_clock(wire::CLOCK_BEFORE_301);
                }
                eeprom::SIZE_A_TO_D
            }
        };
        let length = u16::try_from(size).map_err(|_| I1ProError::ShortRead {
            what: "the EEPROM size",
            got: size,
            expected: usize::from(u16::MAX),
        })?;
        let image = wire.read_eeprom(0, length)?;
        let cal = unit_calibration(&image, revision)?;
        let ambient_table =
            AmbientTable::in_eeprom(&Eeprom::parse(&image, revision).map_err(I1ProError::from)?);
        let info = InstrumentInfo {
            model: MODEL.into(),
            serial: Some(cal.serial.to_string()),
            firmware: Some(format!("{} ({})", misc.firmware, revision_name(revision))),
            connection: wire.link.describe(),
        };
        Ok(I1Pro {
            wire,
            cal,
            info,
            clock,
            integration_s: None,
            darks: None,
            reflective_dark: None,
            ambient_table,
            white: None,
        })
    }

    /// The link, e.g. to check that a replayed transcript was played to its end.
    pub fn link(&self) -> &L {
        &self.wire.link
    }

    /// The unit's calibration as read from its EEPROM.
    pub fn calibration(&self) -> &Calibration {
        &self.cal
    }

    /// The hardware revision.
    pub fn revision(&self) -> Revision {
        self.wire.revision
    }

    fn dark_valid_s(&self) -> f64 {
        match self.wire.revision {
            Revision::AToD => DARK_VALID_A_TO_D_S,
            Revision::E => DARK_VALID_E_S,
        }
    }

    fn supports(&self, mode: MeasureMode) -> bool {
        match mode {
            MeasureMode::Emissive => true,
            MeasureMode::Reflective => self.cal.white_reference.is_some(),
            MeasureMode::Ambient => self.cal.has_ambient(),
        }
    }

    fn unsupported(&self, mode: MeasureMode) -> DriverError {
        DriverError::Unsupported {
            instrument: MODEL.into(),
            what: match mode {
                MeasureMode::Ambient if self.cal.claims_ambient() => {
                    let table = match self.ambient_table {
                        AmbientTable::Unusable { band, value } => format!(
                            "holds {value} at {} nm, not a positive factor",
                            START_NM + STEP_NM * band as f64
                        ),
                        _ => "is the \"no ambient\" marker (−1 in every band) that units without the diffuser store".into(),
                    };
                    format!(
                        "ambient measurements: its EEPROM's capability bits claim the diffuser, but its ambient calibration (key 0x044E) {table}, so an ambient reading would be meaningless; emissive and reflective measurements are unaffected"
                    )
                }
                MeasureMode::Ambient => "ambient measurements: this unit has no diffuser".into(),
                MeasureMode::Reflective => {
                    "reflective measurements: this unit has no white reference".into()
                }
                MeasureMode::Emissive => "emissive measurements".into(),
            },
        }
    }

    /// Why `mode` needs calibrating now, or None when its calibrations are valid.
    fn due(&self, mode: MeasureMode) -> Option<String> {
        let now = self.clock.now_s();
        let age = |at: f64, valid: f64, what: &str| {
            (now - at > valid)
                .then(|| format!("the {what} calibration expired after {} min", valid / 60.0))
        };
        match mode {
            MeasureMode::Emissive | MeasureMode::Ambient => match &self.darks {
                None => Some("no dark calibration yet".into()),
                Some((_, at)) => age(*at, self.dark_valid_s(), "dark"),
            },
            MeasureMode::Reflective => match (&self.reflective_dark, &self.white) {
                (None, _) | (_, None) => Some("no white-tile calibration yet".into()),
                (Some((_, d)), Some((_, w))) => {
                    age(*d, self.dark_valid_s(), "dark").or_else(|| age(*w, WHITE_VALID_S, "white"))
                }
            },
        }
    }

    fn reading(&self, values: Vec<f64>, quantity: Quantity, integration_s: f64) -> Reading {
        let spectrum = Spectrum::measured(START_NM, STEP_NM, values)
            .expect("36 bands on an even grid")
            .with_quantity(quantity);
        let xyz: Xyz = match quantity {
            Quantity::Reflectance => reflectance_to_xyz(
                &spectrum.clone().with_outside(Outside::HoldEnds),
                &Illuminant::D65.spectrum(),
                ObserverKind::Cie1931,
            ),
            _ => radiance_to_xyz(&spectrum, ObserverKind::Cie1931),
        };
        let xyy = xyz.to_xyy();
        Reading {
            xyz,
            xyy: [xyy.x, xyy.y, xyy.luminance],
            spectrum: Some(spectrum),
            flags: Vec::<Flag>::new(),
            integration_s: Some(integration_s),
            instrument: MODEL.into(),
            timestamp_s: now_s(),
        }
    }
}

/// How often GetMisc is asked whether a unit in low power has come up, 100 ms apart.
const POWER_POLLS: usize = 15;

/// Brings a unit that reports low power up: reset with the power mask, then GetMisc until
/// the power state changes (Argyll polls 15 times, 100 ms apart).
fn power_up<L: UsbLink>(wire: &mut Wire<L>) -> Result<(), DriverError> {
    wire.request(Request::Reset {
        mask: commands::RESET_POWER,
    })?;
    for _ in 0..POWER_POLLS {
        let misc =
            Misc::parse(&wire.request(Request::GetMisc)?).map_err(|e| reply("get misc", e))?;
        if misc.high_power() {
            return Ok(());
        }
        if wire.settle {
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
    }
    Err(I1ProError::LowPower.into())
}

/// The calibration of a unit from its EEPROM image. On Rev E the bands are built from the
/// unit's factory cell → wavelength mapping (key 0x2F63) rather than taken from the Rev A–D
/// filter tables.
pub fn unit_calibration(image: &[u8], revision: Revision) -> Result<Calibration, I1ProError> {
    let model = match revision {
        Revision::AToD => Model::I1Pro,
        Revision::E => Model::I1Pro2,
    };
    let items = Eeprom::parse(image, revision)?;
    let mut cal = Calibration::from_eeprom(&items, model)?;
    if let Some(e) = &cal.rev_e {
        cal.filter = wavelength::filter_from_poly(&e.wavelength_poly_emissive)?;
    }
    Ok(cal)
}

fn reply(request: &'static str, source: replies::ReplyError) -> DriverError {
    I1ProError::Reply { request, source }.into()
}

/// The codec's spectra are in mW (ArgyllCMS's unit); the colour core's in W.
fn watts(s: &[f64; BANDS]) -> Vec<f64> {
    s.iter().map(|v| v / 1000.0).collect()
}

impl<L: UsbLink> Instrument for I1Pro<L> {
    fn info(&self) -> InstrumentInfo {
        self.info.clone()
    }

    fn capabilities(&self) -> Capabilities {
        let dark = CalibrationNeed {
            name: "dark".into(),
            condition: CalibrationCondition::OnWhiteTile,
            valid_for_s: Some(self.dark_valid_s()),
        };
        let white = CalibrationNeed {
            name: "white".into(),
            condition: CalibrationCondition::OnWhiteTile,
            valid_for_s: Some(WHITE_VALID_S),
        };
        let modes = MeasureMode::ALL
            .into_iter()
            .filter(|m| self.supports(*m))
            .map(|mode| ModeInfo {
                mode,
                spot: false,
                calibrations: match mode {
                    MeasureMode::Reflective => vec![dark.clone(), white.clone()],
                    _ => vec![dark.clone()],
                },
            })
            .collect();
        Capabilities {
            modes,
            spectral: true,
            acceptance_angle_deg: None,
            luminance_range_cd_m2: None,
            options: vec![OptionInfo {
                name: "integration_s".into(),
                description: "emissive and ambient integration time; auto finds it per reading"
                    .into(),
                values: OptionValues::Number {
                    min: engine::shortest(&self.wire).unwrap_or(self.cal.min_integration_s),
                    max: engine::longest(&self.wire, &self.cal).unwrap_or(engine::DARK_LONG_S),
                    unit: "s".into(),
                    auto: true,
                },
                default: "auto".into(),
            }],
        }
    }

    fn calibration_needed(
        &mut self,
        mode: MeasureMode,
    ) -> Result<Option<CalibrationCondition>, DriverError> {
        if !self.supports(mode) {
            return Err(self.unsupported(mode));
        }
        Ok(self.due(mode).map(|_| CalibrationCondition::OnWhiteTile))
    }

    /// Every calibration of the i1Pro is done on its white tile: the tile covers the sensor
    /// for the darks (lamp off) and is the reference for the white (lamp on).
    fn calibrate(
        &mut self,
        mode: MeasureMode,
        condition: &CalibrationCondition,
    ) -> Result<CalibrationOutcome, DriverError> {
        if !self.supports(mode) {
            return Err(self.unsupported(mode));
        }
        if *condition != CalibrationCondition::OnWhiteTile {
            return Ok(CalibrationOutcome::Needs(CalibrationCondition::OnWhiteTile));
        }
        match mode {
            MeasureMode::Emissive | MeasureMode::Ambient => {
                let pair = engine::dark_pair(&mut self.wire, &self.cal)?;
                self.darks = Some((pair, self.clock.now_s()));
            }
            MeasureMode::Reflective => {
                let dark = engine::dark(
                    &mut self.wire,
                    &self.cal,
                    engine::REFLECTIVE_S,
                    engine::REFLECTIVE_READINGS,
                )?
                .mean;
                let factors = engine::white(&mut self.wire, &self.cal, &dark)?;
                let now = self.clock.now_s();
                self.reflective_dark = Some((dark, now));
                self.white = Some((factors, now));
            }
        }
        Ok(CalibrationOutcome::Done)
    }

    fn measure(&mut self, request: &crate::instrument::Request) -> Result<Reading, DriverError> {
        let mode = request.mode;
        if !self.supports(mode) {
            return Err(self.unsupported(mode));
        }
        if let Some(reason) = self.due(mode) {
            return Err(DriverError::NeedsCalibration {
                instrument: MODEL.into(),
                mode,
                condition: CalibrationCondition::OnWhiteTile,
                reason,
            });
        }
        match mode {
            MeasureMode::Emissive | MeasureMode::Ambient => {
                let (darks, _) = self.darks.as_ref().expect("checked by due()");
                let p =
                    engine::emissive_shot(&mut self.wire, &self.cal, darks, self.integration_s)?;
                if mode == MeasureMode::Emissive {
                    let s = pipeline::emissive(&self.cal, &p.spectrum);
                    Ok(self.reading(watts(&s), Quantity::Radiance, p.integration_s))
                } else {
                    let s = pipeline::ambient(&self.cal, &p.spectrum).map_err(I1ProError::from)?;
                    Ok(self.reading(watts(&s), Quantity::Irradiance, p.integration_s))
                }
            }
            MeasureMode::Reflective => {
                let (dark, _) = self.reflective_dark.as_ref().expect("checked by due()");
                let (factors, _) = self.white.as_ref().expect("checked by due()");
                let (r, p) = engine::reflective(&mut self.wire, &self.cal, dark, factors)?;
                if p.averaged.saturated {
                    return Err(I1ProError::SaturatedSample.into());
                }
                Ok(self.reading(r.to_vec(), Quantity::Reflectance, p.integration_s))
            }
        }
    }

    fn set_option(&mut self, name: &str, value: &str) -> Result<(), DriverError> {
        if name != "integration_s" {
            return Err(DriverError::UnknownOption {
                instrument: MODEL.into(),
                option: name.into(),
                known: "integration_s".into(),
            });
        }
        if value == "auto" {
            self.integration_s = None;
            return Ok(());
        }
        // The clock's limits, shown as the round numbers they stand for (the longest is
        // 2 s on a whole number of clocks, a little over).
        let min = engine::shortest(&self.wire)?;
        let max = engine::longest(&self.wire, &self.cal)?;
        let (low, high) = ((min * 1e6).round() / 1e6, (max * 1e3).round() / 1e3);
        match value.trim().parse::<f64>() {
            Ok(t) if t.is_finite() && (low..=max.max(high)).contains(&t) => {
                self.integration_s = Some(t);
                Ok(())
            }
            _ => Err(DriverError::BadOption {
                instrument: MODEL.into(),
                option: name.into(),
                value: value.into(),
                message: format!("expected auto or a time in seconds from {low} to {high}"),
            }),
        }
    }

    fn option_values(&self) -> Vec<(String, String)> {
        vec![(
            "integration_s".into(),
            self.integration_s
                .map(|t| t.to_string())
                .unwrap_or_else(|| "auto".into()),
        )]
    }
}

#[cfg(test)]
mod real_unit_tests;
#[cfg(test)]
mod tests;
