//! What every way of opening an instrument is given: the caller's options and, for a
//! simulation, the settings parsed from the spec. Shared by the registry's rows and the
//! models' own open functions, so neither depends on the other's file.

use std::path::PathBuf;
use std::sync::Arc;

use crate::world::World;

/// The environment variable that sets the simulated instruments' time scale.
pub const TIME_SCALE_ENV: &str = "METAMER_SIM_TIME_SCALE";

/// Extra choices when opening an instrument.
#[derive(Clone, Default)]
pub struct OpenOptions {
    /// What a simulated instrument sees (default: light of
    /// [`DEFAULT_STIMULUS_XYZ`](crate::world::DEFAULT_STIMULUS_XYZ)).
    pub stimulus: Option<Arc<dyn World>>,
    /// Record the session to this new transcript file.
    pub record: Option<PathBuf>,
}

/// How a simulated instrument behaves, from `sim:MODEL?time_scale=…&seed=…&noise=…`.
#[derive(Clone, Debug, PartialEq)]
pub struct SimSettings {
    /// Multiplies every delay: 1 is the real instrument's pace, 0 no delay at all.
    pub time_scale: f64,
    /// Seed of the measurement noise; the same seed gives the same readings.
    pub seed: u64,
    /// Add the instrument's repeatability noise.
    pub noise: bool,
    /// The model's own options (`rev=e` of `sim:i1pro`), named in its registry row's
    /// `sim_options`, in the order given.
    pub extra: Vec<(String, String)>,
}

impl Default for SimSettings {
    fn default() -> Self {
        SimSettings {
            time_scale: 1.0,
            seed: 1,
            noise: true,
            extra: Vec::new(),
        }
    }
}
