//! Statistics of a comparison with uncertainty: per patch the colour differences, their
//! 95 % intervals and what can be said about the JND; over the patches the mean and max.
//!
//! "Below the JND" is said of a patch only where its ΔE*ab interval's upper end is below
//! 2.3, "above" only where the lower end is above it; otherwise it is undecided.
//!
//! **Which interval.** A patch's intervals come from the propagation
//! ([`super::propagate`]): Student's t with each side's degrees of freedom, so a side read
//! by the box's `width` rule, whose row states the repeatability pooled across the spots
//! and its degrees of freedom (`dof`), gets t with the pooled ν. That rule's count is fixed
//! by the level of the spot's first two readings and the spots read before it, not by the
//! spot's mean, so the fixed-count interval holds at its count
//! ([`super::sequential`]). A side whose repeats a `verdict` rule stopped on the ΔE*ab they
//! showed (its row has `most`, the display's spots) gets instead the repeated interval of
//! [`super::sequential::repeated_interval`] for ΔE*ab, which holds at whatever count the
//! rule stopped: the JND verdict follows it. The ΔE00 interval and the summaries over
//! patches stay the propagation's, with that side's pooled figure and its degrees of
//! freedom.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::color::{delta_e2000, delta_e76, Xyz, COLORCHECKER_NAMES};

use super::covariance::{self, Cov3};
use super::error::ValidationError;
use super::montecarlo::{summary_interval, Metric, PatchDraws, Statistic};
use super::propagate::{propagate, Interval, Propagated, Propagation, Uncertain};
use super::readings::{PatchReading, ReadingSet, UncertaintySource};
use super::sequential::{repeated_interval, to_lab_covariance, Reference, Sequenced};
pub use super::uncertain::{JndVerdict, JND_DE76};

/// One side's reading of a patch as the assessment keeps it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Side {
    pub xyz: Xyz,
    /// Standard uncertainty of the mean in X, Y and Z (the square roots of `cov_xyz`'s
    /// diagonal).
    pub u_xyz: [f64; 3],
    /// The mean's full covariance in X, Y and Z.
    #[serde(default)]
    pub cov_xyz: Cov3,
    /// Its degrees of freedom where estimated from repeats (k − 1); None where known.
    #[serde(default)]
    pub dof: Option<usize>,
    pub u_lab: f64,
    pub n: usize,
    pub uncertainty: UncertaintySource,
    pub lab: [f64; 3],
}

/// One patch assessed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchAssessment {
    pub patch: usize,
    pub name: String,
    pub reference: Side,
    pub test: Side,
    pub de76: f64,
    pub de00: f64,
    pub de76_interval: Interval,
    pub de00_interval: Interval,
    pub jnd: JndVerdict,
    /// Either input marks the colour as outside the display's gamut.
    pub out_of_gamut: bool,
}

/// How many patches fall on each side of the JND.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct JndCount {
    pub below: usize,
    pub above: usize,
    pub undecided: usize,
}

/// A statistic over the patches with its interval (Monte Carlo only; bias-aware, so it
/// holds the value).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stat {
    pub value: f64,
    pub interval: Option<Interval>,
}

/// A comparison of two sets of readings with uncertainty.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Assessment {
    /// What the reference readings are ("box") and what is tested ("display").
    pub reference: String,
    pub test: String,
    /// CIELAB's reference white.
    pub white: Xyz,
    pub propagation: String,
    pub patches: Vec<PatchAssessment>,
    pub mean_de76: Stat,
    pub max_de76: Stat,
    pub mean_de00: Stat,
    pub max_de00: Stat,
    /// Patches whose ΔE*ab point estimate is below the JND (no uncertainty considered), as
    /// the paper counts them: shown only named as such.
    pub below_jnd_point: usize,
    /// The verdicts at 95 % confidence: the count every summary leads with.
    pub jnd: JndCount,
}

/// Options of an assessment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AssessOptions {
    pub propagation: Propagation,
    /// A standard uncertainty in ΔE*ab the test side's readings carry beyond their own
    /// (e.g. a display model's verification error), spread evenly over L*, a*, b*.
    pub model_term_de: f64,
}

impl Default for AssessOptions {
    fn default() -> Self {
        AssessOptions {
            propagation: Propagation::default(),
            model_term_de: 0.0,
        }
    }
}

fn side(p: &PatchReading, white: Xyz, extra_lab: f64) -> (Side, Uncertain) {
    let u_lab = (p.u_lab.powi(2) + extra_lab.powi(2)).sqrt();
    (
        Side {
            xyz: p.xyz,
            u_xyz: p.u_xyz,
            cov_xyz: covariance::of_factors(&p.u_factors),
            dof: p.dof,
            u_lab,
            n: p.n,
            uncertainty: p.source,
            lab: p.xyz.to_lab(white).to_array(),
        },
        Uncertain {
            xyz: p.xyz,
            factors: p.u_factors.clone(),
            dof: p.dof,
            u_lab,
        },
    )
}

/// Assesses `test` against `reference` on the patches both have, in CIELAB relative to
/// `white`.
pub fn assess(
    reference_name: &str,
    reference: &ReadingSet,
    test_name: &str,
    test: &ReadingSet,
    white: Xyz,
    opts: &AssessOptions,
) -> Result<Assessment, ValidationError> {
    check_white(white)?;
    let common: Vec<usize> = reference
        .patches
        .keys()
        .filter(|k| test.patches.contains_key(k))
        .copied()
        .collect();
    if common.is_empty() {
        return Err(ValidationError::NoCommonPatches {
            reference: reference.file.clone(),
            test: test.file.clone(),
        });
    }
    // Spread over three axes so the expected squared length of the term is its ΔE².
    let model_lab = opts.model_term_de / 3f64.sqrt();
    let pairs = common
        .iter()
        .map(|&k| PatchPair {
            patch: k,
            reference: side(&reference.patches[&k], white, 0.0),
            test: side(&test.patches[&k], white, model_lab),
            out_of_gamut: reference.patches[&k].out_of_gamut || test.patches[&k].out_of_gamut,
            sequential: sequenced(&reference.patches[&k], &test.patches[&k], white, model_lab),
        })
        .collect();
    Ok(compare_pairs(
        reference_name,
        test_name,
        pairs,
        white,
        opts.propagation,
    ))
}

/// Where one side's repeats were stopped by a verdict rule (its `most`), that side and the
/// other as the repeated interval takes them; `extra_lab` is the test side's own CIELAB
/// term (a display model's), fixed whatever the count, so it goes with the other side's.
fn sequenced(
    reference: &PatchReading,
    test: &PatchReading,
    white: Xyz,
    extra_lab: f64,
) -> Option<(Reference, Sequenced)> {
    let (other, read, read_extra, other_extra) = match (reference.most, test.most) {
        (_, Some(_)) => (reference, test, extra_lab, 0.0),
        (Some(_), None) => (test, reference, 0.0, extra_lab),
        (None, None) => return None,
    };
    let lab_var =
        other.u_lab.powi(2) + other_extra.powi(2) + read.u_lab.powi(2) + read_extra.powi(2);
    Some((
        Reference {
            xyz: other.xyz,
            cov_mean: covariance::of_factors(&other.u_factors),
            dof: other.dof.map(|d| d as f64),
            lab_var,
        },
        Sequenced {
            mean: read.xyz,
            n: read.n,
            reading_lab: to_lab_covariance(&read.reading_covariance(), read.xyz, white),
            dof: read.dof.map(|d| d as f64),
            most: read.most?,
        },
    ))
}

/// CIELAB needs a white with positive X, Y and Z.
pub(super) fn check_white(white: Xyz) -> Result<(), ValidationError> {
    if white.x > 0.0 && white.y > 0.0 && white.z > 0.0 {
        Ok(())
    } else {
        Err(ValidationError::BadWhite {
            white: white.to_array(),
        })
    }
}

/// One patch's two readings as [`compare_pairs`] takes them.
pub(super) struct PatchPair {
    pub patch: usize,
    pub reference: (Side, Uncertain),
    pub test: (Side, Uncertain),
    pub out_of_gamut: bool,
    /// Where a verdict rule stopped one side's repeats: the repeated interval's sides.
    pub sequential: Option<(Reference, Sequenced)>,
}

/// A side known exactly (no uncertainty of its own): what [`super::compare`] compares.
pub(super) fn exact_side(xyz: Xyz, white: Xyz) -> (Side, Uncertain) {
    (
        Side {
            xyz,
            u_xyz: [0.0; 3],
            cov_xyz: covariance::ZERO,
            dof: None,
            u_lab: 0.0,
            n: 1,
            uncertainty: UncertaintySource::Unknown,
            lab: xyz.to_lab(white).to_array(),
        },
        Uncertain {
            xyz,
            factors: Vec::new(),
            dof: None,
            u_lab: 0.0,
        },
    )
}

/// The ColorChecker name of 1-based patch `k`, or "patch k" beyond the chart.
fn patch_name(k: usize) -> String {
    k.checked_sub(1)
        .and_then(|i| COLORCHECKER_NAMES.get(i))
        .map(|s| s.to_string())
        .unwrap_or_else(|| format!("patch {k}"))
}

/// The one comparison: each pair in CIELAB relative to `white` (checked by the caller),
/// its colour differences with their intervals and verdicts, and the summaries over the
/// pairs.
pub(super) fn compare_pairs(
    reference_name: &str,
    test_name: &str,
    pairs: Vec<PatchPair>,
    white: Xyz,
    propagation: Propagation,
) -> Assessment {
    // Patches are independent: their intervals are found in parallel.
    let (patches, propagated): (Vec<PatchAssessment>, Vec<Propagated>) = pairs
        .into_par_iter()
        .map(|pair| {
            let (r, ru) = pair.reference;
            let (t, tu) = pair.test;
            let k = pair.patch;
            let mut p = propagate(&ru, &tu, white, propagation, k);
            let repeated = pair
                .sequential
                .as_ref()
                .and_then(|(r, t)| repeated_interval(r, t, white).map(|(_, interval, _)| interval));
            if let Some(interval) = repeated {
                p.de76 = interval;
            }
            let (rl, tl) = (p.reference_lab, p.test_lab);
            let a = PatchAssessment {
                patch: k,
                name: patch_name(k),
                de76: delta_e76(rl, tl),
                de00: delta_e2000(rl, tl),
                de76_interval: p.de76,
                de00_interval: p.de00,
                jnd: JndVerdict::of(p.de76),
                out_of_gamut: pair.out_of_gamut,
                reference: r,
                test: t,
            };
            (a, p)
        })
        .unzip();
    let mut jnd = JndCount::default();
    for p in &patches {
        match p.jnd {
            JndVerdict::Below => jnd.below += 1,
            JndVerdict::Above => jnd.above += 1,
            JndVerdict::Undecided => jnd.undecided += 1,
        }
    }
    let seed = match propagation {
        Propagation::MonteCarlo { seed, .. } => seed,
        Propagation::Linear => 0,
    };
    let stat = |(metric, summary): (Metric, Statistic)| {
        let values: Vec<f64> = patches
            .iter()
            .map(|p| match metric {
                Metric::De76 => p.de76,
                Metric::De00 => p.de00,
            })
            .collect();
        let draws: Vec<PatchDraws<'_>> = propagated
            .iter()
            .map(|p| PatchDraws {
                reference_lab: p.reference_lab,
                test_lab: p.test_lab,
                noise: p.noise.as_ref(),
                interval: Some(match metric {
                    Metric::De76 => p.de76,
                    Metric::De00 => p.de00,
                }),
            })
            .collect();
        Stat {
            value: summary.of(&values),
            interval: summary_interval(&draws, metric, summary, seed),
        }
    };
    let stats: Vec<Stat> = [
        (Metric::De76, Statistic::Mean),
        (Metric::De76, Statistic::Max),
        (Metric::De00, Statistic::Mean),
        (Metric::De00, Statistic::Max),
    ]
    .into_par_iter()
    .map(stat)
    .collect();
    let [mean_de76, max_de76, mean_de00, max_de00] = [stats[0], stats[1], stats[2], stats[3]];
    Assessment {
        reference: reference_name.into(),
        test: test_name.into(),
        white,
        propagation: propagation.describe(),
        below_jnd_point: patches.iter().filter(|p| p.de76 < JND_DE76).count(),
        patches,
        mean_de76,
        max_de76,
        mean_de00,
        max_de00,
        jnd,
    }
}

impl Stat {
    /// "0.55 [0.50, 0.62]", or the value alone without an interval.
    pub fn show(&self) -> String {
        match self.interval {
            Some(i) => format!("{:.2} [{:.2}, {:.2}]", self.value, i.lo, i.hi),
            None => format!("{:.2}", self.value),
        }
    }
}

impl Assessment {
    /// The one-line summary a user reads first: the verdicts at 95 % confidence, the
    /// point-estimate count named as such, the summaries with their intervals.
    pub fn summary(&self) -> String {
        format!(
            "{} vs {}: {} of {} patches below the JND (ΔE*ab {JND_DE76}) at 95 % confidence, {} above, {} undecided ({} below by point estimate); ΔE*ab mean {} max {}; ΔE00 mean {} max {}",
            self.test,
            self.reference,
            self.jnd.below,
            self.patches.len(),
            self.jnd.above,
            self.jnd.undecided,
            self.below_jnd_point,
            self.mean_de76.show(),
            self.max_de76.show(),
            self.mean_de00.show(),
            self.max_de00.show()
        )
    }

    /// The patches that are above the JND, or may be.
    pub fn failing(&self) -> impl Iterator<Item = &PatchAssessment> {
        self.patches.iter().filter(|p| p.jnd != JndVerdict::Below)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::validation::readings::parse_readings;
    use std::path::Path;

    fn set(text: &str) -> ReadingSet {
        parse_readings(text, Path::new("t.csv")).unwrap()
    }

    #[test]
    fn verdicts_follow_the_interval_not_the_point() {
        let white = Xyz::new(95.047, 100.0, 108.883);
        // Greys at L* 50 (Y 18.418652), 51.5 (19.703227) and 60 (28.123334);
        // by hand from L* = 116 (Y/Yn)^(1/3) − 16.
        let g = |k: usize, y: f64| format!("{k},{},{y},{}\n", 0.950_47 * y, 1.088_83 * y);
        let reference = set(&format!(
            "patch,X,Y,Z\n{}{}{}",
            g(1, 18.418_652),
            g(2, 18.418_652),
            g(3, 18.418_652)
        ));
        // Patch 1: ΔE 1.5 known exactly → below. Patch 2: ΔE 10 → above. Patch 3: repeats
        // 16.5 and 23.0 (mean 19.75, ΔE 1.6; the scatter along the grey axis is ±3.25 in Y,
        // ±3.8 in L*): too scattered to decide.
        let test = set(&format!(
            "patch,X,Y,Z\n{}{}{}{}",
            g(1, 19.703_227),
            g(2, 28.123_334),
            g(3, 16.5),
            g(3, 23.0)
        ));
        let a = assess(
            "box",
            &reference,
            "display",
            &test,
            white,
            &AssessOptions::default(),
        )
        .unwrap();
        assert!((a.patches[0].de76 - 1.5).abs() < 1e-4);
        assert_eq!(
            a.patches.iter().map(|p| p.jnd).collect::<Vec<_>>(),
            [JndVerdict::Below, JndVerdict::Above, JndVerdict::Undecided]
        );
        assert_eq!(a.below_jnd_point, 2);
        assert_eq!(
            a.jnd,
            JndCount {
                below: 1,
                above: 1,
                undecided: 1
            }
        );
        // The mean over the draws brackets the mean of the values.
        let m = a.mean_de76;
        let i = m.interval.unwrap();
        assert!(i.lo <= m.value + 0.5 && m.value - 0.5 <= i.hi, "{m:?}");
    }

    /// A display patch a verdict rule stopped (`most`) takes the repeated interval: with one
    /// look (most 2) it is ΔE ± z₀.₉₇₅·σ along the difference, by hand for greys that differ
    /// in L* alone (reference exact, the test's noise in Y only: σ_L = dL*/dY·sd_Y/√n, with
    /// dL*/dY = (116/3)·(Y/Yₙ)^(−2/3)/Yₙ); more looks widen it (Pocock's constant for 2 to 5
    /// readings). A pooled figure's degrees of freedom reach the side.
    #[test]
    fn a_patch_a_verdict_rule_stopped_takes_the_repeated_interval() {
        let white = Xyz::new(95.047, 100.0, 108.883);
        let g = |k: usize, y: f64| format!("{k},{},{y},{}", 0.950_47 * y, 1.088_83 * y);
        let reference = set(&format!("patch,X,Y,Z\n{}\n", g(1, 18.418_652)));
        let test = |tail: &str| {
            set(&format!(
                "patch,X,Y,Z,sd_X,sd_Y,sd_Z,n,cov_XY,cov_XZ,cov_YZ,u_lab,dof,most\n{},0,0.5,0,2,0,0,0,0,{tail}\n",
                g(1, 19.703_227)
            ))
        };
        let run = |t: &ReadingSet| {
            assess(
                "box",
                &reference,
                "display",
                t,
                white,
                &AssessOptions::default(),
            )
            .unwrap()
            .patches[0]
                .clone()
        };
        let one_look = run(&test(",2"));
        let y: f64 = 19.703_227;
        let sigma = 116.0 / 3.0 * (y / 100.0).powf(-2.0 / 3.0) / 100.0 * 0.5 / 2f64.sqrt();
        let half = 1.959_964 * sigma;
        assert!((one_look.de76 - 1.5).abs() < 1e-4, "{}", one_look.de76);
        let i = one_look.de76_interval;
        assert!(
            (i.lo - (one_look.de76 - half)).abs() < 1e-5,
            "{i:?} against ±{half}"
        );
        assert!(
            (i.hi - (one_look.de76 + half)).abs() < 1e-5,
            "{i:?} against ±{half}"
        );
        let five = run(&test(",5")).de76_interval;
        assert!(
            five.hi - five.lo > 1.1 * (i.hi - i.lo),
            "{five:?} against {i:?}"
        );
        // A pooled figure's 72 degrees of freedom, not the row's own 1.
        let pooled = run(&test("72,"));
        assert_eq!(pooled.test.dof, Some(72));
        let own = run(&set(&format!(
            "patch,X,Y,Z,sd_X,sd_Y,sd_Z,n\n{},0,0.5,0,2\n",
            g(1, 19.703_227)
        )));
        assert_eq!(own.test.dof, Some(1));
        // Student's t with 72 degrees of freedom, not 1: a lower upper end (the lower ends
        // are both 0, the noise across the difference being large).
        assert!(
            pooled.de76_interval.hi < own.de76_interval.hi,
            "{pooled:?} {own:?}"
        );
    }

    #[test]
    fn disjoint_patch_sets_are_an_error() {
        let white = Xyz::new(95.0, 100.0, 108.0);
        let r = set("patch,X,Y,Z\n1,1,1,1\n");
        let t = set("patch,X,Y,Z\n2,1,1,1\n");
        let e = assess("box", &r, "display", &t, white, &AssessOptions::default()).unwrap_err();
        assert!(e.to_string().contains("no patch in common"), "{e}");
    }
}
