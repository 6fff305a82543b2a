//! A simulated instrument as a session sees it: the driver on its emulator, plus what makes
//! its readings what they are — the simulation's seed, noise and time scale — among its
//! option values (so a journal records them and a resume with others is refused), and the
//! emulator's noise stream positioned per reading ([`Instrument::seek_noise`]).

use crate::i1pro::{Clock, ManualClock};
use crate::instrument::{Forwarding, Instrument};
use crate::noise::NoiseCursor;
use crate::open::SimSettings;

/// Prefix of the simulation's settings among the option values, apart from the model's own.
pub const SIM_OPTION_PREFIX: &str = "sim_";

/// A driver talking to an emulator whose noise it can position.
pub struct Simulated {
    inner: Box<dyn Instrument>,
    noise: NoiseCursor,
    settings: Vec<(String, String)>,
    /// The emulator's own time at the real instrument's pace.
    pace: ManualClock,
}

impl Simulated {
    /// Wraps `inner`, whose emulator draws its noise through `noise` and counts its time
    /// at the real pace on `pace`.
    pub fn wrap(
        inner: Box<dyn Instrument>,
        noise: NoiseCursor,
        pace: ManualClock,
        settings: &SimSettings,
    ) -> Box<dyn Instrument> {
        Box::new(Simulated {
            inner,
            noise,
            settings: settings_values(settings),
            pace,
        })
    }
}

/// The simulation's settings as option values: `sim_seed`, `sim_noise`, `sim_time_scale`,
/// and the model's own (`sim_rev`).
pub fn settings_values(s: &SimSettings) -> Vec<(String, String)> {
    let mut v = vec![
        ("seed".to_string(), s.seed.to_string()),
        (
            "noise".to_string(),
            if s.noise { "on" } else { "off" }.to_string(),
        ),
        ("time_scale".to_string(), s.time_scale.to_string()),
    ];
    v.extend(s.extra.iter().cloned());
    v.into_iter()
        .map(|(k, value)| (format!("{SIM_OPTION_PREFIX}{k}"), value))
        .collect()
}

impl Forwarding for Simulated {
    fn inner(&self) -> &dyn Instrument {
        self.inner.as_ref()
    }
    fn inner_mut(&mut self) -> &mut dyn Instrument {
        self.inner.as_mut()
    }
    fn option_values(&self) -> Vec<(String, String)> {
        let mut v = self.inner.option_values();
        v.extend(self.settings.iter().cloned());
        v
    }
    fn seek_noise(&mut self, index: u64) {
        self.noise.seek(index);
    }
    fn instrument_time_s(&self) -> Option<f64> {
        Some(self.pace.now_s())
    }
}
