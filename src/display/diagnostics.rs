//! Checks of PLCC's assumptions (paper Eq. 9) on the measured patches, saved with every fit:
//! each channel's chromaticity drift along its ramp, additivity (white against the sum of
//! black and the three primaries), black level share, the TRC's deviation from a power law,
//! the condition number of M, and a plain verdict. Differences are CIEDE2000 in CIELAB relative to the
//! display white, the measure the paper validates with.

use serde::{Deserialize, Serialize};

mod verdict;

use super::model::samples::{Sample, SortedSamples, CHANNEL_NAMES, SAME_DRIVE};
use super::model::{condition_number, fit_power_gamma, ModelKind};
use crate::color::{delta_e2000, Xyz};

/// Default tolerance of the verdict, ΔE00.
pub const TOLERANCE_DE00: f64 = 0.5;

/// How well the fitted model reproduces the measured patches.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Residuals {
    pub patches: usize,
    pub mean_de00: f64,
    pub p95_de00: f64,
    pub max_de00: f64,
    /// Drive values of the worst patch.
    pub worst_rgb: [f64; 3],
    /// Root mean square of the XYZ differences, cd/m².
    pub rms_xyz: f64,
}

/// One channel's ramp checks (absent values: not measured).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChannelDiagnostics {
    pub channel: String,
    /// Ramp levels strictly between 0 and 1.
    pub levels: usize,
    /// Largest xy distance of a ramp patch's black-corrected chromaticity from the full-on
    /// primary's (patches above 5 % of the primary's luminance).
    pub chromaticity_drift_xy: Option<f64>,
    /// Largest ΔE00 between a ramp patch and the constant-chromaticity prediction.
    pub chromaticity_drift_de00: Option<f64>,
    pub drift_at_drive: Option<f64>,
    /// Least-squares power-law exponent of the ramp.
    pub gamma: Option<f64>,
    /// Largest ΔE00 between the measured TRC and that power law along the ramp.
    pub power_law_de00: Option<f64>,
}

/// White measured against black + the three primaries' contributions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Additivity {
    pub de00: f64,
    /// (Y_white − Y_predicted) / Y_white, percent.
    pub luminance_error_percent: f64,
}

/// Everything checked, and the verdict.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Diagnostics {
    pub model: ModelKind,
    pub tolerance_de00: f64,
    pub channels: Vec<ChannelDiagnostics>,
    pub additivity: Option<Additivity>,
    /// Y_black / Y_white.
    pub black_share: Option<f64>,
    pub condition_number: Option<f64>,
    pub residuals: Residuals,
    /// Measurement noise, ΔE00 of one reading (1σ): from repeated patches or given.
    #[serde(default)]
    pub noise: Option<Noise>,
    /// Mixed patches (two or more channels on, the white not counted), when fewer than
    /// model selection needs to judge mixtures: the verdict then says what the profile's
    /// mixtures rest on and how much a measured grid would help.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub few_mixtures: Option<usize>,
    /// Of a table model (lut), the tetrahedra that fold and all of them (see
    /// `Lut3d::folded_tetrahedra`), when any fold.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub folded_tetrahedra: Option<[usize; 2]>,
    /// Assumptions that fail beyond the tolerance and the measurement noise, each in one
    /// sentence.
    pub failures: Vec<String>,
    pub verdict: String,
}

/// How noisy one reading is.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Noise {
    /// 1σ ΔE00 of a single reading around the mean of its repeats.
    pub de00: f64,
    /// Where the figure comes from ("7 repeated patches", "given").
    pub source: String,
    /// Repeated patches whose readings disagree beyond what an instrument's repeatability
    /// allows (see [`REPEAT_Y_TOLERANCE`]), one sentence each: a reading that went wrong,
    /// not noise, and it inflates `de00`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub disagreeing: Vec<String>,
}

/// Largest relative spread of a patch's repeated luminances taken as noise: five times the
/// CS-100A's stated repeatability of ±0.2 % in Y (the tighter of the instruments here), so
/// honest noise never trips it and a reading 30 % low always does.
pub const REPEAT_Y_TOLERANCE: f64 = 0.01;
/// The same for chromaticity: five times the CS-100A's ±0.001 in x and y.
pub const REPEAT_XY_TOLERANCE: f64 = 0.005;

/// Why a patch's repeats disagree beyond the instruments' repeatability, if they do.
fn disagreement(rgb: [f64; 3], xyzs: &[Xyz]) -> Option<String> {
    let ys: Vec<f64> = xyzs.iter().map(|x| x[1]).collect();
    let (lo, hi) = ys
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
            (a.min(y), b.max(y))
        });
    let xys: Vec<(f64, f64)> = xyzs.iter().map(|&x| xy(x)).collect();
    let xy_spread = xys
        .iter()
        .flat_map(|a| {
            xys.iter()
                .map(move |b| (a.0 - b.0).abs().max((a.1 - b.1).abs()))
        })
        .fold(0.0, f64::max);
    // Near black the relative spread means nothing; 0.01 is a meter's last digit.
    let y_bad = hi - lo > REPEAT_Y_TOLERANCE * hi.abs().max(0.01 / REPEAT_Y_TOLERANCE);
    let xy_bad = hi > 1.0 && xy_spread > REPEAT_XY_TOLERANCE;
    (y_bad || xy_bad).then(|| {
        format!(
            "drive {:.3},{:.3},{:.3}: {} readings with Y from {lo:.4} to {hi:.4} \
             ({:.1} % apart) and x, y up to {xy_spread:.4} apart",
            rgb[0],
            rgb[1],
            rgb[2],
            xyzs.len(),
            100.0 * (hi - lo) / hi.abs().max(f64::MIN_POSITIVE)
        )
    })
}

/// The scatter of repeated readings: RMS ΔE00 of each reading from its patch's mean, with
/// n − 1 degrees of freedom per patch; None when no patch was measured twice.
pub fn repeat_noise(patches: &[Sample], white: Xyz) -> Option<Noise> {
    let w = white;
    let key = |p: &Sample| p.rgb.map(|d| (d * 1e6).round() as i64);
    let mut groups: std::collections::HashMap<[i64; 3], Vec<Xyz>> = Default::default();
    for p in patches {
        groups.entry(key(p)).or_default().push(p.xyz);
    }
    let (mut sum, mut dof, mut repeated) = (0.0, 0usize, 0usize);
    let mut disagreeing = Vec::new();
    let mut keys: Vec<&[i64; 3]> = groups.keys().collect();
    keys.sort();
    for key in keys {
        let xyzs = &groups[key];
        if xyzs.len() < 2 {
            continue;
        }
        disagreeing.extend(disagreement(key.map(|k| k as f64 / 1e6), xyzs));
        let n = xyzs.len() as f64;
        let mean: [f64; 3] = std::array::from_fn(|k| xyzs.iter().map(|x| x[k]).sum::<f64>() / n);
        sum += xyzs.iter().map(|x| de(*x, mean, w).powi(2)).sum::<f64>();
        dof += xyzs.len() - 1;
        repeated += 1;
    }
    (dof > 0).then(|| Noise {
        de00: (sum / dof as f64).sqrt(),
        source: format!("{repeated} repeated patches"),
        disagreeing,
    })
}

fn de(a: impl Into<Xyz>, b: impl Into<Xyz>, white: Xyz) -> f64 {
    delta_e2000(a.into().to_lab(white), b.into().to_lab(white))
}

fn xy(v: impl std::ops::Index<usize, Output = f64>) -> (f64, f64) {
    let s = v[0] + v[1] + v[2];
    (v[0] / s, v[1] / s)
}

impl Additivity {
    /// The measured white against the additive sum R + G + B − 2K (black plus the three
    /// primaries' contributions, each the mean of its readings), in CIELAB relative to
    /// `white`; None unless all five were measured.
    pub fn check(set: &SortedSamples, white: Xyz) -> Option<Additivity> {
        let (k, measured) = (set.black?, set.white?);
        let [r, g, b] = [set.primaries[0]?, set.primaries[1]?, set.primaries[2]?];
        let sum: [f64; 3] = std::array::from_fn(|i| r[i] + g[i] + b[i] - 2.0 * k[i]);
        Some(Additivity {
            de00: de(measured, sum, white),
            luminance_error_percent: 100.0 * (measured[1] - sum[1]) / measured[1],
        })
    }
}

impl Diagnostics {
    /// Checks the patch set; `white` is the Lab reference (the display white).
    /// `noise`: the measurement noise, when known (see [`repeat_noise`]); `mixed`: how
    /// many mixed patches the set holds (see [`mixed_patches`]); `folded`: of a table model,
    /// its folded tetrahedra and all of them (see `Lut3d::folded_tetrahedra`).
    pub fn compute(
        set: &SortedSamples,
        model: ModelKind,
        white: Xyz,
        residuals: Residuals,
        noise: Option<Noise>,
        mixed: usize,
        folded: Option<(usize, usize)>,
    ) -> Diagnostics {
        let w = white;
        let mut channels = Vec::new();
        let mut additivity = None;
        let mut condition = None;
        let black_share = set.black.map(|b| b[1] / white[1]);
        let primaries: Option<Vec<Xyz>> = set.primaries.iter().copied().collect();
        if let (Some(black), Some(prims)) = (set.black, primaries) {
            let col = |c: usize| -> [f64; 3] { std::array::from_fn(|k| prims[c][k] - black[k]) };
            let m: [[f64; 3]; 3] = std::array::from_fn(|r| std::array::from_fn(|c| col(c)[r]));
            condition = Some(condition_number(&m));
            additivity = Additivity::check(set, w);
            for (c, name) in CHANNEL_NAMES.iter().enumerate() {
                let p = col(c);
                let norm2: f64 = p.iter().map(|v| v * v).sum();
                let mut ch = ChannelDiagnostics {
                    channel: name.to_string(),
                    levels: set.intermediate_levels(c),
                    chromaticity_drift_xy: None,
                    chromaticity_drift_de00: None,
                    drift_at_drive: None,
                    gamma: None,
                    power_law_de00: None,
                };
                let mut ramp = vec![(0.0, 0.0)];
                let (px, py) = xy(p);
                for (d, xyz) in &set.ramps[c] {
                    let corrected: [f64; 3] = std::array::from_fn(|k| xyz[k] - black[k]);
                    let s = (0..3).map(|k| corrected[k] * p[k]).sum::<f64>() / norm2;
                    ramp.push((*d, s));
                    let predicted: [f64; 3] = std::array::from_fn(|k| black[k] + s * p[k]);
                    let e = de(*xyz, predicted, w);
                    if ch.chromaticity_drift_de00.is_none_or(|m| e > m) {
                        ch.chromaticity_drift_de00 = Some(e);
                        ch.drift_at_drive = Some(*d);
                    }
                    if corrected[1] > 0.05 * p[1] {
                        let (x, y) = xy(corrected);
                        let dxy = ((x - px).powi(2) + (y - py).powi(2)).sqrt();
                        ch.chromaticity_drift_xy =
                            Some(ch.chromaticity_drift_xy.map_or(dxy, |m: f64| m.max(dxy)));
                    }
                }
                if ch.levels > 0 {
                    let g = fit_power_gamma(&ramp);
                    ch.gamma = Some(g);
                    let worst = ramp
                        .iter()
                        .map(|&(d, s)| {
                            let a: [f64; 3] = std::array::from_fn(|k| black[k] + s * p[k]);
                            let b: [f64; 3] = std::array::from_fn(|k| black[k] + d.powf(g) * p[k]);
                            de(a, b, w)
                        })
                        .fold(0.0, f64::max);
                    ch.power_law_de00 = Some(worst);
                }
                channels.push(ch);
            }
        }
        // Σ 1/n over the averaged patches each check combines (n readings each): the check's
        // noise variance in units of one reading's.
        let inv = |n: usize| 1.0 / n.max(1) as f64;
        let primary_inv = |c: usize| set.ramp_readings[c].last().map_or(1.0, |&n| inv(n));
        let additivity_weight = inv(set.white_readings) + (0..3).map(primary_inv).sum::<f64>();
        let drift_weights: Vec<f64> = (0..channels.len())
            .map(|c| {
                let at = channels[c].drift_at_drive;
                let n = set.ramps[c]
                    .iter()
                    .zip(&set.ramp_readings[c])
                    .find(|((d, _), _)| Some(*d) == at)
                    .map_or(1, |(_, &n)| n);
                inv(n) + primary_inv(c)
            })
            .collect();
        let mut d = Diagnostics {
            model,
            tolerance_de00: TOLERANCE_DE00,
            channels,
            additivity,
            black_share,
            condition_number: condition,
            residuals,
            noise,
            few_mixtures: (mixed < MIN_MIXED).then_some(mixed),
            folded_tetrahedra: folded.filter(|f| f.0 > 0).map(|(f, t)| [f, t]),
            failures: Vec::new(),
            verdict: String::new(),
        };
        d.judge(additivity_weight, &drift_weights);
        d
    }
}

/// Fewer mixed patches than this (two or more channels on, the white not counted) leave
/// each of five folds one mixture or none: too few to judge mixtures by cross-validation.
pub const MIN_MIXED: usize = 10;

/// Patches with two or more channels on, the white (all channels full) not counted: the
/// mixtures a set measured.
pub fn mixed_patches(patches: &[Sample]) -> usize {
    patches
        .iter()
        .filter(|p| {
            p.rgb.iter().filter(|&&d| d > SAME_DRIVE).count() >= 2
                && !p.rgb.iter().all(|&d| d >= 1.0 - SAME_DRIVE)
        })
        .count()
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("–".into(), |v| format!("{v:.digits$}"))
}

impl std::fmt::Display for Diagnostics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "channel  levels  drift ΔE00  drift Δxy  γ (power law)  power-law ΔE00"
        )?;
        for ch in &self.channels {
            writeln!(
                f,
                "{:<7}  {:>6}  {:>10}  {:>9}  {:>13}  {:>14}",
                ch.channel,
                ch.levels,
                opt(ch.chromaticity_drift_de00, 2),
                opt(ch.chromaticity_drift_xy, 4),
                opt(ch.gamma, 3),
                opt(ch.power_law_de00, 2)
            )?;
        }
        match &self.additivity {
            Some(a) => writeln!(
                f,
                "additivity: white vs black+R+G+B ΔE00 {:.2}, luminance {:+.2} %",
                a.de00, a.luminance_error_percent
            )?,
            None => writeln!(f, "additivity: not measured")?,
        }
        if let Some(n) = &self.noise {
            writeln!(
                f,
                "measurement noise: ΔE00 {:.3} (1σ of one reading, {})",
                n.de00, n.source
            )?;
        }
        writeln!(
            f,
            "black level: {} % of white; condition number of M: {}",
            opt(self.black_share.map(|b| 100.0 * b), 3),
            opt(self.condition_number, 2)
        )?;
        writeln!(
            f,
            "fit ({}): mean ΔE00 {:.3}, p95 {:.3}, max {:.3} at rgb {:.3},{:.3},{:.3}; rms XYZ {:.4} cd/m²",
            self.model,
            self.residuals.mean_de00,
            self.residuals.p95_de00,
            self.residuals.max_de00,
            self.residuals.worst_rgb[0],
            self.residuals.worst_rgb[1],
            self.residuals.worst_rgb[2],
            self.residuals.rms_xyz
        )?;
        write!(f, "verdict: {}", self.verdict)
    }
}

/// The `q` quantile of ascending, non-empty `sorted`, linear between order statistics (the
/// one definition of p95 used in fits, verifications and the budget study).
pub fn percentile(sorted: &[f64], q: f64) -> f64 {
    let rank = q * (sorted.len() - 1) as f64;
    let lo = rank.floor() as usize;
    let hi = rank.ceil() as usize;
    sorted[lo] + (sorted[hi] - sorted[lo]) * (rank - lo as f64)
}
