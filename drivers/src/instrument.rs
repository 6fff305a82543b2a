//! The one interface every colour instrument offers, real, replayed or simulated.
//!
//! Calibration is a negotiation (after ArgyllCMS `spectro/inst.h`, facts only): the caller
//! asks [`Instrument::calibration_needed`], shows the user what the returned
//! [`CalibrationCondition`] asks for ("put the meter on its white tile"), then calls
//! [`Instrument::calibrate`] with that condition; the instrument may answer with another.

use serde::{Deserialize, Serialize};

/// Who the instrument is.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InstrumentInfo {
    /// Short stable name of the model: `cs100a`, `i1pro`, `sim-…`.
    pub model: String,
    /// Serial number where the device reports one.
    pub serial: Option<String>,
    /// Firmware version where the device reports one.
    pub firmware: Option<String>,
    /// How it is connected: `/dev/ttyUSB0`, `replay:FILE`, `sim`, …
    pub connection: String,
}

/// What an instrument can do, as data (so the CLI, reports and sessions can decide).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Capabilities {
    /// Measures light sources (displays, the box's light) in absolute units.
    pub emissive: bool,
    /// Measures reflectance of surfaces (with its own lamp).
    pub reflective: bool,
    /// Returns a spectrum (not only XYZ).
    pub spectral: bool,
    /// Acceptance angle of a spot meter, degrees (full cone); None for contact devices.
    pub acceptance_angle_deg: Option<f64>,
    /// Response speeds it offers.
    pub speeds: Vec<Speed>,
    /// Luminance range it measures, cd/m².
    pub luminance_range_cd_m2: Option<(f64, f64)>,
}

/// Response speed (integration time class) of a measurement.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Speed {
    /// The instrument's short integration (CS-100A FAST ≈ 100 ms).
    #[default]
    Fast,
    /// The long integration for dark or flickering targets (CS-100A SLOW ≈ 400 ms).
    Slow,
}

/// What a measurement should be.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Request {
    pub mode: MeasureMode,
    pub speed: Speed,
}

/// Kind of measurement.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MeasureMode {
    /// A light source seen by the instrument: absolute XYZ in cd/m².
    #[default]
    Emissive,
    /// A surface lit by the instrument's lamp: relative XYZ (Y = 100 for white).
    Reflective,
}

/// Conditions a reading is flagged with; the values may still be usable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Flag {
    /// Below the instrument's display or accuracy range (CS-100A OK13).
    LowLight,
    /// Luminance above the display range (CS-100A OK12).
    OverRange,
    /// Chromaticity could not be measured (CS-100A OK11).
    ChromaticityOverRange,
    /// The sensor saturated.
    Saturated,
}

impl Flag {
    /// The stable short name used in JSON and logs.
    pub fn name(self) -> &'static str {
        match self {
            Flag::LowLight => "low_light",
            Flag::OverRange => "over_range",
            Flag::ChromaticityOverRange => "chromaticity_over_range",
            Flag::Saturated => "saturated",
        }
    }
}

/// A sampled spectrum carried with a reading.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReadingSpectrum {
    pub start_nm: f64,
    pub step_nm: f64,
    pub values: Vec<f64>,
    /// e.g. `W/(sr·m²·nm)` or `reflectance`.
    pub unit: String,
}

/// One measurement.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reading {
    /// CIE 1931 XYZ: cd/m² for emissive readings, Y = 100 for white in reflective mode.
    pub xyz: [f64; 3],
    /// Chromaticity and luminance as the instrument reports them (x, y, Y).
    pub xyy: [f64; 3],
    pub spectrum: Option<ReadingSpectrum>,
    pub flags: Vec<Flag>,
    /// Integration or response time the instrument used, seconds.
    pub integration_s: Option<f64>,
    /// Model name of the instrument that took it (`cs100a`, `i1pro`, …).
    pub instrument: String,
    /// When it was taken, seconds since the Unix epoch.
    pub timestamp_s: f64,
}

impl Reading {
    /// Builds a reading from Yxy as colorimeters report it (X = xY/y, Z = (1−x−y)Y/y).
    pub fn from_yxy(luminance: f64, x: f64, y: f64, instrument: &str) -> Reading {
        let xyz = if y > 0.0 {
            [x * luminance / y, luminance, (1.0 - x - y) * luminance / y]
        } else {
            [0.0, luminance, 0.0]
        };
        Reading {
            xyz,
            xyy: [x, y, luminance],
            spectrum: None,
            flags: Vec::new(),
            integration_s: None,
            instrument: instrument.to_string(),
            timestamp_s: now_s(),
        }
    }
}

/// Seconds since the Unix epoch (0 if the clock is before it).
pub fn now_s() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

/// Something the user must do before the instrument can calibrate or measure.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CalibrationCondition {
    /// Put the instrument on its white reference tile.
    OnWhiteTile,
    /// Cover the sensor so no light reaches it (dark calibration).
    SensorCapped,
    /// Point the instrument at the target (e.g. the display), ready to measure.
    OnTarget,
    /// Anything else, in the instrument's own words.
    Other(String),
}

impl CalibrationCondition {
    /// What to tell the user.
    pub fn prompt(&self) -> String {
        match self {
            CalibrationCondition::OnWhiteTile => {
                "place the instrument on its white calibration tile".into()
            }
            CalibrationCondition::SensorCapped => "cap the sensor so no light reaches it".into(),
            CalibrationCondition::OnTarget => "aim the instrument at the target".into(),
            CalibrationCondition::Other(s) => s.clone(),
        }
    }
}

/// Outcome of [`Instrument::calibrate`].
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum CalibrationOutcome {
    /// Calibrated; measuring may go on.
    Done,
    /// Another condition is needed first; ask the user and call again.
    Needs(CalibrationCondition),
}

/// Every instrument, whatever its link.
pub trait Instrument: Send {
    fn info(&self) -> InstrumentInfo;
    fn capabilities(&self) -> Capabilities;
    /// The condition the next calibration needs, or None when none is due.
    fn calibration_needed(&mut self) -> Result<Option<CalibrationCondition>, crate::DriverError>;
    /// Calibrates, the user having set up `condition`.
    fn calibrate(
        &mut self,
        condition: &CalibrationCondition,
    ) -> Result<CalibrationOutcome, crate::DriverError>;
    /// Takes one reading.
    fn measure(&mut self, request: &Request) -> Result<Reading, crate::DriverError>;
}

/// What a simulated instrument sees: the light in front of it. A simulated display sets it
/// when it shows a patch; the simulated meter reads it when asked to measure.
pub trait Stimulus: Send + Sync {
    /// CIE 1931 XYZ in cd/m² of what the instrument is aimed at now.
    fn xyz(&self) -> [f64; 3];
    /// The spectral radiance (W·sr⁻¹·m⁻²·nm⁻¹) where the simulation knows it.
    fn spectrum(&self) -> Option<ReadingSpectrum> {
        None
    }
}

/// A stimulus that can be changed from another thread (the simulated display's screen).
#[derive(Debug, Default)]
pub struct SharedStimulus {
    xyz: std::sync::RwLock<[f64; 3]>,
}

impl SharedStimulus {
    pub fn new(xyz: [f64; 3]) -> Self {
        SharedStimulus {
            xyz: std::sync::RwLock::new(xyz),
        }
    }
    pub fn set(&self, xyz: [f64; 3]) {
        *self.xyz.write().unwrap_or_else(|e| e.into_inner()) = xyz;
    }
}

impl Stimulus for SharedStimulus {
    fn xyz(&self) -> [f64; 3] {
        *self.xyz.read().unwrap_or_else(|e| e.into_inner())
    }
}
