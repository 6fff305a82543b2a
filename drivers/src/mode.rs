//! The words a caller and an instrument share before any measurement: the kind of
//! measurement, and what the user must set up for a calibration. Apart from the
//! [`Instrument`](crate::Instrument) trait so the errors can name them without depending on
//! the trait that returns those errors.

use serde::{Deserialize, Serialize};

/// Kind of measurement.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MeasureMode {
    /// A light source seen by the instrument: absolute XYZ in cd/m².
    #[default]
    Emissive,
    /// A surface lit by the instrument's lamp: relative XYZ (Y = 100 for white).
    Reflective,
    /// The light falling on the instrument through a diffuser: illuminance XYZ in lux.
    Ambient,
}

impl MeasureMode {
    pub const ALL: [MeasureMode; 3] = [
        MeasureMode::Emissive,
        MeasureMode::Reflective,
        MeasureMode::Ambient,
    ];

    /// The stable short name used in JSON, logs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            MeasureMode::Emissive => "emissive",
            MeasureMode::Reflective => "reflective",
            MeasureMode::Ambient => "ambient",
        }
    }
}

impl std::fmt::Display for MeasureMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for MeasureMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        MeasureMode::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown mode '{s}' (known: emissive, reflective, ambient)"))
    }
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
