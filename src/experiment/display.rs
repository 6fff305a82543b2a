//! The display stage: the monitor that will show the simulation, characterized by the
//! `characterize` session, and its peak luminance checked against the rendering. The paper
//! uses no tone mapping: it sets the display's maximum luminance so that every rendered
//! value fits. A simulated monitor is set that way; a real one is measured as it is, and
//! when it is too dim the user is told what white luminance to set.

use std::path::Path;

use metamer_drivers::{Instrument, Spec};
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use super::error::ExperimentError;
use super::progress::Progress;
use crate::color::Xyz;
use crate::display::characterize::{self, CharacterizeError, PlanOptions};
use crate::display::{ModelKind, Profile};
use crate::rig::{OpenError, Screen, ScreenSpec, VirtualPanel};
use crate::session::{ProgressSink, RunOptions, StepProgress};

/// The monitor and how it is characterized.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DisplayOptions {
    /// `window:N` or `virtual:PRESET` (written as that text).
    pub screen: ScreenSpec,
    /// The spot meter, as named on the command line.
    pub spot: Spec,
    pub model: ModelKind,
    /// None: the fixed plan (the paper's patches). Some: the adaptive plan with this rule,
    /// its targets the rendered readings the display must show. Left out of the stage's
    /// options when None, so an experiment on the fixed plan keeps its stages' hashes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adaptive: Option<characterize::adaptive::Rule>,
}

/// What `display/display.json` holds: how the monitor was set, so later stages rebuild a
/// simulated one exactly, and the luminance check.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DisplaySetting {
    pub screen: ScreenSpec,
    /// A simulated monitor's full-white luminance, set for the rendering (cd/m²).
    pub virtual_white_cd_m2: Option<f64>,
    /// The measured white, cd/m².
    pub white_xyz: Xyz,
    /// The lowest full-white luminance at which every rendered patch whose chromaticity the
    /// display can show fits without clipping (cd/m²).
    pub needed_white_cd_m2: f64,
    pub model: ModelKind,
}

pub const SETTING_FILE: &str = "display.json";
pub const PROFILE_FILE: &str = "profile.json";
pub const SUMMARY_FILE: &str = "summary.json";

/// The screen of `spec`, set for `setting` when it is simulated.
pub fn open_screen(
    spec: &ScreenSpec,
    virtual_white_cd_m2: Option<f64>,
) -> Result<Box<dyn Screen>, ExperimentError> {
    Ok(characterize::open_screen(spec, virtual_white_cd_m2)?)
}

/// The display stage's checks (and the display-spots stage's, which opens the same screen
/// and meter) before the experiment's first reading: the meter can see the screen, and a
/// real monitor's X display can be reached (without it the box was measured and the scene
/// rendered before the display stage failed).
pub(super) fn preflight(opts: &DisplayOptions) -> Result<(), ExperimentError> {
    characterize::meter_sees(&opts.spot, &opts.screen)?;
    if let ScreenSpec::Window { .. } = opts.screen {
        crate::rig::window::list_monitors(None).map_err(OpenError::Window)?;
    }
    Ok(())
}

/// Headroom above the brightest in-gamut target, so no channel sits at its very end.
const LUMINANCE_HEADROOM: f64 = 1.05;

/// The full-white luminance (cd/m²) at which every target the panel's primaries can show
/// fits below full drive: the paper sets the display's maximum luminance so that no tone
/// mapping is needed. The panel's own primaries at its nominal setting give the linear
/// drives (paper Eq. 9 without the TRC); targets outside the primaries' triangle need gamut
/// mapping whatever the luminance, so they do not raise it.
pub fn white_luminance_for(panel: &VirtualPanel, targets: &[Xyz]) -> f64 {
    let vector = |v: Xyz| Vector3::new(v.x, v.y, v.z);
    let black = vector(panel.xyz([0; 3]));
    let column = |rgb: [u8; 3]| vector(panel.xyz(rgb)) - black;
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
        .map(|t| inv * vector(*t))
        .filter(|lin| lin.iter().all(|&c| c >= 0.0))
        .map(|lin| lin.max())
        .fold(0.0, f64::max);
    if needed > 0.0 {
        nominal_white * needed * LUMINANCE_HEADROOM
    } else {
        nominal_white
    }
}

/// The spot meter aimed at the screen `named` as `screen` (a simulated meter sees only a
/// simulated screen).
pub fn open_meter(
    spec: &Spec,
    named: &ScreenSpec,
    screen: &dyn Screen,
) -> Result<Box<dyn Instrument>, ExperimentError> {
    characterize::meter_sees(spec, named)?;
    Ok(spec.open(screen.stimulus())?)
}

/// The factor by which the display's white must at least be raised so that `target` fits:
/// the largest scale s ≤ 1 at which s·target is inside the profile's gamut, inverted. None
/// when no scale brings it inside (a chromaticity the primaries cannot make).
fn brightness_needed(profile: &Profile, target: Xyz) -> Option<f64> {
    let inside = |s: f64| !profile.inverse(target.map(|v| v * s)).out_of_gamut;
    if inside(1.0) {
        return Some(1.0);
    }
    let (mut lo, mut hi) = (1e-3, 1.0);
    if !inside(lo) {
        return None;
    }
    // 40 halvings: far below any meter's resolution.
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if inside(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(1.0 / lo)
}

/// The white luminance the rendering needs on the display `profile` describes.
pub fn needed_white(profile: &Profile, targets: &[Xyz]) -> f64 {
    let factor = targets
        .iter()
        .filter_map(|t| brightness_needed(profile, *t))
        .fold(1.0, f64::max);
    profile.white_xyz[1] * factor
}

/// A simulated monitor was set for the rendering; a real one that is too dim cannot show it
/// without tone mapping, which the method forbids. Half a percent of slack: the meter's
/// repeatability on the white.
fn check_bright_enough(profile: &Profile, needed: f64, dir: &Path) -> Result<(), ExperimentError> {
    if needed > profile.white_xyz[1] * 1.005 {
        return Err(ExperimentError::DisplayTooDim {
            white_cd_m2: profile.white_xyz[1],
            needed_cd_m2: needed,
            dir: dir.to_path_buf(),
        });
    }
    Ok(())
}

/// The stage's side of a characterization: no notes or warnings (the stage reports
/// progress only), its readings as the experiment's progress.
struct StageListener<F>(F);

impl<F: FnMut(&StepProgress<'_>)> characterize::Listener for StageListener<F> {
    fn note(&mut self, _: &str) {}
    fn warning(&mut self, _: &str) {}
    fn progress(&mut self, _: bool) -> &mut dyn ProgressSink {
        &mut self.0
    }
}

/// Characterizes the display into `dir`; `targets` are the rendered readings it must show.
pub fn characterize_display(
    dir: &Path,
    opts: &DisplayOptions,
    targets: &[Xyz],
    resume: bool,
    unattended: bool,
    run: &RunOptions,
    progress: &dyn Fn(Progress),
) -> Result<(DisplaySetting, Vec<&'static str>), ExperimentError> {
    let screen = opts.screen.clone();
    let virtual_white_cd_m2 = match &screen {
        ScreenSpec::Virtual(p) => Some(white_luminance_for(&VirtualPanel::preset(*p), targets)),
        ScreenSpec::Window { .. } => None,
    };
    let defaults = PlanOptions::default();
    let request = characterize::Request {
        out: dir.to_path_buf(),
        screen,
        virtual_white_cd_m2,
        instrument: opts.spot.clone(),
        speed: None,
        plan: PlanOptions::for_model(opts.model, defaults.ramp_steps, defaults.repeats, None),
        adaptive: opts.adaptive.map(|rule| characterize::adaptive::Adaptive {
            rule,
            targets: targets.to_vec(),
            auto: false,
        }),
        model: opts.model,
        settle: None,
        resume,
        // The stage directory is the experiment's own: a re-run replaces its profile.
        force: true,
        attend: characterize::Attend::Stage { unattended },
        simulated_meter: characterize::SimulatedMeter::Refuse,
        // The experiment's Ctrl-C: the first one stops before the next reading, as in the
        // box and display-spots stages, instead of leaving only the second, which kills.
        run: run.clone(),
    };
    let mut listener = StageListener(|p: &StepProgress<'_>| {
        progress(Progress::Readings {
            done: p.done,
            total: p.total,
        })
    });
    let outcome = characterize::characterize(&request, &mut listener).map_err(|e| match e {
        CharacterizeError::OpenScreen(e) => ExperimentError::OpenScreen(e),
        CharacterizeError::Instrument(e) => ExperimentError::Instrument(e),
        CharacterizeError::SimulatedMeterOnRealScreen(e) => e.into(),
        e => ExperimentError::Characterize(e),
    })?;
    let summary = match outcome {
        characterize::Outcome::Finished(summary) => summary,
        characterize::Outcome::Incomplete {
            done, total, log, ..
        } => {
            return Err(ExperimentError::Incomplete {
                stage: "display",
                done,
                total,
                journal: log,
            })
        }
    };
    let profile = Profile::load(&summary.files.profile)?;
    let needed = needed_white(&profile, targets);
    let setting = DisplaySetting {
        screen: opts.screen.clone(),
        virtual_white_cd_m2,
        white_xyz: profile.white_xyz,
        needed_white_cd_m2: needed,
        model: opts.model,
    };
    check_bright_enough(&profile, needed, dir)?;
    let text = serde_json::to_string_pretty(&setting).map_err(ExperimentError::Json)?;
    super::cache::write_atomic(&dir.join(SETTING_FILE), text.as_bytes())?;
    Ok((setting, vec![SETTING_FILE, PROFILE_FILE, SUMMARY_FILE]))
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
        let at = |s: f64| Xyz::from(w_minus_k.map(|c| c * s));
        let one = white_luminance_for(&panel, &[at(1.0)]);
        assert!((one - white[1] * LUMINANCE_HEADROOM).abs() < 1e-9 * white[1]);
        let two = white_luminance_for(&panel, &[at(1.0), at(2.0)]);
        assert!((two / one - 2.0).abs() < 1e-9);
        // Beyond the primaries: ignored.
        let outside = white_luminance_for(&panel, &[at(1.0), Xyz::new(-5.0, 80.0, 0.0)]);
        assert!((outside - one).abs() < 1e-9);
    }

    /// A profile of the ideal CRT at its nominal white, fitted from a 5³ grid of its exact
    /// emissions: additive, so the matrix model holds it exactly.
    fn crt_profile() -> (VirtualPanel, Profile) {
        let panel = VirtualPanel::preset(Preset::IdealCrt);
        let level = |i: u8| i * 63 + i / 4 * 3;
        let mut patches = Vec::new();
        for r in 0..5 {
            for g in 0..5 {
                for b in 0..5 {
                    let rgb = [level(r), level(g), level(b)];
                    patches.push(crate::display::Sample {
                        rgb: rgb.map(|c| f64::from(c) / 255.0),
                        xyz: panel.xyz(rgb),
                    });
                }
            }
        }
        let profile = crate::display::fit_profile(ModelKind::MatrixLsq, &patches, None).unwrap();
        (panel, profile)
    }

    /// A rendering twice as bright as the display's white needs twice its luminance; the
    /// display is refused with the luminance to set, and a rendering it can show passes.
    #[test]
    fn a_display_too_dim_for_the_rendering_is_refused_with_the_white_to_set() {
        let (panel, profile) = crt_profile();
        let white = panel.xyz([255; 3]);
        let black = panel.xyz([0; 3]);
        // Black plus twice (white − black): the display's own colour, twice as bright.
        let twice = Xyz::from([0, 1, 2].map(|k| black[k] + 2.0 * (white[k] - black[k])));
        let half = Xyz::from([0, 1, 2].map(|k| black[k] + 0.5 * (white[k] - black[k])));
        let needed = needed_white(&profile, &[half, twice]);
        // s·twice is inside while s·(black + 2(w − b)) ≤ w, i.e. s ≤ 1/(2 − k/w) with k
        // the black's Y: that scale, inverted, times the white.
        let exact = white[1] * (2.0 - black[1] / white[1]);
        assert!(
            (needed - exact).abs() < 1e-3 * exact,
            "needed {needed}, exact {exact}"
        );
        let dir = Path::new("/exp/display");
        let e = check_bright_enough(&profile, needed, dir).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains(&format!("{:.1} cd/m²", profile.white_xyz[1]))
                && msg.contains(&format!("{needed:.1} cd/m²"))
                && msg.contains("/exp/display"),
            "{msg}"
        );
        // What the display shows as it is: no refusal.
        let fits = needed_white(&profile, &[half]);
        assert!((fits - profile.white_xyz[1]).abs() < 1e-9);
        check_bright_enough(&profile, fits, dir).unwrap();
    }
}
