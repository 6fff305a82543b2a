//! Shaper + matrix fitted jointly over every patch, in CIELAB: XYZ = b + M·[R′ G′ B′]ᵀ with
//! one monotone curve per channel, the form of an ICC matrix/TRC display profile.
//!
//! Where `matrix-lsq` takes its curves from single-channel ramps, this model lets every
//! patch shape them, so scattered patch sets (no ramps at all) fit as well as ramp sets.
//! The fit runs in two Levenberg–Marquardt stages:
//! 1. a power law per channel with the matrix and black offset (15 parameters), started
//!    from γ 2.2 and a weighted linear least-squares matrix;
//! 2. each curve becomes a ramp table on `K` evenly spaced drive knots, interpolated in
//!    the domain of its stage-1 power law (so the start is exactly stage 1), whose knot
//!    values are free but monotone by construction: the root-domain value at knot k is the
//!    normalised cumulative sum of positive increments e^tⱼ. Its error is the CIELAB
//!    difference relative to the display white, so where the curves are not power laws
//!    dark and bright patches count by what is seen.
//!
//! Stage 1 is stage 2 with all increments equal. Which of the two forms is returned is
//! decided by cross-validation: on a display whose curves are power laws the knots would
//! only follow the meter's noise, while on most LCDs they are what makes the fit.
//!
//! When the power laws are kept and they hold within a meter's noise (their misses, in
//! units of the CS-100A's noise, no more than twice that noise on average), what is left
//! is the meter's noise; then they are refitted with each reading's miss counted in units
//! of a reading's noise (relative luminance, x and y), the most likely parameters, which
//! average every reading's noise by its size. Where the misses are larger, the form is
//! what misses, and the CIELAB fit stays. CIELAB counts the dim patches' chromaticity
//! for less than their noise warrants: on the ramp-only set of `ideal-crt` read with the
//! CS-100A's noise (six meter seeds) the inverse round trip's mean ΔE00 fell from 0.008
//! to 0.003, below `colprof -as`'s 0.007 (benches/argyll/README.md, `tests/display/ramp_fit.rs`).

use nalgebra::{DMatrix, DVector};

use super::error::FitError;
use super::least_squares::levenberg_marquardt;
use super::plcc::singular;
use super::samples::{fold_of, Sample, SortedSamples, SAME_DRIVE};
use super::{DisplayModel, MatrixTrc, ModelKind, Trc};
use crate::color::{delta_e2000, Lab, Xyz};

/// Knot intervals per curve for a patch count: each knot costs one parameter per channel,
/// so very small sets get few; on the simulated panels held-out error still fell from 4 to
/// 6 knots at 50 scattered patches and from 6 to 8 at 200, so sets of 120 get all 8.
pub fn default_knots(patches: usize) -> usize {
    match patches {
        0..=19 => 2,
        20..=39 => 4,
        40..=119 => 6,
        _ => 8,
    }
}

/// Fits the shaper + matrix model to every patch; `knots` intervals per curve (≥ 1).
pub fn fit_shaper_matrix(
    set: &SortedSamples,
    patches: &[Sample],
    knots: usize,
) -> Result<MatrixTrc, FitError> {
    let (lab, knotted, noise) = fit_stages(set, patches, knots, true)?;
    if knots <= 1 || choose_stage(set, patches, knots, &knotted) {
        return Ok(noise.unwrap_or(lab));
    }
    Ok(knotted)
}

/// Stage 1's model fitted in CIELAB (power laws, as stage-2 tables with equal increments),
/// stage 2's, and with `noise_units` stage 1 refitted in units of a reading's noise.
fn fit_stages(
    set: &SortedSamples,
    patches: &[Sample],
    knots: usize,
    noise_units: bool,
) -> Result<(MatrixTrc, MatrixTrc, Option<MatrixTrc>), FitError> {
    let kind = ModelKind::ShaperMatrix;
    let knots = knots.max(1);
    let (problem, shared) = Problem::new(set, patches)?;
    let (mut lower, mut upper) = (vec![-10.0; 12], vec![10.0; 12]);
    for i in 9..12 {
        lower[i] = -0.5;
        upper[i] = 0.5;
    }
    let (p1, p1_noise) = problem.power_laws(&shared, (&lower, &upper), noise_units);
    let gamma = [p1[0], p1[1], p1[2]];
    let drive: Vec<f64> = (0..=knots).map(|k| k as f64 / knots as f64).collect();
    let free = knots - 1;
    let (start2, p2) = problem.knot_tables(&p1, gamma, &drive, free, (&lower, &upper));
    let model = |p: &[f64]| {
        let (m, b) = problem.unpack(&p[3 * free..]);
        MatrixTrc::new(kind, b.into(), m, tables(p, free, &drive, gamma)).map_err(singular)
    };
    let noise = match p1_noise {
        Some(p) => {
            let (m, b) = problem.unpack(&p[3..]);
            let trc = std::array::from_fn(|c| Trc::Table {
                drive: drive.clone(),
                value: drive.iter().map(|d| d.powf(p[c])).collect(),
                exponent: p[c],
            });
            Some(MatrixTrc::new(kind, b.into(), m, trc).map_err(singular)?)
        }
        None => None,
    };
    Ok((model(&start2)?, model(&p2)?, noise))
}

/// What both stages fit: the patches, their CIELAB relative to a white that stays fixed
/// during the fit, and the white's luminance that the matrix and black are scaled by.
struct Problem<'a> {
    patches: &'a [Sample],
    measured: Vec<Lab>,
    white: Xyz,
    yw: f64,
}

impl<'a> Problem<'a> {
    /// The problem, and the parameters both stages share at their start: the linear
    /// matrix (row-major) and black of power laws of 2.2, in units of white Y.
    fn new(
        set: &SortedSamples,
        patches: &'a [Sample],
    ) -> Result<(Problem<'a>, Vec<f64>), FitError> {
        let kind = ModelKind::ShaperMatrix;
        if patches.len() < 8 {
            return Err(FitError::Missing {
                model: kind,
                what: format!(
                    "at least 8 patches to fit 15 parameters in 3 equations each (found {})",
                    patches.len()
                ),
            });
        }
        let (black0, m0) =
            linear_matrix(patches, &[2.2; 3], set.white.map(|w| w[1])).ok_or_else(|| {
                FitError::Failed {
                    model: kind,
                    message:
                        "the patches do not span the three channels: the matrix is undetermined \
                      (measure colours that vary each of red, green and blue)"
                            .into(),
                }
            })?;
        // The CIELAB reference stays fixed during the fit: the measured white if there is
        // one, otherwise the start model's white.
        let white = set.white.unwrap_or_else(|| {
            Xyz::from(std::array::from_fn(|r| {
                black0[r] + m0[r].iter().sum::<f64>()
            }))
        });
        let yw = white[1];
        if !(yw.is_finite() && yw > 0.0) {
            return Err(FitError::Failed {
                model: kind,
                message: format!("the white has no positive luminance (Y = {yw})"),
            });
        }
        let mut shared: Vec<f64> = m0.iter().flatten().map(|v| v / yw).collect();
        shared.extend(black0.iter().map(|v| v / yw));
        let problem = Problem {
            patches,
            measured: patches.iter().map(|p| p.xyz.to_lab(white)).collect(),
            white,
            yw,
        };
        Ok((problem, shared))
    }

    /// The CIELAB misses of `predict` on every patch.
    fn lab_residual(&self, predict: &dyn Fn([f64; 3]) -> [f64; 3]) -> Vec<f64> {
        let mut r = Vec::with_capacity(3 * self.patches.len());
        for (p, m) in self.patches.iter().zip(&self.measured) {
            let lab = Xyz::from_array(predict(p.rgb)).to_lab(self.white);
            r.extend([lab.l - m.l, lab.a - m.a, lab.b - m.b]);
        }
        r
    }

    /// The misses of `predict` on every patch in units of a reading's noise.
    fn noise_residual(&self, predict: &dyn Fn([f64; 3]) -> [f64; 3]) -> Vec<f64> {
        let floor = NOISE_FLOOR * self.yw;
        let mut r = Vec::with_capacity(3 * self.patches.len());
        for p in self.patches {
            let q = predict(p.rgb);
            r.extend(reading_residual(q, p.xyz.into(), floor));
        }
        r
    }

    /// The matrix and black of the 12 shared parameters.
    fn unpack(&self, p: &[f64]) -> ([[f64; 3]; 3], [f64; 3]) {
        (
            std::array::from_fn(|r| std::array::from_fn(|c| p[r * 3 + c] * self.yw)),
            std::array::from_fn(|r| p[9 + r] * self.yw),
        )
    }

    /// Stage 1: power laws, fitted in CIELAB, and with `noise_units` refitted in units of
    /// a reading's noise where that fits within it.
    fn power_laws(
        &self,
        shared: &[f64],
        (lower, upper): (&[f64], &[f64]),
        noise_units: bool,
    ) -> (Vec<f64>, Option<Vec<f64>>) {
        let mut start: Vec<f64> = vec![2.2; 3];
        start.extend(shared);
        let mut lo1 = vec![0.3; 3];
        lo1.extend(lower);
        let mut hi1 = vec![5.0; 3];
        hi1.extend(upper);
        let stage1 = |p: &[f64]| -> Vec<f64> {
            let (m, b) = self.unpack(&p[3..]);
            self.lab_residual(&|rgb| {
                apply(&m, &b, std::array::from_fn(|c| rgb[c].max(0.0).powf(p[c])))
            })
        };
        let p1 = levenberg_marquardt(&stage1, &start, &lo1, &hi1);
        let stage1_noise = |p: &[f64]| -> Vec<f64> {
            let (m, b) = self.unpack(&p[3..]);
            self.noise_residual(&|rgb| {
                apply(&m, &b, std::array::from_fn(|c| rgb[c].max(0.0).powf(p[c])))
            })
        };
        // Kept only where the power laws hold within the noise: a reduced χ² (in units of
        // the assumed noise) beyond MAX_REDUCED_CHI2 says the misses are the form's, not the
        // meter's, and then CIELAB's weighting by what is seen is the better one.
        let p1_noise = noise_units
            .then(|| levenberg_marquardt(&stage1_noise, &p1, &lo1, &hi1))
            .filter(|p| {
                let dof = (3 * self.patches.len()).saturating_sub(p.len()).max(1);
                let chi2: f64 = stage1_noise(p).iter().map(|r| r * r).sum();
                chi2 / dof as f64 <= MAX_REDUCED_CHI2
            });
        (p1, p1_noise)
    }

    /// Stage 2: monotone knot tables (`free` free increments per channel) in each power
    /// law's root domain, started from stage 1's `p1`; its start and its fit.
    fn knot_tables(
        &self,
        p1: &[f64],
        gamma: [f64; 3],
        drive: &[f64],
        free: usize,
        (lower, upper): (&[f64], &[f64]),
    ) -> (Vec<f64>, Vec<f64>) {
        let mut start2 = vec![0.0; 3 * free];
        start2.extend(&p1[3..]);
        let mut lo2 = vec![-8.0; 3 * free];
        lo2.extend(lower);
        let mut hi2 = vec![8.0; 3 * free];
        hi2.extend(upper);
        let stage2 = |p: &[f64]| -> Vec<f64> {
            let trc = tables(p, free, drive, gamma);
            let (m, b) = self.unpack(&p[3 * free..]);
            self.lab_residual(&|rgb| apply(&m, &b, std::array::from_fn(|c| trc[c].eval(rgb[c]))))
        };
        let p2 = if free > 0 {
            levenberg_marquardt(&stage2, &start2, &lo2, &hi2)
        } else {
            start2.clone()
        };
        (start2, p2)
    }
}

/// XYZ of linear drives `lin` through matrix `m` over black `b`.
fn apply(m: &[[f64; 3]; 3], b: &[f64; 3], lin: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| b[r] + m[r][0] * lin[0] + m[r][1] * lin[1] + m[r][2] * lin[2])
}

/// Stage 2's tone curves of parameters `t`: per channel, `free` log increments after a
/// first of 1, accumulated and normalised, raised to the channel's power law `gamma`.
fn tables(t: &[f64], free: usize, drive: &[f64], gamma: [f64; 3]) -> [Trc; 3] {
    std::array::from_fn(|c| {
        let mut inc = vec![1.0];
        inc.extend(t[c * free..(c + 1) * free].iter().map(|v| v.exp()));
        let total: f64 = inc.iter().sum();
        let mut u = vec![0.0];
        let mut acc = 0.0;
        for v in &inc {
            acc += v;
            u.push(acc / total);
        }
        Trc::Table {
            drive: drive.to_vec(),
            value: u.iter().map(|v| v.powf(gamma[c])).collect(),
            exponent: gamma[c],
        }
    })
}

/// Below this fraction of the white's luminance a reading's noise is taken as constant,
/// as near black a meter's noise stops shrinking with the light (the same floor as
/// `matrix-lsq`'s weights).
const NOISE_FLOOR: f64 = 0.01;

/// The most a power-law fit's mean squared miss may be, in units of the assumed noise's
/// variance, for it to be taken as noise: 4, misses up to twice the CS-100A's 1σ (a meter
/// twice as noisy still qualifies). On the ramp-only sets of `ips-lcd` and
/// `wide-gamut-ccfl`, whose curves are not power laws, it was 700–2400 with or without the
/// meter's noise; on the noisy `ideal-crt` 0.7–0.9.
const MAX_REDUCED_CHI2: f64 = 4.0;

/// Relative luminance and chromaticity repeatability of one reading (1σ): those of the
/// CS-100A (0.1 % of Y, 0.0005 in x and y). Only their ratio shapes the fit.
const SIGMA_Y_REL: f64 = 0.001;
const SIGMA_XY: f64 = 0.0005;

/// A prediction's miss of a reading in units of the reading's noise: relative luminance,
/// x and y. Below `floor` (cd/m²) luminance counts as `floor`, as a meter's noise stops
/// shrinking with the light near black.
fn reading_residual(predicted: [f64; 3], measured: [f64; 3], floor: f64) -> [f64; 3] {
    let chroma = |v: [f64; 3]| {
        let s = v[0] + v[1] + v[2];
        if s.abs() < 1e-300 {
            [0.0, 0.0]
        } else {
            [v[0] / s, v[1] / s]
        }
    };
    let (cp, cm) = (chroma(predicted), chroma(measured));
    let y = measured[1].max(floor);
    // Near black a reading's chromaticity is as uncertain as its luminance allows.
    let w = (measured[1] / floor).min(1.0);
    [
        (predicted[1] - measured[1]) / y / SIGMA_Y_REL,
        w * (cp[0] - cm[0]) / SIGMA_XY,
        w * (cp[1] - cm[1]) / SIGMA_XY,
    ]
}

/// Folds of the cross-validation that decides between stage 1 and stage 2.
const FOLDS: usize = 3;

/// At most this many patches take part in that cross-validation (a seeded subset beyond),
/// so its cost is bounded whatever the file holds.
const CV_PATCHES: usize = 1000;

/// Whether the power laws (stage 1) predict held-out patches at least as well as the knots
/// (stage 2), both fitted in CIELAB (mean ΔE00 over [`FOLDS`] folds, the cube's corners
/// always fitted): the form is chosen by what is seen, like against like. `knotted` (the whole
/// set's stage 2) gives the white where the set has none.
fn choose_stage(
    set: &SortedSamples,
    patches: &[Sample],
    knots: usize,
    knotted: &MatrixTrc,
) -> bool {
    let corner = |p: &Sample| {
        p.rgb
            .iter()
            .all(|&d| !(SAME_DRIVE..=1.0 - SAME_DRIVE).contains(&d))
    };
    let mut order: Vec<usize> = (0..patches.len()).collect();
    order.sort_by_key(|&i| fold_of(i));
    let chosen: Vec<usize> = order.into_iter().take(CV_PATCHES).collect();
    let white = set.white.unwrap_or_else(|| knotted.forward([1.0; 3]));
    let mut error = [0.0f64; 2];
    for fold in 0..FOLDS {
        let held = |i: usize| !corner(&patches[i]) && fold_of(i) % FOLDS == fold;
        let train: Vec<Sample> = chosen
            .iter()
            .filter(|&&i| !held(i))
            .map(|&i| patches[i])
            .collect();
        let Ok((one, two, _)) = fit_stages(&SortedSamples::new(&train), &train, knots, false)
        else {
            return false;
        };
        for &i in chosen.iter().filter(|&&i| held(i)) {
            let measured = patches[i].xyz.to_lab(white);
            for (e, m) in error.iter_mut().zip([&one, &two]) {
                *e += delta_e2000(m.forward(patches[i].rgb).to_lab(white), measured);
            }
        }
    }
    error[0] <= error[1]
}

/// Black offset and matrix by linear least squares for fixed power-law curves, each patch
/// weighted by 1 / max(Y, 1 % of the brightest), close to a relative (perceptual) error.
fn linear_matrix(
    patches: &[Sample],
    gamma: &[f64; 3],
    white_y: Option<f64>,
) -> Option<([f64; 3], [[f64; 3]; 3])> {
    let n = patches.len();
    let brightest = white_y.unwrap_or_else(|| patches.iter().map(|p| p.xyz[1]).fold(0.0, f64::max));
    let mut a = DMatrix::<f64>::zeros(n, 4);
    let mut rhs = DMatrix::<f64>::zeros(n, 3);
    for (i, p) in patches.iter().enumerate() {
        let w = 1.0 / p.xyz[1].max(0.01 * brightest).max(1e-12);
        for c in 0..3 {
            a[(i, c)] = w * p.rgb[c].max(0.0).powf(gamma[c]);
            rhs[(i, c)] = w * p.xyz[c];
        }
        a[(i, 3)] = w;
    }
    let svd = a.svd(true, true);
    let sv = &svd.singular_values;
    if sv.min() <= 1e-9 * sv.max() {
        return None;
    }
    let mut m = [[0.0; 3]; 3];
    let mut b = [0.0; 3];
    for r in 0..3 {
        let col = DVector::from_iterator(n, rhs.column(r).iter().copied());
        let x = svd.solve(&col, 1e-12).ok()?;
        for c in 0..3 {
            m[r][c] = x[c];
        }
        b[r] = x[3];
    }
    Some((b, m))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::display::model::DisplayModel;

    /// An additive display with known power laws and black: the model family contains
    /// it, so the fit must find it from scattered patches alone (no ramps, no white).
    #[test]
    fn recovers_an_additive_power_law_display_from_scattered_patches() {
        let m = [[41.2, 35.8, 18.0], [21.3, 71.5, 7.2], [1.9, 11.9, 95.0]];
        let b = [0.3, 0.31, 0.35];
        let g = [2.4, 2.2, 2.0];
        let truth = |rgb: [f64; 3]| -> [f64; 3] {
            std::array::from_fn(|r| b[r] + (0..3).map(|c| m[r][c] * rgb[c].powf(g[c])).sum::<f64>())
        };
        // A 3-dimensional Halton set: scattered, no two patches share a channel level.
        let halton = |mut i: usize, base: usize| {
            let (mut f, mut x) = (1.0, 0.0);
            while i > 0 {
                f /= base as f64;
                x += f * (i % base) as f64;
                i /= base;
            }
            x
        };
        let patches: Vec<Sample> = (1..=60)
            .map(|i| {
                let rgb = [halton(i, 2), halton(i, 3), halton(i, 5)];
                Sample {
                    rgb,
                    xyz: truth(rgb).into(),
                }
            })
            .collect();
        let set = SortedSamples::new(&patches);
        let fit = fit_shaper_matrix(&set, &patches, 4).unwrap();
        for rgb in [
            [0.0; 3],
            [1.0; 3],
            [0.05, 0.0, 0.0],
            [0.3, 0.7, 0.1],
            [0.9, 0.2, 0.6],
        ] {
            let (f, t) = (fit.forward(rgb), truth(rgb));
            for k in 0..3 {
                assert!(
                    (f[k] - t[k]).abs() < 2e-3 * 100.0,
                    "{rgb:?}: {f:?} vs {t:?}"
                );
            }
        }
    }

    /// The curves of `fit` are stage 1's power laws when every knot value is (k/K)^γ.
    fn is_power_law(fit: &MatrixTrc) -> bool {
        fit.trc.iter().all(|t| match t {
            Trc::Table {
                drive,
                value,
                exponent,
            } => drive
                .iter()
                .zip(value)
                .all(|(d, v)| (v - d.powf(*exponent)).abs() < 1e-9),
            _ => false,
        })
    }

    /// 300 seeded scattered patches of an additive display with the channel curve `curve`,
    /// read with a 0.3 % luminance noise.
    fn noisy_display(curve: impl Fn(f64) -> f64) -> Vec<Sample> {
        let m = [[41.2, 35.8, 18.0], [21.3, 71.5, 7.2], [1.9, 11.9, 95.0]];
        let mut rng = metamer_drivers::noise::SplitMix64::new(7);
        (0..300)
            .map(|_| {
                let rgb: [f64; 3] = std::array::from_fn(|_| rng.uniform());
                let lin = rgb.map(&curve);
                let k = 1.0 + 0.003 * rng.normal();
                let xyz = std::array::from_fn(|r| {
                    k * (0.2 + (0..3).map(|c| m[r][c] * lin[c]).sum::<f64>())
                });
                Sample {
                    rgb,
                    xyz: xyz.into(),
                }
            })
            .collect()
    }

    /// With noise on a power-law display the knots only follow the noise, and
    /// cross-validation drops them; an S-shaped curve (not a power law by far) keeps them.
    #[test]
    fn knots_are_kept_only_where_the_curve_needs_them() {
        let power = noisy_display(|d| d.powf(2.2));
        let fit = fit_shaper_matrix(&SortedSamples::new(&power), &power, 8).unwrap();
        assert!(is_power_law(&fit), "{:?}", fit.trc);
        let s_curve = noisy_display(|d| d * d * (3.0 - 2.0 * d));
        let fit = fit_shaper_matrix(&SortedSamples::new(&s_curve), &s_curve, 8).unwrap();
        assert!(!is_power_law(&fit), "{:?}", fit.trc);
    }

    /// By hand: a reading of XYZ (40, 50, 10) has x 0.4, y 0.5. A prediction 1 % brighter
    /// at the same chromaticity misses by 0.01 / 0.001 = 10 luminance σ and no chromatic
    /// σ; (41, 50, 9) has the same sum and Y, x 0.41: 0.01 / 0.0005 = 20 σ in x, 0 in y.
    /// A reading of Y 0.5 below a floor of 1 counts its luminance miss against the floor
    /// and its chromaticity at half weight.
    #[test]
    fn a_readings_miss_is_counted_in_units_of_its_noise() {
        let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-9);
        let m = [40.0, 50.0, 10.0];
        let r = reading_residual([40.4, 50.5, 10.1], m, 1.0);
        assert!(close(r, [10.0, 0.0, 0.0]), "{r:?}");
        let r = reading_residual([41.0, 50.0, 9.0], m, 1.0);
        assert!(close(r, [0.0, 20.0, 0.0]), "{r:?}");
        let dim = [0.4, 0.5, 0.1];
        let r = reading_residual([0.41, 0.5, 0.09], dim, 1.0);
        assert!(close(r, [0.0, 10.0, 0.0]), "{r:?}");
        let r = reading_residual([0.4, 0.51, 0.1], dim, 1.0);
        let x = 0.4 / 1.01 - 0.4;
        let y = 0.51 / 1.01 - 0.5;
        assert!(
            close(r, [0.01 / 0.001, 0.5 * x / 0.0005, 0.5 * y / 0.0005]),
            "{r:?}"
        );
    }

    #[test]
    fn refuses_patches_that_vary_only_one_channel() {
        let patches: Vec<Sample> = (0..20)
            .map(|i| {
                let d = i as f64 / 19.0;
                Sample {
                    rgb: [d, 0.0, 0.0],
                    xyz: Xyz::new(40.0 * d * d, 20.0 * d * d, 2.0 * d * d),
                }
            })
            .collect();
        let err = fit_shaper_matrix(&SortedSamples::new(&patches), &patches, 4).unwrap_err();
        assert!(err.to_string().contains("do not span"), "{err}");
    }
}
