//! What measuring mixtures besides the ramps buys, as the budget study measured it: the
//! numbers `fit` and `characterize` quote to a user whose plan holds no mixtures. A leaf
//! module, so the diagnostics and the plan can quote it without depending on the study.

use crate::rig::virtual_display::Preset;

/// What the mixture study measured for one display: the ramp-only plan fitted with PLVC
/// (what `auto` takes on it), and with a grid added fitted with the LUT.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MixtureGain {
    pub preset: Preset,
    /// Mean ΔE00 of reproduced colours from the 50 ramp patches alone.
    pub ramps_only_de00: f64,
    /// (points per axis, patches added, mean ΔE00) with a grid added.
    pub with_grid: [(usize, usize, f64); 2],
}

/// When the study was measured, and how ([`MEASURED_MIXTURE_GAINS`]).
pub const MIXTURE_GAINS_MEASURED: &str =
    "metamer budget's mixture study, 3 trials with seed 1, measured 2026-12-02";

/// [`super::budget::run_mixture_study`] on the two LCD presets with 3 trials and seed 1 (`print_mixture_study` in tests/display/ramp_fit.rs prints
/// them); what `fit` tells a user whose set has no
/// mixtures.
pub const MEASURED_MIXTURE_GAINS: [MixtureGain; 2] = [
    MixtureGain {
        preset: Preset::IpsLcd,
        ramps_only_de00: 0.513,
        with_grid: [(4, 59, 0.190), (5, 111, 0.093)],
    },
    MixtureGain {
        preset: Preset::WideGamutCcfl,
        ramps_only_de00: 0.830,
        with_grid: [(4, 59, 0.244), (5, 111, 0.103)],
    },
];

/// One sentence for a user whose patch set holds no mixtures: how much measuring a grid
/// besides the ramps cut the error in the study.
pub fn mixture_advice() -> String {
    let [a, b] = MEASURED_MIXTURE_GAINS;
    format!(
        "On the simulated LCDs, adding a 4³ grid ({} patches) to a 50-patch ramp plan cut the \
         mean ΔE00 of reproduced colours from {:.2} to {:.2} ({}) and from {:.2} to {:.2} ({}), \
         a 5³ grid ({} patches) to {:.2} and {:.2} ({}): measure a grid of 5 steps per axis \
         besides the ramps and fit the lut.",
        a.with_grid[0].1,
        a.ramps_only_de00,
        a.with_grid[0].2,
        a.preset.name(),
        b.ramps_only_de00,
        b.with_grid[0].2,
        b.preset.name(),
        a.with_grid[1].1,
        a.with_grid[1].2,
        b.with_grid[1].2,
        MIXTURE_GAINS_MEASURED
    )
}
