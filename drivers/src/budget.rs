//! What measuring costs in time, asked before measuring: each model states, from its own
//! protocol facts, how long one reading of an expected light takes and how long its
//! calibration takes and stays valid, so a planner can budget a session before it opens
//! anything. The figures are the instrument's own time (integration, lamp, measuring time
//! and wire time), not the rig's (a display's settle time, an operator's hands).

use crate::instrument::MeasureMode;
use crate::DriverError;

/// What a planner asks: a reading in `mode` of a light of about `luminance_cd_m2`
/// (emissive: luminance, cd/m²; ambient: illuminance, lx; reflective: ignored), with the
/// model's options as a spec or `set_option` names them (`speed=slow`, `rev=e`,
/// `integration_s=0.5`).
#[derive(Clone, Debug, PartialEq)]
pub struct TimeQuery {
    pub mode: MeasureMode,
    pub luminance_cd_m2: f64,
    pub options: Vec<(String, String)>,
}

impl TimeQuery {
    /// A query without model options.
    pub fn new(mode: MeasureMode, luminance_cd_m2: f64) -> TimeQuery {
        TimeQuery {
            mode,
            luminance_cd_m2,
            options: Vec::new(),
        }
    }

    /// The value of option `name`, if given.
    pub fn option(&self, name: &str) -> Option<&str> {
        self.options
            .iter()
            .rev()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }
}

/// The answer: seconds of instrument time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeBudget {
    /// One reading of the light asked about.
    pub reading_s: f64,
    /// The calibration the mode needs before its first reading (0 where it needs none).
    pub calibration_s: f64,
    /// How long that calibration stays valid; None where it never expires (or there is
    /// none).
    pub calibration_valid_s: Option<f64>,
}

impl TimeBudget {
    /// `readings` readings of this light, with the calibrations they need: one at the start
    /// and one each time the last expires.
    pub fn session_s(&self, readings: usize) -> f64 {
        let reading = self.reading_s * readings as f64;
        let calibrations = match self.calibration_valid_s {
            Some(valid) if valid > 0.0 && self.calibration_s > 0.0 => {
                // Each calibration covers `valid` seconds of readings and itself.
                1.0 + ((reading - valid).max(0.0) / valid).ceil()
            }
            _ if self.calibration_s > 0.0 => 1.0,
            _ => 0.0,
        };
        reading + calibrations * self.calibration_s
    }
}

/// A model's budget from its facts.
pub type TimeBudgetFn = fn(&TimeQuery) -> Result<TimeBudget, DriverError>;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::registry::time_budget;

    /// A session of 100 readings of 30 s each (3000 s) with a calibration of 10 s valid for
    /// 1800 s: one at the start and one after 1800 s, so 3020 s.
    #[test]
    fn a_session_calibrates_again_when_the_calibration_expires() {
        let b = TimeBudget {
            reading_s: 30.0,
            calibration_s: 10.0,
            calibration_valid_s: Some(1800.0),
        };
        assert_eq!(b.session_s(100), 3020.0);
        assert_eq!(b.session_s(10), 310.0);
        let none = TimeBudget {
            calibration_s: 0.0,
            calibration_valid_s: None,
            ..b
        };
        assert_eq!(none.session_s(3), 90.0);
    }

    #[test]
    fn an_unknown_model_or_a_negative_light_is_refused() {
        let q = TimeQuery::new(MeasureMode::Emissive, 1.0);
        assert!(time_budget("nope", &q).is_err());
        assert!(time_budget("i1d3", &q).is_err());
        let bad = TimeQuery::new(MeasureMode::Emissive, -1.0);
        assert!(time_budget("i1pro", &bad).is_err());
    }
}
