//! Display models fitted to patches from small analytic displays: round trips where PLCC's
//! assumptions hold, diagnostics where they fail, singular primaries, out-of-gamut targets,
//! and a `.ti3` in the exact layout ArgyllCMS dispread writes.

use std::path::Path;

use metamer::color::{delta_e2000, Xyz};
use metamer::display::model::Sample;
use metamer::display::{
    fit_profile, fit_profile_with, read_measurement_file, FitError, FitOptions, ModelKind, Profile,
};

use crate::support::unused_dir;

/// XYZ = black + Σ col_c · d_c^γ_c, optionally with a blue chromaticity drift along its ramp
/// and a loss of additivity (channels driven together give less than their sum).
#[derive(Clone)]
struct Analytic {
    black: [f64; 3],
    cols: [[f64; 3]; 3],
    gamma: [f64; 3],
    /// XYZ added to blue: drift · 4·b(1−b)·b^γ_b · [8, 6, −8] (zero at 0 and 1): its
    /// chromaticity moves along the ramp.
    blue_drift: f64,
    /// Output scaled by 1 − k·(l_r l_g + l_g l_b + l_b l_r)/3.
    interaction: f64,
}

/// The display of `tests/data/dispread_analytic.ti3` (sRGB-like primaries, 120.25 cd/m²).
fn ideal() -> Analytic {
    Analytic {
        black: [0.25, 0.26, 0.30],
        cols: [
            [49.49, 25.51, 2.32],
            [42.91, 85.82, 14.30],
            [21.66, 8.66, 114.07],
        ],
        gamma: [2.2, 2.3, 2.1],
        blue_drift: 0.0,
        interaction: 0.0,
    }
}

impl Analytic {
    fn forward(&self, rgb: [f64; 3]) -> Xyz {
        let l: [f64; 3] = std::array::from_fn(|c| rgb[c].powf(self.gamma[c]));
        let k = 1.0 - self.interaction * (l[0] * l[1] + l[1] * l[2] + l[2] * l[0]) / 3.0;
        let b = rgb[2];
        let drift = [8.0, 6.0, -8.0].map(|v| v * self.blue_drift * 4.0 * b * (1.0 - b) * l[2]);
        let xyz: [f64; 3] = std::array::from_fn(|k2| {
            self.black[k2] + k * (0..3).map(|c| self.cols[c][k2] * l[c]).sum::<f64>() + drift[k2]
        });
        xyz.into()
    }

    /// Black, white, ramps per channel and a 5³ grid, each drive triple once.
    fn unique_patches(&self, ramp_levels: usize) -> Vec<Sample> {
        let mut out: Vec<Sample> = Vec::new();
        for p in self.patches(ramp_levels) {
            if !out.iter().any(|q| q.rgb == p.rgb) {
                out.push(p);
            }
        }
        out
    }

    /// Black, white, ramps per channel and a 5³ grid (black, white and grid levels of the
    /// ramps appear twice, with identical readings).
    fn patches(&self, ramp_levels: usize) -> Vec<Sample> {
        self.patches_with_grid(ramp_levels, 5)
    }

    /// Black, white, `ramp_levels` levels per channel ramp and a `grid`³ grid.
    fn patches_with_grid(&self, ramp_levels: usize, grid: usize) -> Vec<Sample> {
        let mut rgbs = vec![[0.0; 3], [1.0; 3]];
        for c in 0..3 {
            for i in 1..=ramp_levels {
                let mut v = [0.0; 3];
                v[c] = i as f64 / ramp_levels as f64;
                rgbs.push(v);
            }
        }
        let lv: Vec<f64> = (0..grid).map(|i| i as f64 / (grid - 1) as f64).collect();
        for &r in &lv {
            for &g in &lv {
                for &b in &lv {
                    rgbs.push([r, g, b]);
                }
            }
        }
        rgbs.into_iter()
            .map(|rgb| Sample {
                rgb,
                xyz: self.forward(rgb),
            })
            .collect()
    }

    fn white(&self) -> Xyz {
        self.forward([1.0; 3])
    }
}

/// Deterministic drive triples spread over the cube.
fn drives(n: usize) -> Vec<[f64; 3]> {
    let mut s: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n).map(|_| [next(), next(), next()]).collect()
}

fn de00(a: Xyz, b: Xyz, white: Xyz) -> f64 {
    delta_e2000(a.to_lab(white), b.to_lab(white))
}

/// Largest ΔE00 between a target the display can show and what the display shows for the
/// drive values the profile computes for it.
fn round_trip(display: &Analytic, profile: &Profile, n: usize) -> f64 {
    let w = display.white();
    drives(n)
        .into_iter()
        .map(|rgb| {
            let target = display.forward(rgb);
            let inv = profile.inverse(target);
            assert!(!inv.out_of_gamut, "{rgb:?} → {inv:?}");
            de00(display.forward(inv.rgb), target, w)
        })
        .fold(0.0, f64::max)
}

#[test]
fn plcc_round_trip_where_its_assumptions_hold() {
    let d = ideal();
    let gamma = fit_profile(ModelKind::PlccGamma, &d.patches(16), None).unwrap();
    let e = round_trip(&d, &gamma, 2000);
    assert!(e < 0.01, "plcc-gamma round trip ΔE00 {e}");
    // Piecewise-linear ramps are exact at their levels; between them the error shrinks with
    // the level count: 255 levels (every 8-bit code) keep it far below 0.01.
    let plcc = fit_profile(ModelKind::Plcc, &d.patches(255), None).unwrap();
    let e = round_trip(&d, &plcc, 2000);
    assert!(e < 0.01, "plcc round trip ΔE00 {e}");
    let diag = plcc.diagnostics();
    assert!(diag.failures.is_empty(), "{diag}");
    assert!(
        diag.verdict
            .starts_with("PLCC's assumptions hold within ΔE00 0.5"),
        "{}",
        diag.verdict
    );
    assert!(plcc.residuals.max_de00 < 0.01, "{:?}", plcc.residuals);
    // Eq. 9's matrix is the full-on primaries minus black: the analytic columns.
    let cond = diag.condition_number.unwrap();
    assert!(cond > 1.0 && cond < 20.0, "{cond}");
}

#[test]
fn paper_gamma_is_used_when_given() {
    let d = ideal();
    let p = fit_profile_with(
        ModelKind::PlccGamma,
        &d.patches(4),
        None,
        &FitOptions {
            gamma: Some(2.2),
            ..FitOptions::default()
        },
    )
    .unwrap();
    // Red has γ = 2.2 exactly, so its ramp is reproduced; green (γ 2.3) is not.
    let mid_red = d.forward([0.5, 0.0, 0.0]);
    assert!(de00(p.forward([0.5, 0.0, 0.0]), mid_red, d.white()) < 1e-9);
    let mid_green = d.forward([0.0, 0.5, 0.0]);
    assert!(de00(p.forward([0.0, 0.5, 0.0]), mid_green, d.white()) > 0.5);
    assert!(
        p.diagnostics().verdict.contains("PLCC's assumptions hold"),
        "{}",
        p.diagnostics().verdict
    );
}

#[test]
fn violated_assumptions_are_named() {
    let mut d = ideal();
    d.blue_drift = 1.0;
    d.interaction = 0.08;
    let p = fit_profile(ModelKind::Plcc, &d.patches(16), None).unwrap();
    let diag = p.diagnostics();
    assert!(
        diag.verdict.starts_with("PLCC's assumptions fail"),
        "{diag}"
    );
    let additivity = diag.additivity.as_ref().unwrap();
    // white = black + 0.92 · Σ columns: luminance 8 % of the sum short of it
    let sum_y: f64 = d.cols.iter().map(|c| c[1]).sum();
    let expected = 100.0 * (-0.08 * sum_y) / (d.black[1] + 0.92 * sum_y);
    assert!(
        (additivity.luminance_error_percent - expected).abs() < 1e-9,
        "{additivity:?} vs {expected}"
    );
    assert!(diag.failures.iter().any(|f| f.contains("not additive")));
    assert!(diag
        .failures
        .iter()
        .any(|f| f.contains("blue channel's chromaticity drifts")));
    assert!(!diag
        .failures
        .iter()
        .any(|f| f.contains("red channel's chromaticity")));
    // the added XYZ 4·b(1−b)·b^2.1 peaks at b = 3.1/4.1 ≈ 0.76; relative to blue's own
    // output the shift is largest a little lower
    let blue = &diag.channels[2];
    let at = blue.drift_at_drive.unwrap();
    assert!((0.4..=0.8).contains(&at), "{at}");
    // The same failures under the lut, which does not assume what fails: the verdict
    // leads with the model, then names the same failed assumptions.
    let lut = fit_profile(ModelKind::Lut, &d.patches(16), None).unwrap();
    let v = &lut.diagnostics().verdict;
    assert!(
        v.starts_with(
            "The lut assumes neither constant chromaticity nor additivity, so it holds where \
             PLCC's assumptions fail, as they do here: "
        ) && v.contains("blue channel's chromaticity drifts")
            && !v.contains("Models that do not assume them"),
        "{v}"
    );
}

#[test]
fn singular_primaries_are_a_clear_error() {
    let mut d = ideal();
    // blue's column = red's + green's: M has rank 2
    d.cols[2] = std::array::from_fn(|k| d.cols[0][k] + d.cols[1][k]);
    for kind in ModelKind::ALL {
        let e = fit_profile(kind, &d.patches(8), None).unwrap_err();
        assert!(matches!(e, FitError::SingularPrimaries { .. }), "{e}");
        let text = e.to_string();
        assert!(text.contains("condition number"), "{text}");
        assert!(!text.contains("NaN"), "{text}");
    }
    // nearly singular: blue barely differs from red + green
    d.cols[2][2] += 1e-4;
    let e = fit_profile(ModelKind::Plcc, &d.patches(8), None).unwrap_err();
    assert!(matches!(e, FitError::SingularPrimaries { condition, .. } if condition > 1e4));
}

#[test]
fn missing_patches_are_named() {
    let d = ideal();
    let no_black: Vec<Sample> = d
        .patches(4)
        .into_iter()
        .filter(|p| p.rgb != [0.0; 3])
        .collect();
    let e = fit_profile(ModelKind::Plcc, &no_black, None).unwrap_err();
    assert_eq!(
        e.to_string(),
        "plcc needs the black patch (r,g,b = 0,0,0); the measurements have none"
    );
    let corners: Vec<Sample> = d
        .patches(1)
        .into_iter()
        .filter(|p| p.rgb.iter().all(|&v| v == 0.0 || v == 1.0))
        .collect();
    let e = fit_profile(ModelKind::Plcc, &corners, None).unwrap_err();
    assert!(e.to_string().contains("a red ramp"), "{e}");
    assert!(fit_profile(ModelKind::Plcc, &[], None).is_err());
}

#[test]
fn out_of_gamut_and_negative_targets_are_reported_not_hidden() {
    let d = ideal();
    for kind in ModelKind::ALL {
        let p = fit_profile(kind, &d.patches(16), None).unwrap();
        let white = d.forward([1.0; 3]);
        // twice the white: every channel beyond full drive
        let inv = p.inverse(white.map(|v| 2.0 * v));
        assert!(inv.out_of_gamut, "{kind}");
        assert_eq!(inv.rgb, [1.0; 3], "{kind}");
        assert!(inv.unclipped.iter().all(|&v| v > 1.0), "{kind} {inv:?}");
        // negative XYZ: below black, flagged, clipped into 0–1, never NaN
        let inv = p.inverse(Xyz::new(-1.0, -2.0, -3.0));
        assert!(inv.out_of_gamut, "{kind}");
        assert!(
            inv.rgb.iter().all(|v| (0.0..=1.0).contains(v)),
            "{kind} {inv:?}"
        );
        assert!(
            inv.unclipped.iter().all(|v| v.is_finite()),
            "{kind} {inv:?}"
        );
        assert!(inv.unclipped.iter().any(|&v| v < 0.0), "{kind} {inv:?}");
        // a saturated green beyond the primary's chromaticity: one channel negative
        let g = d.forward([0.0, 0.6, 0.0]);
        let inv = p.inverse(Xyz::new(g[0] - 5.0, g[1], g[2] - 3.0));
        assert!(
            inv.out_of_gamut && inv.unclipped.iter().any(|&v| v < 0.0),
            "{kind} {inv:?}"
        );
        // black itself is in gamut
        let inv = p.inverse(d.black.into());
        assert!(!inv.out_of_gamut, "{kind} {inv:?}");
        assert!(inv.rgb.iter().all(|&v| v.abs() < 1e-6), "{kind} {inv:?}");
    }
}

#[test]
fn profile_saves_and_loads() {
    let d = ideal();
    let dir = unused_dir("profile");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("p.json");
    for kind in ModelKind::ALL {
        let p = fit_profile(kind, &d.patches(16), None).unwrap();
        p.save(&path, &metamer::output::OutputPolicy::new(true))
            .unwrap();
        let q = Profile::load(&path).unwrap();
        // PLVC is stored as the grid LUT of its sums: the kind says what was fitted.
        assert_eq!(q.model, kind);
        assert_eq!(q.model().name(), p.model().name());
        for rgb in drives(20) {
            let xyz = p.forward(rgb);
            assert_eq!(q.forward(rgb), xyz);
            assert_eq!(q.inverse(xyz), p.inverse(xyz));
        }
        assert_eq!(q.diagnostics(), p.diagnostics());
    }
    std::fs::write(&path, "{\"format\": 3}").unwrap();
    let e = Profile::load(&path).unwrap_err().to_string();
    assert!(
        e.contains("p.json:1:") && e.contains("not a display profile"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `tests/data/dispread_analytic.ti3` holds the display [`ideal`] in dispread's layout:
/// XYZ normalised to white Y = 100 and LUMINANCE_XYZ_CDM2 the absolute white.
#[test]
fn dispread_ti3_fits_to_the_analytic_display() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dispread_analytic.ti3");
    let m = read_measurement_file(&path).unwrap();
    assert!(m.absolute);
    assert_eq!(m.patches.len(), 137);
    let d = ideal();
    for p in &m.patches {
        let want = d.forward(p.rgb);
        for k in 0..3 {
            assert!(
                (p.xyz[k] - want[k]).abs() < 2e-6 * 120.25,
                "{p:?} vs {want:?}"
            );
        }
    }
    let p = fit_profile(ModelKind::PlccGamma, &m.patches, Some(&path)).unwrap();
    let metamer::display::model::ModelParams::MatrixTrc(mt) = &p.parameters else {
        panic!("plcc-gamma is a matrix model")
    };
    for c in 0..3 {
        let metamer::display::model::Trc::Power { gamma } = mt.trc[c] else {
            panic!("plcc-gamma has power laws")
        };
        assert!((gamma - d.gamma[c]).abs() < 1e-4, "{c}: {gamma}");
        for k in 0..3 {
            assert!((mt.matrix[k][c] - d.cols[c][k]).abs() < 1e-3, "{k},{c}");
            assert!((mt.black[k] - d.black[k]).abs() < 1e-3);
        }
    }
    assert!((p.white_xyz[1] - 120.25).abs() < 1e-9);
    let input = p.input.as_ref().unwrap();
    assert_eq!(input.sha256.len(), 64);
    assert_eq!(input.patches, 137);
    assert!(round_trip(&d, &p, 500) < 0.01);
}

fn mean_and_max_round_trip(display: &Analytic, profile: &Profile, n: usize) -> (f64, f64) {
    let w = display.white();
    let es: Vec<f64> = drives(n)
        .into_iter()
        .map(|rgb| {
            let target = display.forward(rgb);
            let inv = profile.inverse(target);
            de00(display.forward(inv.rgb), target, w)
        })
        .collect();
    (
        es.iter().sum::<f64>() / es.len() as f64,
        es.iter().copied().fold(0.0, f64::max),
    )
}

#[test]
fn every_model_round_trips_a_display_that_satisfies_plcc() {
    let d = ideal();
    // Curve models match the analytic power laws exactly; interpolating models need the
    // ramp at every 8-bit code to stay below 0.01 between levels.
    for (kind, levels) in [
        (ModelKind::PlccGamma, 16),
        (ModelKind::Gog, 16),
        (ModelKind::Gogo, 16),
        (ModelKind::Plcc, 255),
        (ModelKind::MatrixLsq, 255),
        (ModelKind::Lut, 255),
    ] {
        let p = fit_profile(kind, &d.patches(levels), None).unwrap();
        let (_, max) = mean_and_max_round_trip(&d, &p, 2000);
        assert!(max < 0.01, "{kind}: round trip ΔE00 {max}");
        assert!(p.diagnostics().failures.is_empty(), "{kind}");
    }
}

#[test]
fn richer_models_cope_where_plcc_fails() {
    let mut d = ideal();
    d.blue_drift = 1.0;
    d.interaction = 0.04;
    let patches = d.patches_with_grid(16, 9);
    let mean = |kind| {
        let p = fit_profile(kind, &patches, None).unwrap();
        mean_and_max_round_trip(&d, &p, 2000).0
    };
    let plcc = mean(ModelKind::Plcc);
    let lut = mean(ModelKind::Lut);
    let lsq = mean(ModelKind::MatrixLsq);
    assert!(plcc > 1.0, "plcc {plcc}");
    assert!(lut < 0.2 && lut < 0.2 * plcc, "lut {lut} vs plcc {plcc}");
    assert!(lsq < 0.7 * plcc, "matrix-lsq {lsq} vs plcc {plcc}");
}

/// A grid with a hole is no longer refused: it is fitted as scattered data, and the
/// missing node is filled from its neighbours and the shaper-matrix model, so the colour
/// that was not measured is still predicted below a JND on this additive power-law display.
#[test]
fn lut_fills_a_grid_with_a_missing_patch() {
    let d = ideal();
    let hole = [0.5, 0.75, 0.25];
    let patches: Vec<Sample> = d.patches(4).into_iter().filter(|p| p.rgb != hole).collect();
    let profile = fit_profile(ModelKind::Lut, &patches, None).unwrap();
    let white = d.forward([1.0; 3]);
    let e = delta_e2000(
        profile.forward(hole).to_lab(white),
        d.forward(hole).to_lab(white),
    );
    assert!(e < 0.5, "ΔE00 {e} at the missing patch");
}

#[test]
fn verdict_separates_measurement_noise_from_the_display() {
    let mut d = ideal();
    d.interaction = 0.03;
    let patches = d.unique_patches(16);
    let judged = |noise: Option<f64>| {
        let options = FitOptions {
            noise_de00: noise,
            ..FitOptions::default()
        };
        fit_profile_with(ModelKind::Plcc, &patches, None, &options)
            .unwrap()
            .diagnostics()
            .clone()
    };
    let exact = judged(None);
    let a = exact.additivity.as_ref().unwrap().de00;
    assert!(a > 0.5, "additivity {a}");
    assert!(exact.failures.iter().any(|f| f.contains("not additive")));
    assert!(
        exact.verdict.contains("No patch was measured twice"),
        "{}",
        exact.verdict
    );
    // a meter whose single reading scatters by ΔE00 a/2 (1σ) cannot tell: 2σ√4 = 2a > a − 0.5
    let noisy = judged(Some(a / 2.0));
    assert!(noisy.failures.is_empty(), "{noisy}");
    assert!(
        noisy.verdict.contains("Within measurement noise"),
        "{}",
        noisy.verdict
    );
    assert!(noisy.verdict.contains("additivity"), "{}", noisy.verdict);
    // a precise one can
    let precise = judged(Some(0.01));
    assert!(!precise.failures.is_empty(), "{precise}");
}

#[test]
fn noise_is_estimated_from_repeated_patches() {
    let d = ideal();
    let mut patches = d.unique_patches(4);
    let white = d.forward([1.0; 3]);
    // grey 0.5 measured twice more, ±0.5 % in luminance: ΔE00 of each from the mean
    let grey = d.forward([0.5; 3]);
    patches.push(Sample {
        rgb: [0.5; 3],
        xyz: grey.map(|v| v * 1.005),
    });
    patches.push(Sample {
        rgb: [0.5; 3],
        xyz: grey.map(|v| v * 0.995),
    });
    let n = metamer::display::diagnostics::repeat_noise(&patches, white).unwrap();
    assert_eq!(n.source, "1 repeated patches");
    // three readings at 1, 1.005, 0.995: deviations 0, ±0.5 %; σ² = Σ ΔE² / (3 − 1)
    let w = white;
    let e = de00(grey.map(|v| v * 1.005), grey, w);
    let e2 = de00(grey.map(|v| v * 0.995), grey, w);
    let want = ((e * e + e2 * e2) / 2.0).sqrt();
    assert!((n.de00 - want).abs() < 1e-12, "{} vs {want}", n.de00);
    let p = fit_profile(ModelKind::Plcc, &patches, None).unwrap();
    assert_eq!(p.diagnostics().noise.as_ref().unwrap(), &n);
}

#[test]
fn a_white_repeat_read_30_percent_low_is_warned_about_not_taken_as_noise() {
    let d = ideal();
    let mut patches = d.unique_patches(4);
    let white = d.forward([1.0; 3]);
    // White twice more: once within the CS-100A's ±0.2 %, once 30 % low.
    for k in [1.002, 0.7] {
        patches.push(Sample {
            rgb: [1.0; 3],
            xyz: white.map(|v| v * k),
        });
    }
    let n = metamer::display::diagnostics::repeat_noise(&patches, white).unwrap();
    // Y from 0.7·Yw to 1.002·Yw: (1.002 − 0.7)/1.002 = 30.1 % apart.
    assert_eq!(n.disagreeing.len(), 1, "{:?}", n.disagreeing);
    assert!(
        n.disagreeing[0].contains("(30.1 % apart)"),
        "{}",
        n.disagreeing[0]
    );
    let p = fit_profile(ModelKind::Plcc, &patches, None).unwrap();
    let verdict = &p.diagnostics().verdict;
    assert!(
        verdict.starts_with(
            "Warning: repeated readings disagree beyond the instrument's repeatability"
        ),
        "{verdict}"
    );
    // Repeats within the stated repeatability raise no warning.
    patches.pop();
    let n = metamer::display::diagnostics::repeat_noise(&patches, white).unwrap();
    assert!(n.disagreeing.is_empty(), "{:?}", n.disagreeing);
}

const FOLD_BLACK: [f64; 3] = [0.5, 0.5, 0.6];
const FOLD_PRIMARIES: [[f64; 3]; 3] = [[40.0, 20.0, 2.0], [35.0, 70.0, 10.0], [18.0, 8.0, 95.0]];

/// Patches of a linear display at the drive levels `levels` (every combination), except that
/// full white reads `white`, plus half-drive ramps for the table's shapers.
fn grid_with_white(levels: &[f64], white: [f64; 3]) -> Vec<Sample> {
    let (black, [r, g, b]) = (FOLD_BLACK, FOLD_PRIMARIES);
    let mut out = Vec::new();
    for &i in levels {
        for &j in levels {
            for &k in levels {
                let xyz = if (i, j, k) == (1.0, 1.0, 1.0) {
                    white
                } else {
                    std::array::from_fn(|c| black[c] + i * r[c] + j * g[c] + k * b[c])
                };
                out.push(Sample {
                    rgb: [i, j, k],
                    xyz: xyz.into(),
                });
            }
        }
    }
    if !levels.contains(&0.5) {
        for (c, p) in [r, g, b].iter().enumerate() {
            let mut rgb = [0.0; 3];
            rgb[c] = 0.5;
            out.push(Sample {
                rgb,
                xyz: Xyz::from(std::array::from_fn::<f64, 3, _>(|k| black[k] + 0.5 * p[k])),
            });
        }
    }
    out
}

fn white_at(sign_of_blue: f64) -> [f64; 3] {
    let (black, [r, g, b]) = (FOLD_BLACK, FOLD_PRIMARIES);
    std::array::from_fn(|c| black[c] + r[c] + g[c] + sign_of_blue * b[c])
}

/// A measured 3×3×3 grid of a linear display whose white reads R + G − B: the grid LUT
/// stores every reading, so its top cell folds. By hand (as in `Lut3d::folded_tetrahedra`'s
/// test): the paths reaching white last along blue end with the edge W − (R + G + B/2) =
/// −1.5·B and flip; the others keep the primaries' orientation, so 2 of the 2³·6 = 48
/// tetrahedra fold. The report says so before its residuals; with an additive white it
/// says nothing.
#[test]
fn a_folded_table_is_reported() {
    let levels = [0.0, 0.5, 1.0];
    let p = fit_profile(
        ModelKind::Lut,
        &grid_with_white(&levels, white_at(-1.0)),
        None,
    )
    .unwrap();
    assert_eq!(p.diagnostics.folded_tetrahedra, Some([2, 48]));
    let v = &p.diagnostics.verdict;
    let warning = v.find("folds in 2 of its 48 tetrahedra").expect(v);
    assert!(
        warning < v.find("The fitted lut reproduces").unwrap(),
        "{v}"
    );
    let p = fit_profile(
        ModelKind::Lut,
        &grid_with_white(&levels, white_at(1.0)),
        None,
    )
    .unwrap();
    assert_eq!(p.diagnostics.folded_tetrahedra, None);
    assert!(!p.diagnostics.verdict.contains("folds"));
}

/// The same impossible white among the cube's corners and half ramps goes to the scattered
/// fit (a 9-level table: 8³·6 = 3072 tetrahedra), which without a constraint folds there.
/// The fit holds the edges of its folded tetrahedra along their channels and refits until
/// the determinant test (a different criterion from the one it enforces) finds no fold; an
/// additive white needs no edge held.
#[test]
fn the_scattered_fit_does_not_fold_where_the_readings_would() {
    use metamer::display::model::{fit_lut_scattered, samples::SortedSamples};
    let fit = |patches: &[Sample], lambda| {
        fit_lut_scattered(&SortedSamples::new(patches), patches, 9, lambda).unwrap()
    };
    let corners = [0.0, 1.0];
    let folded = grid_with_white(&corners, white_at(-1.0));
    let constrained = fit(&folded, None);
    assert_eq!(constrained.lut.folded_tetrahedra(), (0, 3072));
    assert!(constrained.held_edges > 0);
    let p = fit_profile(ModelKind::Lut, &folded, None).unwrap();
    assert_eq!(p.diagnostics.folded_tetrahedra, None);
    let additive = fit(&grid_with_white(&corners, white_at(1.0)), None);
    assert_eq!(additive.held_edges, 0);
    assert_eq!(additive.lut.folded_tetrahedra(), (0, 3072));
}
