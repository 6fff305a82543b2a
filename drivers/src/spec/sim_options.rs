//! The options of a simulation spec, `sim:MODEL?time_scale=F&seed=N&noise=on|off` plus the
//! model's own, read into the settings its emulator is opened with.

use crate::error::DriverError;
use crate::open::{SimSettings, TIME_SCALE_ENV};

/// Parses `time_scale=…&seed=…&noise=off`.
pub(super) fn sim_settings(
    spec: &str,
    query: &str,
    model_options: &[&str],
) -> Result<SimSettings, DriverError> {
    let bad = |message: String| DriverError::BadSpecOption {
        spec: spec.to_string(),
        message,
    };
    let mut config = SimSettings::default();
    if let Ok(v) = std::env::var(TIME_SCALE_ENV) {
        config.time_scale =
            parse_scale(&v).ok_or_else(|| bad(format!("{TIME_SCALE_ENV}={v:?} {SCALE_RANGE}")))?;
    }
    for option in query.split('&').filter(|o| !o.is_empty()) {
        let (key, value) = option.split_once('=').unwrap_or((option, ""));
        match key {
            "time_scale" => {
                config.time_scale = parse_scale(value)
                    .ok_or_else(|| bad(format!("time_scale={value:?} {SCALE_RANGE}")))?
            }
            "seed" => {
                config.seed = value
                    .parse()
                    .map_err(|_| bad(format!("seed={value:?} is not a whole number")))?
            }
            "noise" => {
                config.noise = match value {
                    "on" => true,
                    "off" => false,
                    _ => return Err(bad(format!("noise={value:?}: expected on or off"))),
                }
            }
            key if model_options.contains(&key) => {
                config.extra.push((key.to_string(), value.to_string()))
            }
            _ => {
                let mut known = vec!["time_scale", "seed", "noise"];
                known.extend(model_options);
                return Err(bad(format!(
                    "unknown option '{key}' (known: {})",
                    known.join(", ")
                )));
            }
        }
    }
    Ok(config)
}

/// Slowest simulated pace: 1000 times the real instrument's already makes one CS-100A
/// reading take minutes; beyond it a scale can only be a typo, and the emulator's delays
/// would overflow.
pub const MAX_TIME_SCALE: f64 = 1000.0;
const SCALE_RANGE: &str = "is not a number from 0 to 1000 (1 = the real instrument's pace)";

pub(super) fn parse_scale(v: &str) -> Option<f64> {
    v.trim()
        .parse::<f64>()
        .ok()
        .filter(|s| (0.0..=MAX_TIME_SCALE).contains(s))
}
