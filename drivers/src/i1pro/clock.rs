//! The time the driver judges calibration validity by, injectable so tests and simulations
//! can let a calibration expire without waiting half an hour.

use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Seconds since some fixed start; only differences matter.
pub trait Clock: Send + Sync {
    fn now_s(&self) -> f64;
}

/// Wall-clock time, for real instruments.
#[derive(Debug)]
pub struct SystemClock(Instant);

impl Default for SystemClock {
    fn default() -> Self {
        SystemClock(Instant::now())
    }
}

impl Clock for SystemClock {
    fn now_s(&self) -> f64 {
        self.0.elapsed().as_secs_f64()
    }
}

/// Time that moves only when told: tests and transcript replays advance it by hand.
#[derive(Clone, Debug, Default)]
pub struct ManualClock(Arc<Mutex<f64>>);

impl ManualClock {
    pub fn new() -> ManualClock {
        ManualClock::default()
    }

    /// Moves time on by `s` seconds.
    pub fn advance(&self, s: f64) {
        *self.0.lock().unwrap_or_else(|e| e.into_inner()) += s;
    }
}

impl Clock for ManualClock {
    fn now_s(&self) -> f64 {
        *self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Wall-clock time sped up by `1 / time_scale`, so a simulated instrument running at
/// `time_scale` = 0.001 ages its calibrations a thousand times faster, as its readings are
/// a thousand times faster. A time scale of 0 freezes it.
#[derive(Debug)]
pub struct ScaledClock {
    start: Instant,
    speed: f64,
}

impl ScaledClock {
    pub fn new(time_scale: f64) -> ScaledClock {
        ScaledClock {
            start: Instant::now(),
            speed: if time_scale > 0.0 {
                1.0 / time_scale
            } else {
                0.0
            },
        }
    }
}

impl Clock for ScaledClock {
    fn now_s(&self) -> f64 {
        self.start.elapsed().as_secs_f64() * self.speed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_manual_clock_moves_only_when_advanced_and_clones_share_it() {
        let c = ManualClock::new();
        let d = c.clone();
        assert_eq!(c.now_s(), 0.0);
        d.advance(1800.5);
        assert_eq!(c.now_s(), 1800.5);
        assert_eq!(ScaledClock::new(0.0).now_s(), 0.0);
    }
}
