//! What a characterization measures: black, the full-on primaries and
//! white, per-channel and grey ramps for the fit, optionally an N×N×N grid of the drive
//! cube (for models without PLCC's assumptions, such as a 3D LUT), and a fixed set of
//! verification patches
//! the fit never sees, the whole list repeated `repeats` times (pass after pass, so slow
//! drift of the display spreads over all patches rather than biasing a few).
//!
//! The verification set is 24 seeded pseudo-random drive triplets plus the 24 ColorChecker
//! patches (BabelColor average, `data/colorchecker_babelcolor_average.csv`) under D65
//! encoded as sRGB (IEC 61966-2-1:1999 matrix and transfer function): natural colours
//! spread over the drive cube as a display would show them.

use std::time::Duration;

use metamer_drivers::MeasureMode;
use serde::{Deserialize, Serialize};

use crate::color::{
    self, srgb_encode, xyz_to_linear_srgb, ColorCheckerSet, Illuminant, ObserverKind,
};
use crate::display::ModelKind;
use crate::session::{Prepare, SessionPlan, Step};

/// The journal's session kind.
pub const SESSION_KIND: &str = "characterize";
/// The role of the one instrument a characterization uses.
pub const METER: &str = "meter";

/// Default number of levels per ramp, 0 and 255 included.
pub const DEFAULT_RAMP_STEPS: usize = 9;
/// Number of pseudo-random verification patches.
pub const RANDOM_VERIFICATION: usize = 24;
/// The seed of the random verification patches; fixed, so every session with the same
/// options measures the same patches and logs stay comparable.
pub const VERIFICATION_SEED: u64 = 0x6d65_7461_6d65_7231;

/// What a patch is measured for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Purpose {
    /// Input of the model fit.
    Fit,
    /// Held out to verify the fitted model.
    Verify,
}

/// One drive colour of the plan as it is measured: what is shown, which pass, and what
/// it is for.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct DriveStep {
    /// Position in the measuring order, 0-based over all repeats.
    pub index: usize,
    /// Which of the distinct patches this is (0-based; the same in every repeat).
    pub patch: usize,
    /// Pass, 0-based.
    pub repeat: usize,
    /// 8-bit drive values.
    pub rgb: [u8; 3],
    pub purpose: Purpose,
    /// For people: `black`, `red ramp 64`, `ColorChecker dark skin`, `random 7`.
    pub label: String,
}

/// What a plan with too few mixed fit patches (two or more channels on, the white not
/// counted: the grey ramp's steps, a grid) leaves unmeasured, and what a grid would buy (from
/// the budget study); None when the plan measures enough mixtures for `auto` to judge them.
pub fn plan_advice(plan: &Plan) -> Option<String> {
    let mixed = plan
        .distinct
        .iter()
        .filter(|s| s.purpose == Purpose::Fit)
        .filter(|s| s.rgb.iter().filter(|&&v| v > 0).count() >= 2 && s.rgb != [255; 3])
        .count();
    (mixed < crate::display::diagnostics::MIN_MIXED).then(|| {
        format!(
            "this plan fits on {mixed} mixed patch{} besides the white, too few to judge \
             mixtures: the profile's mixed colours will rest on the model's assumptions. {}",
            if mixed == 1 { "" } else { "es" },
            crate::display::mixture_advice::mixture_advice()
        )
    })
}

/// Points per axis of the LUT's default grid.
pub const LUT_GRID_STEPS: usize = 5;

/// The drive-cube grid a model needs by default: none for the matrix models; for the LUT a
/// 5³ grid (or the ramps' levels, when the ramps have fewer): the LUT corrects PLVC, which
/// the ramps give, where the grid's mixtures show it wrong. On the simulated monitors with
/// the CS-100A's noise, ramps of 9 and a 5³ grid (141 patches) reproduced the verification
/// colours as well as ramps of 9 and the 9³ grid of their levels (729 patches): ΔE00 0.144
/// against 0.162 on ips-lcd, 0.260 against 0.247 on wide-gamut-ccfl, 0.006 against 0.030 on
/// ideal-crt (tests/display/ramp_fit.rs, 2026-12-02).
pub fn default_grid_steps(model: ModelKind, ramp_steps: usize) -> usize {
    if model == ModelKind::Lut {
        ramp_steps.min(LUT_GRID_STEPS)
    } else {
        0
    }
}

/// The options a plan is made from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct PlanOptions {
    /// Levels per ramp including 0 and 255 (2–256).
    pub ramp_steps: usize,
    /// Passes over all patches (≥ 1).
    pub repeats: usize,
    /// Levels per channel of a fit grid over the drive cube, 0 and 255 included (0 = no
    /// grid, else 2–64).
    pub grid_steps: usize,
}

impl PlanOptions {
    /// The plan for `model`: `ramp_steps` and `repeats` as given, and the fit grid asked
    /// for or, when None, the model's default ([`default_grid_steps`]). `characterize` and
    /// the experiment's display stage both make their plan here.
    pub fn for_model(
        model: ModelKind,
        ramp_steps: usize,
        repeats: usize,
        grid_steps: Option<usize>,
    ) -> PlanOptions {
        PlanOptions {
            ramp_steps,
            repeats,
            grid_steps: grid_steps.unwrap_or(default_grid_steps(model, ramp_steps)),
        }
    }
}

impl Default for PlanOptions {
    fn default() -> Self {
        PlanOptions {
            ramp_steps: DEFAULT_RAMP_STEPS,
            repeats: 1,
            grid_steps: 0,
        }
    }
}

/// Options that make no plan.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    #[error("ramp steps must be between 2 and 256 (levels per ramp, 0 and 255 included), got {0}")]
    RampSteps(usize),
    #[error("repeats must be at least 1, got {0}")]
    Repeats(usize),
    #[error("grid steps must be 0 (no grid) or between 2 and 64, got {0}")]
    GridSteps(usize),
}

/// Black, red, green, blue and white: the first patches of every plan.
const KEY_PATCHES: usize = 5;

/// The ordered list of patches to show and measure.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub options: PlanOptions,
    /// The distinct patches, in measuring order within a pass.
    pub distinct: Vec<DriveStep>,
    /// Every measurement: `distinct` × repeats, and with one repeat a second reading of
    /// black, the primaries and white at the end.
    pub patches: Vec<DriveStep>,
}

impl Plan {
    pub fn new(options: PlanOptions) -> Result<Plan, PlanError> {
        if !(2..=256).contains(&options.ramp_steps) {
            return Err(PlanError::RampSteps(options.ramp_steps));
        }
        if options.repeats == 0 {
            return Err(PlanError::Repeats(options.repeats));
        }
        if options.grid_steps == 1 || options.grid_steps > 64 {
            return Err(PlanError::GridSteps(options.grid_steps));
        }
        let mut distinct: Vec<(String, [u8; 3], Purpose)> = vec![
            ("black".into(), [0, 0, 0], Purpose::Fit),
            ("red".into(), [255, 0, 0], Purpose::Fit),
            ("green".into(), [0, 255, 0], Purpose::Fit),
            ("blue".into(), [0, 0, 255], Purpose::Fit),
            ("white".into(), [255, 255, 255], Purpose::Fit),
        ];
        // Interior levels only: 0 and 255 are black and the full-on patches above.
        let levels: Vec<u8> = (1..options.ramp_steps - 1)
            .map(|i| (255.0 * i as f64 / (options.ramp_steps - 1) as f64).round() as u8)
            .collect();
        for (name, mask) in [
            ("red", [1, 0, 0]),
            ("green", [0, 1, 0]),
            ("blue", [0, 0, 1]),
            ("grey", [1, 1, 1]),
        ] {
            for &v in &levels {
                distinct.push((
                    format!("{name} ramp {v}"),
                    [mask[0] * v, mask[1] * v, mask[2] * v],
                    Purpose::Fit,
                ));
            }
        }
        if options.grid_steps > 0 {
            let n = options.grid_steps;
            let level = |i: usize| (255.0 * i as f64 / (n - 1) as f64).round() as u8;
            for r in 0..n {
                for g in 0..n {
                    for b in 0..n {
                        let rgb = [level(r), level(g), level(b)];
                        // Corners and axes the ramps already hold are not measured twice.
                        if !distinct.iter().any(|d| d.1 == rgb) {
                            distinct.push((format!("grid {rgb:?}"), rgb, Purpose::Fit));
                        }
                    }
                }
            }
        }
        for (i, rgb) in random_patches(RANDOM_VERIFICATION, VERIFICATION_SEED)
            .into_iter()
            .enumerate()
        {
            distinct.push((format!("random {}", i + 1), rgb, Purpose::Verify));
        }
        for (name, rgb) in colorchecker_srgb() {
            distinct.push((format!("ColorChecker {name}"), rgb, Purpose::Verify));
        }
        let distinct: Vec<DriveStep> = distinct
            .into_iter()
            .enumerate()
            .map(|(i, (label, rgb, purpose))| DriveStep {
                index: i,
                patch: i,
                repeat: 0,
                rgb,
                purpose,
                label,
            })
            .collect();
        let mut patches = Vec::with_capacity(options.repeats * distinct.len());
        for repeat in 0..options.repeats {
            for p in &distinct {
                patches.push(DriveStep {
                    index: repeat * distinct.len() + p.patch,
                    repeat,
                    ..p.clone()
                });
            }
        }
        if options.repeats == 1 {
            // Black, the primaries and white once more at the end: the fit needs repeated
            // patches to tell the meter's noise from the display's faults (the additivity
            // check combines five readings; the CS-100A's ±0.001 in xy alone is ΔE00 ≈ 1 on
            // it), and a change between the two readings shows drift during the session.
            for p in &distinct[..KEY_PATCHES] {
                patches.push(DriveStep {
                    index: patches.len(),
                    repeat: 1,
                    ..p.clone()
                });
            }
        }
        Ok(Plan {
            options,
            distinct,
            patches,
        })
    }

    /// The plan as session steps, each shown on the screen and read by the [`METER`] in
    /// emissive mode, waiting `settle` before each reading. `display` (the canonical display
    /// name) is one of the plan's options: a journal is resumed on the display it measured.
    pub fn session_plan(&self, display: &str, settle: Duration) -> SessionPlan<DriveStep> {
        let o = &self.options;
        let options = [
            ("ramp_steps", o.ramp_steps.to_string()),
            ("repeats", o.repeats.to_string()),
            ("grid_steps", o.grid_steps.to_string()),
            ("display", display.to_string()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
        SessionPlan {
            kind: SESSION_KIND.into(),
            options,
            steps: self
                .patches
                .iter()
                .map(|p| Step {
                    label: p.label.clone(),
                    role: METER.into(),
                    mode: MeasureMode::Emissive,
                    prepare: Prepare::Show { rgb: p.rgb },
                    settle,
                    data: p.clone(),
                })
                .collect(),
        }
    }
}

/// `n` drive triplets from the workspace's seeded generator (SplitMix64).
pub fn random_patches(n: usize, seed: u64) -> Vec<[u8; 3]> {
    let mut rng = metamer_drivers::noise::SplitMix64::new(seed);
    (0..n)
        .map(|_| {
            let r = rng.next_u64();
            [(r >> 8) as u8, (r >> 24) as u8, (r >> 40) as u8]
        })
        .collect()
}

/// The 24 ColorChecker patches under D65 as 8-bit sRGB (out-of-gamut channels clipped).
pub fn colorchecker_srgb() -> Vec<(&'static str, [u8; 3])> {
    let d65 = Illuminant::D65.spectrum();
    color::colorchecker(ColorCheckerSet::BabelColorAverage)
        .iter()
        .zip(color::COLORCHECKER_NAMES)
        .map(|(reflectance, name)| {
            let xyz = color::reflectance_to_xyz(reflectance, &d65, ObserverKind::Cie1931)
                .scaled(0.01)
                .to_array();
            let rgb = xyz_to_linear_srgb(xyz)
                .map(|linear| (srgb_encode(linear.clamp(0.0, 1.0)) * 255.0).round() as u8);
            (name, rgb)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fp(plan: &Plan) -> String {
        plan.session_plan("virtual:ips-lcd", Duration::ZERO)
            .fingerprint()
            .unwrap()
    }

    #[test]
    fn default_plan_has_the_promised_patches() {
        let plan = Plan::new(PlanOptions::default()).unwrap();
        // 5 + 4 ramps × 7 interior levels + 24 random + 24 ColorChecker.
        assert_eq!(plan.distinct.len(), 5 + 28 + 48);
        assert_eq!(plan.patches[..81], plan.distinct[..]);
        // With one repeat, black, the primaries and white are read again at the end.
        assert_eq!(plan.patches.len(), 86);
        for (i, p) in plan.patches[81..].iter().enumerate() {
            assert_eq!((p.index, p.patch, p.repeat), (81 + i, i, 1));
            assert_eq!(p.rgb, plan.distinct[i].rgb);
        }
        let twice = Plan::new(PlanOptions {
            repeats: 2,
            ..PlanOptions::default()
        })
        .unwrap();
        assert_eq!(twice.patches.len(), 2 * 81);
        let fit: Vec<_> = plan
            .distinct
            .iter()
            .filter(|p| p.purpose == Purpose::Fit)
            .collect();
        assert_eq!(fit.len(), 33);
        assert_eq!(fit[0].rgb, [0, 0, 0]);
        assert_eq!(fit[4].rgb, [255, 255, 255]);
        // 9 steps: 255·i/8 rounded = 32, 64, 96, 128, 159, 191, 223.
        let red: Vec<u8> = fit
            .iter()
            .filter(|p| p.label.starts_with("red ramp"))
            .map(|p| p.rgb[0])
            .collect();
        assert_eq!(red, [32, 64, 96, 128, 159, 191, 223]);
        let grey = fit.iter().find(|p| p.label == "grey ramp 128").unwrap();
        assert_eq!(grey.rgb, [128, 128, 128]);
    }

    #[test]
    fn repeats_are_whole_passes_and_the_fingerprint_tracks_the_plan() {
        let one = Plan::new(PlanOptions {
            ramp_steps: 3,
            repeats: 1,
            grid_steps: 0,
        })
        .unwrap();
        let three = Plan::new(PlanOptions {
            ramp_steps: 3,
            repeats: 3,
            grid_steps: 0,
        })
        .unwrap();
        let n = one.distinct.len();
        assert_eq!(three.patches.len(), 3 * n);
        for (i, p) in three.patches.iter().enumerate() {
            assert_eq!(p.index, i);
            assert_eq!((p.repeat, p.patch), (i / n, i % n));
            assert_eq!(p.rgb, one.distinct[i % n].rgb);
        }
        let again = Plan::new(PlanOptions {
            ramp_steps: 3,
            repeats: 1,
            grid_steps: 0,
        })
        .unwrap();
        assert_eq!(fp(&one), fp(&again));
        // The wait before a reading is how, not what: it does not change the fingerprint;
        // the display measured does, and names itself as the option that differs.
        let slow = one.session_plan("virtual:ips-lcd", Duration::from_millis(500));
        assert_eq!(slow.fingerprint().unwrap(), fp(&one));
        let elsewhere = one.session_plan("window:0", Duration::ZERO);
        assert_ne!(elsewhere.fingerprint().unwrap(), fp(&one));
        assert_eq!(elsewhere.options["display"], "window:0");
        assert_ne!(fp(&one), fp(&three));
        assert_ne!(fp(&one), fp(&Plan::new(PlanOptions::default()).unwrap()));
        assert!(matches!(
            Plan::new(PlanOptions {
                ramp_steps: 1,
                repeats: 1,
                grid_steps: 0,
            }),
            Err(PlanError::RampSteps(1))
        ));
        assert!(matches!(
            Plan::new(PlanOptions {
                ramp_steps: 257,
                repeats: 1,
                grid_steps: 0,
            }),
            Err(PlanError::RampSteps(257))
        ));
        assert!(matches!(
            Plan::new(PlanOptions {
                ramp_steps: 9,
                repeats: 0,
                grid_steps: 0,
            }),
            Err(PlanError::Repeats(0))
        ));
        // Two steps: no interior levels, only black, primaries and white for the fit.
        let two = Plan::new(PlanOptions {
            ramp_steps: 2,
            repeats: 1,
            grid_steps: 0,
        })
        .unwrap();
        assert_eq!(
            two.distinct
                .iter()
                .filter(|p| p.purpose == Purpose::Fit)
                .count(),
            5
        );
    }

    #[test]
    fn a_grid_adds_the_cube_without_repeating_ramp_patches() {
        let base = Plan::new(PlanOptions {
            grid_steps: 0,
            ..PlanOptions::default()
        })
        .unwrap();
        let grid = Plan::new(PlanOptions {
            grid_steps: 5,
            ..PlanOptions::default()
        })
        .unwrap();
        // 5³ = 125 grid points; 0, 64, 128, 191, 255 per channel. Already planned: black,
        // white, 3 primaries, and the 64/128/191 levels of the four ramps (12): 17.
        assert_eq!(grid.distinct.len(), base.distinct.len() + 125 - 17);
        assert!(grid.distinct.iter().any(|p| p.rgb == [64, 191, 0]));
        assert_ne!(fp(&grid), fp(&base));
        for bad in [1, 65] {
            assert!(matches!(
                Plan::new(PlanOptions {
                    grid_steps: bad,
                    ..PlanOptions::default()
                }),
                Err(PlanError::GridSteps(_))
            ));
        }
    }

    #[test]
    fn colorchecker_patches_match_published_srgb() {
        // The sRGB values of the table in Wikipedia's "ColorChecker" article (from X-Rite's
        // data): dark skin #735244, light skin #c29682, white 9.5 #f3f3f2, neutral 5
        // #7a7a79, black 2 #343434. Those are of one chart, the BabelColor average of thirty,
        // so a few codes may differ (dark saturated patches more: blue's red is 14 apart).
        let cc = colorchecker_srgb();
        assert_eq!(cc.len(), 24);
        for (i, published) in [
            (0, [115, 82, 68]),
            (1, [194, 150, 130]),
            (18, [243, 243, 242]),
            (21, [122, 122, 121]),
            (23, [52, 52, 52]),
        ] {
            let got = cc[i].1;
            for c in 0..3 {
                assert!(
                    (i32::from(got[c]) - published[c]).abs() <= 8,
                    "{}: {got:?} vs {published:?}",
                    cc[i].0
                );
            }
        }
    }

    #[test]
    fn random_patches_are_seeded_and_spread() {
        let a = random_patches(24, VERIFICATION_SEED);
        assert_eq!(a, random_patches(24, VERIFICATION_SEED));
        assert_ne!(a, random_patches(24, 1));
        // Spread: every channel has codes in each half of the range.
        for c in 0..3 {
            assert!(a.iter().any(|p| p[c] < 128) && a.iter().any(|p| p[c] >= 128));
        }
    }
}
