//! The made-up rig of the session engine test: a screen, a spot meter that reads it, a
//! spectrometer with dark and white calibrations that expire, and an operator who places
//! the spectrometer where the prompts say.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use metamer::image::Drive8Image;

use metamer::session::{
    Answer, Operator, OperatorError, Placement, Screen, ScreenError, ScriptedOperator,
};
use metamer_drivers::{
    CalibrationCondition, CalibrationNeed, CalibrationOutcome, Capabilities, DriverError,
    Instrument, InstrumentInfo, MeasureMode, ModeInfo, Reading, Request,
};

/// Measurements a spectrometer calibration lasts.
pub const VALID_FOR: usize = 2;

/// What the rig looks at: the screen's drive values and the tile under the spectrometer.
#[derive(Default)]
pub struct World {
    pub rgb: [u8; 3],
    pub tile: usize,
}

pub type Shared = Arc<Mutex<World>>;

pub struct FakeScreen(pub Shared);

impl Screen for FakeScreen {
    fn show(&mut self, rgb: [u8; 3]) -> Result<(), ScreenError> {
        self.0.lock().unwrap().rgb = rgb;
        Ok(())
    }
    fn spec(&self) -> String {
        "fake".into()
    }
    fn describe(&self) -> String {
        "the session engine test's made-up screen".into()
    }
    /// The engine shows colours only; an image has no place on this rig.
    fn show_image(&mut self, _: &Drive8Image) -> Result<Placement, ScreenError> {
        Err(ScreenError::Backend {
            screen: self.spec(),
            source: "the made-up screen shows colours only".into(),
        })
    }
    /// No image is ever shown here, so none can slide.
    fn shift_image(&mut self, _: [i64; 2]) -> Result<(), ScreenError> {
        Err(ScreenError::NoImage {
            screen: self.spec(),
        })
    }
    fn default_settle(&self) -> Duration {
        Duration::ZERO
    }
    fn stimulus(&self) -> Option<Arc<dyn metamer_drivers::World>> {
        None
    }
}

pub fn info(model: &str) -> InstrumentInfo {
    InstrumentInfo {
        model: model.into(),
        serial: None,
        firmware: None,
        connection: "test".into(),
    }
}

/// Reads the screen: XYZ = drive values × 0.5 cd/m², no calibration.
pub struct SpotMeter(pub Shared);

impl Instrument for SpotMeter {
    fn info(&self) -> InstrumentInfo {
        info("fake-spot")
    }
    fn capabilities(&self) -> Capabilities {
        Capabilities {
            modes: vec![ModeInfo {
                mode: MeasureMode::Emissive,
                spot: true,
                calibrations: vec![],
            }],
            spectral: false,
            acceptance_angle_deg: Some(1.0),
            luminance_range_cd_m2: None,
            options: vec![],
        }
    }
    fn calibration_needed(
        &mut self,
        _: MeasureMode,
    ) -> Result<Option<CalibrationCondition>, DriverError> {
        Ok(None)
    }
    fn calibrate(
        &mut self,
        _: MeasureMode,
        _: &CalibrationCondition,
    ) -> Result<CalibrationOutcome, DriverError> {
        Ok(CalibrationOutcome::Done)
    }
    fn measure(&mut self, _: &Request) -> Result<Reading, DriverError> {
        let rgb = self.0.lock().unwrap().rgb;
        Ok(fixed(rgb.map(|c| f64::from(c) * 0.5), "fake-spot"))
    }
}

/// A reading with a fixed timestamp, so two runs' readings compare equal.
pub fn fixed(xyz: [f64; 3], instrument: &str) -> Reading {
    Reading {
        timestamp_s: 0.0,
        ..Reading::from_yxy(
            xyz[1],
            xyz[0] / xyz.iter().sum::<f64>(),
            xyz[1] / xyz.iter().sum::<f64>(),
            instrument,
        )
    }
}

/// Reflective readings of the tile it is on; needs a dark then a white calibration, which
/// lasts [`VALID_FOR`] measurements. Like a calibration that expires by time, the expiry is
/// found only when measuring.
pub struct Spectrometer {
    pub world: Shared,
    pub dark_done: bool,
    pub valid: bool,
    pub used: usize,
    /// Whether `calibration_needed` knows of an expiry a measurement found; if not, only
    /// the measurement's error says what is needed.
    pub reports_expiry: bool,
    pub calibrated_once: bool,
}

impl Spectrometer {
    pub fn new(world: Shared) -> Spectrometer {
        Spectrometer {
            world,
            dark_done: false,
            valid: false,
            used: 0,
            reports_expiry: true,
            calibrated_once: false,
        }
    }
}

impl Instrument for Spectrometer {
    fn info(&self) -> InstrumentInfo {
        info("fake-spectro")
    }
    fn capabilities(&self) -> Capabilities {
        let need = |name: &str, condition| CalibrationNeed {
            name: name.into(),
            condition,
            valid_for_s: Some(1.0),
        };
        Capabilities {
            modes: vec![ModeInfo {
                mode: MeasureMode::Reflective,
                spot: false,
                calibrations: vec![
                    need("dark", CalibrationCondition::SensorCapped),
                    need("white", CalibrationCondition::OnWhiteTile),
                ],
            }],
            spectral: true,
            acceptance_angle_deg: None,
            luminance_range_cd_m2: None,
            options: vec![],
        }
    }
    fn calibration_needed(
        &mut self,
        _: MeasureMode,
    ) -> Result<Option<CalibrationCondition>, DriverError> {
        if !self.reports_expiry && self.calibrated_once {
            return Ok(None);
        }
        Ok(match (self.valid, self.dark_done) {
            (true, _) => None,
            (false, false) => Some(CalibrationCondition::SensorCapped),
            (false, true) => Some(CalibrationCondition::OnWhiteTile),
        })
    }
    fn calibrate(
        &mut self,
        mode: MeasureMode,
        condition: &CalibrationCondition,
    ) -> Result<CalibrationOutcome, DriverError> {
        match condition {
            CalibrationCondition::SensorCapped if !self.valid => {
                self.dark_done = true;
                Ok(CalibrationOutcome::Needs(CalibrationCondition::OnWhiteTile))
            }
            CalibrationCondition::OnWhiteTile if self.dark_done => {
                self.valid = true;
                self.calibrated_once = true;
                self.used = 0;
                Ok(CalibrationOutcome::Done)
            }
            other => Err(DriverError::Unsupported {
                instrument: "fake-spectro".into(),
                what: format!("{mode} calibration on {other:?} before the dark calibration"),
            }),
        }
    }
    fn measure(&mut self, request: &Request) -> Result<Reading, DriverError> {
        if !self.valid || self.used >= VALID_FOR {
            self.valid = false;
            self.dark_done = false;
            return Err(DriverError::NeedsCalibration {
                instrument: "fake-spectro".into(),
                mode: request.mode,
                condition: CalibrationCondition::SensorCapped,
                reason: "the calibration expired".into(),
            });
        }
        self.used += 1;
        let t = self.world.lock().unwrap().tile as f64;
        Ok(fixed([10.0 * t, 11.0 * t, 12.0 * t], "fake-spectro"))
    }
}

/// A scripted operator who also does what the tile prompts ask.
pub struct TileOperator {
    pub script: ScriptedOperator,
    pub world: Shared,
}

impl Operator for TileOperator {
    fn ask(&mut self, prompt: &str) -> Result<Answer, OperatorError> {
        if let Some(tile) = prompt.strip_prefix("place the spectrometer on tile ") {
            self.world.lock().unwrap().tile = tile.parse().unwrap();
        }
        self.script.ask(prompt)
    }
}
