//! Integration and lamp times in the instrument's clock units, and how long the host waits
//! for readings.

/// Integration clock period and sub-clock divider of Rev A–D firmware before 301, which has
/// no clock modes: one sub-clock, the shortest integration, is 8.84 ms.
pub const CLOCK_US_BEFORE_301: u8 = 68;
pub const SUB_CLOCK_DIVIDER_BEFORE_301: u8 = 130;
/// Rev E's fixed clock: 36 µs × 136 = 4.896 ms shortest integration.
pub const CLOCK_US_E: u32 = 36;
pub const SUB_CLOCK_DIVIDER_E: u32 = 136;
/// One clock mode of a unit: the integration clock's period and the sub-clock divider, as
/// GetClockMode (0xD1) reports them for the mode in force (Rev A–D firmware ≥ 301), as
/// firmware before 301 has them fixed, or as Rev E's GetMeasChar (0xD5) reports them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClockUnit {
    /// Integration clock period, seconds.
    pub clock_s: f64,
    /// Integration clocks per sub-clock.
    pub divider: u32,
}

impl ClockUnit {
    /// The shortest integration in this mode: one sub-clock, `clock × divider`. ArgyllCMS
    /// takes firmware before 301 to stop at 8.84 ms, "one sub clock" (68 µs × 130), and on
    /// later firmware steps the modes from 1 until the time is at least 0.99 of a
    /// sub-clock.
    pub fn shortest_s(&self) -> f64 {
        self.clock_s * f64::from(self.divider)
    }

    /// The sub-clock period (the unit of lamp times), seconds.
    pub fn sub_clock_s(&self) -> f64 {
        self.shortest_s()
    }
}

/// The clock mode and clock count for an integration time `t`: the first mode, in the
/// unit's order (mode 1 first, as ArgyllCMS steps them), in which `t` rounds to at least
/// one sub-clock and to at most `max_clocks` clocks. None when no mode can integrate `t`.
pub fn pick_mode(modes: &[ClockUnit], t: f64, max_clocks: u64) -> Option<(usize, u64)> {
    if !(t.is_finite() && t > 0.0) {
        return None;
    }
    modes.iter().enumerate().find_map(|(i, m)| {
        let n = (t / m.clock_s).round();
        (n >= f64::from(m.divider) && n <= max_clocks as f64).then_some((i, n as u64))
    })
}

/// The shortest integration any of `modes` allows.
pub fn shortest_s(modes: &[ClockUnit]) -> Option<f64> {
    modes.iter().map(ClockUnit::shortest_s).reduce(f64::min)
}

/// The lamp must have been off this long before a lamp-off (dark or emissive) reading.
pub const LAMP_REST_S: f64 = 1.5;
/// A scan is read in chunks of at most this many readings…
pub const SCAN_CHUNK_READINGS: usize = 64;
/// …for at most this long.
pub const MAX_SCAN_S: f64 = 30.0;

/// Whether the firmware measures the previous integration time and then the current one
/// (revisions 200–399), so a read after changing the time takes both.
pub fn measures_previous_too(firmware: u16) -> bool {
    (200..400).contains(&firmware)
}

/// How long the host waits for the readings of one trigger: 2 s slack plus the integrations,
/// the lamp's warm-up when it is lit, and the previous integration time on firmware that
/// measures it first (see [`measures_previous_too`]).
pub fn readings_timeout_s(
    readings: u32,
    integration_s: f64,
    lamp_s: Option<f64>,
    previous_integration_s: Option<f64>,
) -> f64 {
    2.0 + f64::from(readings) * integration_s
        + lamp_s.unwrap_or(0.0)
        + previous_integration_s.unwrap_or(0.0)
}

/// A duration that cannot be sent.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TimingError {
    #[error("{what} of {seconds} s is not a usable duration")]
    BadDuration { what: &'static str, seconds: f64 },
    #[error(
        "{what} of {seconds} s needs {clocks} clocks, more than the {max} the request can carry"
    )]
    TooManyClocks {
        what: &'static str,
        seconds: f64,
        clocks: u64,
        max: u64,
    },
}

/// Clocks for a duration: `round(seconds / unit)`, at most `max`. Integration times count
/// integration clocks; lamp times count sub-clocks.
pub fn clocks(what: &'static str, seconds: f64, unit_s: f64, max: u64) -> Result<u64, TimingError> {
    if !(seconds.is_finite() && seconds >= 0.0 && unit_s.is_finite() && unit_s > 0.0) {
        return Err(TimingError::BadDuration { what, seconds });
    }
    let n = (seconds / unit_s).round();
    if n > max as f64 {
        return Err(TimingError::TooManyClocks {
            what,
            seconds,
            clocks: n as u64,
            max,
        });
    }
    Ok(n as u64)
}

/// The lamp's warm-up never exceeds this many sub-clocks: longer requests are cut to it.
pub const MAX_LAMP_CLOCKS: u64 = 256;

/// Lamp sub-clocks for a warm-up time, capped at [`MAX_LAMP_CLOCKS`].
pub fn lamp_clocks(seconds: f64, sub_clock_s: f64) -> Result<u64, TimingError> {
    Ok(clocks("lamp time", seconds, sub_clock_s, u64::MAX)?.min(MAX_LAMP_CLOCKS))
}

#[cfg(test)]
mod tests;
