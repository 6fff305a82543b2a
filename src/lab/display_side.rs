//! The display side of the simulated lab: set the simulated monitor's peak luminance,
//! characterize it with the `characterize` session, and show the simulation on it.

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use metamer_drivers::{Instrument, World};
use nalgebra::{Matrix3, Vector3};
use serde::Serialize;

use crate::color::Xyz;
use crate::display::characterize::finish::Summary;
use crate::display::characterize::{self, default_grid_steps, PlanOptions};
use crate::display::gamut::{map_to_gamut, GamutMapping};
use crate::display::{ModelKind, Profile};
use crate::rig::virtual_display::quantize;
use crate::rig::{Screen, VirtualPanel};
use crate::session::{RunOptions, ScriptedOperator, StepProgress};

use super::error::LabError;
use super::meter::mean_reading;

/// Noise index of the first reproduced target's readings: past any characterization
/// plan's steps, which take the indices from 0.
pub const REPRODUCTION_READINGS: u64 = 1 << 32;

/// Headroom above the brightest in-gamut target, so no channel sits at its very end.
const LUMINANCE_HEADROOM: f64 = 1.05;

/// The full-white luminance (cd/m²) at which every target the panel's primaries can show
/// fits below full drive: the paper sets the display's maximum luminance so that no tone
/// mapping is needed. The panel's own primaries at its nominal setting give the linear
/// drives (paper Eq. 9 without the TRC); targets outside the primaries' triangle need gamut
/// mapping whatever the luminance, so they do not raise it.
pub fn white_luminance_for(panel: &VirtualPanel, targets: &[[f64; 3]]) -> f64 {
    let black = Vector3::from(panel.xyz([0; 3]));
    let column = |rgb: [u8; 3]| Vector3::from(panel.xyz(rgb)) - black;
    let m = Matrix3::from_columns(&[
        column([255, 0, 0]),
        column([0, 255, 0]),
        column([0, 0, 255]),
    ]);
    let nominal_white = panel.xyz([255; 3])[1];
    let Some(inv) = m.try_inverse() else {
        return nominal_white;
    };
    let needed = targets
        .iter()
        .map(|t| inv * Vector3::from(*t))
        .filter(|lin| lin.iter().all(|&c| c >= 0.0))
        .map(|lin| lin.max())
        .fold(0.0, f64::max);
    if needed > 0.0 {
        nominal_white * needed * LUMINANCE_HEADROOM
    } else {
        nominal_white
    }
}

/// Characterizes `display` with `meter` into `dir` (the `characterize` session: durable
/// journal, resume, fit, held-out verification, profile, `.ti3`, report).
pub fn characterize(
    dir: &Path,
    display: &mut dyn Screen,
    meter: &mut dyn Instrument,
    instrument_spec: &str,
    model: ModelKind,
    resume: bool,
    progress: &dyn Fn(usize, usize),
) -> Result<(Profile, Summary), LabError> {
    let defaults = PlanOptions::default();
    let options = characterize::Options {
        dir: dir.to_path_buf(),
        plan: PlanOptions {
            grid_steps: default_grid_steps(model, defaults.ramp_steps),
            ..defaults
        },
        model,
        instrument: instrument_spec.to_string(),
        settle: Some(Duration::ZERO),
        resume,
        force: false,
        run: RunOptions::default(),
    };
    // A simulated rig: nothing to do by hand, every request is done.
    let mut operator = ScriptedOperator::confirming();
    let mut sink = |p: &StepProgress<'_>| progress(p.done, p.total);
    match characterize::run(&options, display, meter, &mut operator, &mut sink)? {
        characterize::Outcome::Finished(summary) => {
            let profile = Profile::load(&summary.files.profile)?;
            Ok((profile, *summary))
        }
        characterize::Outcome::Incomplete { done, total, .. } => Err(LabError::Incomplete {
            missing: total - done,
        }),
    }
}

/// One simulated reading reproduced on the display.
#[derive(Clone, Debug, Serialize)]
pub struct Reproduced {
    /// What the display was asked to show, cd/m².
    pub target_xyz: [f64; 3],
    /// The inverse model's drive values before gamut mapping.
    pub unclipped_rgb: [f64; 3],
    pub out_of_gamut: bool,
    /// The 8-bit drive values shown.
    pub rgb8: [u8; 3],
    /// The meter's mean reading of the display, cd/m².
    pub measured_xyz: [f64; 3],
}

/// Shows each target through `profile` (with `mapping` where it is out of gamut) and reads
/// it `repeats` times with `meter`.
pub fn reproduce_and_measure(
    display: &mut dyn Screen,
    meter: &mut dyn Instrument,
    profile: &Profile,
    mapping: GamutMapping,
    white: Xyz,
    targets: &[[f64; 3]],
    repeats: usize,
) -> Result<Vec<Reproduced>, LabError> {
    let forward = |rgb: [f64; 3]| profile.forward(rgb);
    targets
        .iter()
        .enumerate()
        .map(|(i, &t)| {
            let inverse = profile.inverse(t);
            let rgb = map_to_gamut(
                mapping,
                &forward,
                inverse.unclipped,
                Xyz::from_array(t),
                white,
            );
            let rgb8 = rgb.map(quantize);
            display.show(rgb8)?;
            // Target i's noise is the same whether the characterization before it was
            // measured in this run or read back from its journal.
            meter.seek_noise(REPRODUCTION_READINGS + i as u64);
            let measured_xyz = mean_reading(meter, repeats)?;
            Ok(Reproduced {
                target_xyz: t,
                unclipped_rgb: inverse.unclipped,
                out_of_gamut: inverse.out_of_gamut,
                rgb8,
                measured_xyz,
            })
        })
        .collect()
}

/// What a simulated meter aimed at `display` sees; the lab runs on simulated displays only.
pub fn stimulus_of(display: &dyn Screen) -> Result<Arc<dyn World>, LabError> {
    display.stimulus().ok_or(LabError::NotSimulated)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::Preset;

    /// Doubling the luminance a target asks for doubles the white luminance chosen, and a
    /// target on the nominal white needs the nominal white (plus headroom).
    #[test]
    fn white_luminance_scales_with_the_targets() {
        let panel = VirtualPanel::preset(Preset::IdealCrt);
        let white = panel.xyz([255; 3]);
        let black = panel.xyz([0; 3]);
        let w_minus_k = [0, 1, 2].map(|k| white[k] - black[k]);
        let at = |s: f64| w_minus_k.map(|c| c * s);
        let one = white_luminance_for(&panel, &[at(1.0)]);
        assert!((one - white[1] * LUMINANCE_HEADROOM).abs() < 1e-9 * white[1]);
        let two = white_luminance_for(&panel, &[at(1.0), at(2.0)]);
        assert!((two / one - 2.0).abs() < 1e-9);
        // Beyond the primaries: ignored.
        let outside = white_luminance_for(&panel, &[at(1.0), [-5.0, 80.0, 0.0]]);
        assert!((outside - one).abs() < 1e-9);
    }
}
