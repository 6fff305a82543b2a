//! The one interface every colour instrument offers, real, replayed or simulated.
//!
//! Calibration is a negotiation (after ArgyllCMS `spectro/inst.h`, facts only): the caller
//! asks [`Instrument::calibration_needed`], shows the user what the returned
//! [`CalibrationCondition`] asks for ("put the meter on its white tile"), then calls
//! [`Instrument::calibrate`] with that condition; the instrument may answer with another.

use metamer_color::{Spectrum, XyY, Xyz};
use serde::{Deserialize, Serialize};

pub use crate::mode::{CalibrationCondition, MeasureMode};

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
    /// The measurement modes it offers, each with the calibrations it needs.
    pub modes: Vec<ModeInfo>,
    /// Returns a spectrum (not only XYZ).
    pub spectral: bool,
    /// Acceptance angle of a spot meter, degrees (full cone); None for contact devices.
    pub acceptance_angle_deg: Option<f64>,
    /// Luminance range it measures, cd/m².
    pub luminance_range_cd_m2: Option<(f64, f64)>,
    /// Settings particular to this model (CS-100A response speed, an i1Pro's integration
    /// time), changed with [`Instrument::set_option`]; not part of [`Request`] because no
    /// other instrument understands them.
    pub options: Vec<OptionInfo>,
}

impl Capabilities {
    /// The description of `mode`, if the instrument offers it.
    pub fn mode(&self, mode: MeasureMode) -> Option<&ModeInfo> {
        self.modes.iter().find(|m| m.mode == mode)
    }

    /// Whether the instrument offers `mode`.
    pub fn supports(&self, mode: MeasureMode) -> bool {
        self.mode(mode).is_some()
    }
}

/// One measurement mode an instrument offers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModeInfo {
    pub mode: MeasureMode,
    /// Aimed from a distance through optics with an acceptance angle (a spot meter), rather
    /// than placed on the target.
    pub spot: bool,
    /// The calibrations this mode needs, in the order they are done.
    pub calibrations: Vec<CalibrationNeed>,
}

/// A calibration a mode needs and how long it stays valid.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CalibrationNeed {
    /// Short stable name (`dark`, `white`).
    pub name: String,
    /// What the user must set up for it.
    pub condition: CalibrationCondition,
    /// Seconds after which it expires and a measurement answers
    /// [`DriverError::NeedsCalibration`](crate::DriverError::NeedsCalibration); None when it
    /// never expires within a session.
    pub valid_for_s: Option<f64>,
}

/// A model-specific setting, described as data so a CLI or a log can list and record it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OptionInfo {
    /// Short stable name (`speed`, `integration_s`).
    pub name: String,
    pub description: String,
    pub values: OptionValues,
    /// The value in force when the instrument is opened, as text.
    pub default: String,
}

/// What values a model-specific setting takes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OptionValues {
    /// One of these words.
    Choice(Vec<String>),
    /// A number in `min..=max`, in `unit`; `auto` is allowed where `auto` is true.
    Number {
        min: f64,
        max: f64,
        unit: String,
        auto: bool,
    },
}

/// What a measurement should be. Model-specific settings are not here but in
/// [`Instrument::set_option`], so one request means the same to every instrument.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Request {
    pub mode: MeasureMode,
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

/// One measurement.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reading {
    /// CIE 1931 XYZ: cd/m² for emissive readings, Y = 100 for white in reflective mode.
    pub xyz: Xyz,
    /// Chromaticity and luminance as the instrument reports them (x, y, Y).
    pub xyy: [f64; 3],
    /// The spectrum where the instrument measures one, tagged with its quantity (radiance,
    /// irradiance or reflectance).
    pub spectrum: Option<Spectrum>,
    pub flags: Vec<Flag>,
    /// Integration or response time the instrument used, seconds.
    pub integration_s: Option<f64>,
    /// Model name of the instrument that took it (`cs100a`, `i1pro`, …).
    pub instrument: String,
    /// When it was taken, seconds since the Unix epoch.
    pub timestamp_s: f64,
}

impl Reading {
    /// Builds a reading from Yxy as colorimeters report it, converted by the colour core's
    /// [`XyY::to_xyz`] (no chromaticity: X and Z are NaN).
    pub fn from_yxy(luminance: f64, x: f64, y: f64, instrument: &str) -> Reading {
        let xyz = XyY { x, y, luminance }.to_xyz();
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

    /// The XYZ a spectral instrument reports with `spectrum` (the i1Pro's rule): 683·∫S·x̄ȳz̄
    /// with the CIE 1931 observer for a radiance (cd/m²) or an irradiance (lux); for a
    /// reflectance, the XYZ under D65 with white at Y = 100, the spectrum's ends held.
    /// None for a spectrum that does not say what it measures. A reading read back from a
    /// file whose XYZ is not this was edited or damaged.
    pub fn xyz_of_spectrum(spectrum: &Spectrum) -> Option<Xyz> {
        use metamer_color::{
            radiance_to_xyz, reflectance_to_xyz, Illuminant, ObserverKind, Outside, Quantity,
        };
        let xyz = match spectrum.quantity()? {
            Quantity::Reflectance => reflectance_to_xyz(
                &spectrum.clone().with_outside(Outside::HoldEnds),
                &Illuminant::D65.spectrum(),
                ObserverKind::Cie1931,
            ),
            Quantity::Radiance | Quantity::Irradiance => {
                radiance_to_xyz(spectrum, ObserverKind::Cie1931)
            }
        };
        Some(xyz)
    }
}

/// Seconds since the Unix epoch (0 if the clock is before it).
pub fn now_s() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
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
///
/// Calibration is negotiated per mode: before measuring in a mode the caller asks
/// [`Instrument::calibration_needed`], has the user set up the condition, and calls
/// [`Instrument::calibrate`] until it answers [`CalibrationOutcome::Done`]. A calibration
/// can expire during a session; [`Instrument::measure`] then answers
/// [`DriverError::NeedsCalibration`](crate::DriverError::NeedsCalibration) and the caller
/// negotiates again and repeats the measurement.
pub trait Instrument: Send {
    fn info(&self) -> InstrumentInfo;
    fn capabilities(&self) -> Capabilities;
    /// The condition the next calibration for `mode` needs, or None when none is due.
    fn calibration_needed(
        &mut self,
        mode: MeasureMode,
    ) -> Result<Option<CalibrationCondition>, crate::DriverError>;
    /// Calibrates for `mode`, the user having set up `condition`.
    fn calibrate(
        &mut self,
        mode: MeasureMode,
        condition: &CalibrationCondition,
    ) -> Result<CalibrationOutcome, crate::DriverError>;
    /// Takes one reading.
    fn measure(&mut self, request: &Request) -> Result<Reading, crate::DriverError>;
    /// Changes a model-specific setting named in [`Capabilities::options`].
    fn set_option(&mut self, name: &str, value: &str) -> Result<(), crate::DriverError> {
        let _ = value;
        Err(crate::DriverError::UnknownOption {
            instrument: self.info().model,
            option: name.to_string(),
            known: self
                .capabilities()
                .options
                .iter()
                .map(|o| o.name.clone())
                .collect::<Vec<_>>()
                .join(", "),
        })
    }
    /// The model-specific settings in force, as (name, value) text, for logs and resume
    /// checks.
    fn option_values(&self) -> Vec<(String, String)> {
        Vec::new()
    }
    /// The next measurements belong to reading `index` of a session. A simulated
    /// instrument draws their noise from (seed, index), so a resumed session reads what an
    /// uninterrupted one would; a real instrument has nothing to do.
    fn seek_noise(&mut self, index: u64) {
        let _ = index;
    }
    /// Seconds of the instrument's own time (integration, lamp, measuring and wire time)
    /// spent since it was opened, at the real instrument's pace, where the instrument
    /// counts it: a simulation does, whatever its time scale, so a session at `time_scale`
    /// 0 still learns what its readings would have cost. None for a real instrument, whose
    /// time is the wall time of its calls.
    fn instrument_time_s(&self) -> Option<f64> {
        None
    }
}

/// An instrument that passes every call on to the one it wraps, but for the ones it
/// overrides here: the one place wrappers (the simulation's, a session's shifted noise
/// stream) delegate, so a method added to [`Instrument`] reaches every wrapped instrument.
pub trait Forwarding: Send {
    fn inner(&self) -> &dyn Instrument;
    fn inner_mut(&mut self) -> &mut dyn Instrument;
    /// [`Instrument::option_values`].
    fn option_values(&self) -> Vec<(String, String)> {
        self.inner().option_values()
    }
    /// [`Instrument::seek_noise`].
    fn seek_noise(&mut self, index: u64) {
        self.inner_mut().seek_noise(index);
    }
    /// [`Instrument::instrument_time_s`].
    fn instrument_time_s(&self) -> Option<f64> {
        self.inner().instrument_time_s()
    }
}

impl<T: Forwarding> Instrument for T {
    fn info(&self) -> InstrumentInfo {
        self.inner().info()
    }
    fn capabilities(&self) -> Capabilities {
        self.inner().capabilities()
    }
    fn calibration_needed(
        &mut self,
        mode: MeasureMode,
    ) -> Result<Option<CalibrationCondition>, crate::DriverError> {
        self.inner_mut().calibration_needed(mode)
    }
    fn calibrate(
        &mut self,
        mode: MeasureMode,
        condition: &CalibrationCondition,
    ) -> Result<CalibrationOutcome, crate::DriverError> {
        self.inner_mut().calibrate(mode, condition)
    }
    fn measure(&mut self, request: &Request) -> Result<Reading, crate::DriverError> {
        self.inner_mut().measure(request)
    }
    fn set_option(&mut self, name: &str, value: &str) -> Result<(), crate::DriverError> {
        self.inner_mut().set_option(name, value)
    }
    fn option_values(&self) -> Vec<(String, String)> {
        Forwarding::option_values(self)
    }
    fn seek_noise(&mut self, index: u64) {
        Forwarding::seek_noise(self, index);
    }
    fn instrument_time_s(&self) -> Option<f64> {
        Forwarding::instrument_time_s(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use metamer_color::Quantity;

    #[test]
    fn a_spectral_reading_carries_its_grid_and_quantity_in_json() {
        let spectrum = Spectrum::from_grid(380.0, 10.0, vec![0.25, 0.5, 0.75])
            .unwrap()
            .with_quantity(Quantity::Radiance);
        let reading = Reading {
            spectrum: Some(spectrum),
            timestamp_s: 0.0,
            ..Reading::from_yxy(30.0, 0.3, 0.6, "i1pro")
        };
        let json = serde_json::to_value(&reading).unwrap();
        assert_eq!(
            json["spectrum"],
            serde_json::json!({"start_nm": 380, "step_nm": 10, "values": [0.25, 0.5, 0.75],
                               "quantity": "radiance"})
        );
        // X = 0.3·30/0.6 = 15, Z = 0.1·30/0.6 = 5.
        for (got, want) in reading.xyz.to_array().iter().zip([15.0, 30.0, 5.0]) {
            assert!((got - want).abs() < 1e-12, "{:?}", reading.xyz);
        }
        let back: Reading = serde_json::from_value(json).unwrap();
        assert_eq!(back, reading);
    }
}
