//! Repeats that stop when they are decided: how many times a target is read, from the
//! readings taken so far, with 95 % intervals that stay valid although the count depends
//! on the data.
//!
//! Three rules ([`RepeatRule`]): a fixed count (the paper's 5); until the target's own
//! interval reaches a stated width (`width`, what the box's spots can use: their verdict
//! needs the display's reading, measured later); until the interval of ΔE*ab against a
//! reference already measured lies beyond the JND (CIELAB ΔE*ab 2.3) by a margin
//! (`verdict`, for the display's spots, measured after the box). Every rule takes at least
//! two readings and at most a stated count.
//!
//! **Noise.** One reading's XYZ covariance is the instrument's stated repeatability at the
//! target's level ([`repeatability::covariance`]) times a factor s²: 1 (the stated figure,
//! known), or pooled across the targets the instrument read in the same mode, with its
//! degrees of freedom ([`pool`]). CIELAB covariances are carried to first order through the
//! Jacobian of XYZ → CIELAB at the mean (central differences).
//!
//! **Width.** With one reading's CIELAB covariance C and n readings, the 95 % region of
//! the target's CIELAB is the ellipsoid n·(L − L̂)ᵀ C⁻¹ (L − L̂) ≤ q, q = χ²₃(0.95) = 7.815
//! for a known figure and q = 3·F₀.₉₅(3, ν) for one estimated with ν degrees of freedom
//! (Hotelling). It lies inside the ball of radius h = √(q·λ_max(C)/n), the half-width the
//! rule compares with its fraction of the JND. The rule evaluates C at the mean of the
//! first two readings and s² from the targets read before: the count is then fixed by
//! readings whose errors are independent of the mean's error after them (for normal
//! readings, the mean of n is independent of every earlier reading's deviation from it;
//! only the first two readings' mean, through the level, is shared, a second-order effect
//! on C), so the interval at the stopping count is the fixed-count one. Stopping on the
//! target's own scatter instead (its sample covariance) stops when the scatter happens to
//! be small; with Hotelling's region the loss is small for a yellow read up to 30 times
//! (94.5 % in the tests), but the count then depends on the very figure the interval uses.
//!
//! **Verdict.** The test side's mean t̂ₙ after n readings against the reference r̂ (its
//! covariance of the mean C_r fixed, measured before): ΔÊₙ = |t̂ₙ − r̂| in CIELAB, to first
//! order ΔE + u·(eₜ,ₙ − e_r) along the unit difference u, with variance
//! vₙ = a + b/n (a = uᵀC_r u, b = uᵀCₜu for one test reading). Dₙ = ΔÊₙ − ΔE has
//! Cov(Dₘ, Dₙ) = vₙ for m < n: the joint law of a Brownian motion observed at information
//! times Iₙ = 1/vₙ (the canonical form of group sequential tests; Jennison and Turnbull
//! 2000, §3.1). A rule that looks at every n from 2 to K and stops when it likes is covered
//! by repeated confidence intervals ΔÊₙ ± c·√vₙ with the constant c for which the motion
//! leaves ±c·√Iₙ at some look with probability 0.05 (Pocock's boundary for these looks,
//! computed by the Armitage–McPherson–Rowe recursion: [`boundary`]): all K intervals hold
//! ΔE together with probability 0.95, so the one at whichever look the rule stops holds it
//! with at least 0.95 — whatever the rule, including this one's margin. The first-order
//! form holds while the noise is small against ΔE: at the meter's own noise on a yellow
//! (ΔE/σ of one reading ≈ 8 at the JND) the coverage at the JND is 95.0 %, at twice it
//! 94.3 %, at three times 92.8 % (ΔE being a length, its law skews as σ grows); beyond
//! that the Monte Carlo inversion of [`super::montecarlo`] would be needed at each look. At a true ΔE on
//! the JND the rule stops early only when its interval misses the truth, so the coverage
//! there is the boundary's 95 % exactly; far from the JND it is above 95 % (the price of
//! looking). c is computed for a/b rounded down to a step of 2^¼ (see [`verdict`]), a
//! larger constant where the looks are more alike. With an estimated figure (ν degrees of
//! freedom, Welch–Satterthwaite over both sides) the nominal level of c is carried to
//! Student's t.
//!
//! **In the validation.** The readings files carry what a rule used. The box's spots read
//! by `width` (or by a `fixed` count the plan states as its rule) state one reading's
//! covariance as the pooled figure (s² on the stated shape, pooled over every spot's kept
//! readings) with its ν (`dof` column): the width rule's count is not chosen on the spot's
//! mean, so the validation's intervals are the fixed-count ones,
//! Student's t with the pooled ν (Welch–Satterthwaite over both sides,
//! [`super::montecarlo`]). The display's spots read by `verdict` state the same and `most`:
//! their count was chosen on the ΔE*ab the readings showed, so the validation's ΔE*ab
//! interval for them is [`repeated_interval`], the repeated interval at the count reached
//! (valid whatever the stopping, for any comparison of that side: box or simulation), and
//! the JND verdict follows it. The ΔE00 intervals and the summaries over patches stay the
//! fixed-count ones with the pooled ν.
//!
//! **What the width of display vs box costs.** The paper's plan (box 5, display 3, each
//! patch its own scatter) gives ΔE*ab a half-width of t(ν_WS)·√(s_b²/5 + s_d²/3), ν_WS
//! ≈ 4 by Welch–Satterthwaite (t ≈ 2.7): few degrees of freedom, but also a sample
//! scatter that is often below σ. Pooled sides give 1.98·σ·√(1/n_b + 1/n_d) with ν ≈ 70–150,
//! and a verdict rule with more than one look its boundary's constant instead of 1.98
//! (2.12 for looks at 2 and 3 readings with a box read twice). Per patch, two pooled
//! readings a side match the paper's plan on average; its median over 24 patches varies
//! by ±15 % from session to session with the paper's own scatter (docs/benchmarks.md).
//!
//! Every choice follows from the readings given and the rule, so a resumed session and a
//! re-run take the same count.

pub mod boundary;
pub mod distributions;
pub mod pool;

#[cfg(test)]
mod coverage;
#[cfg(test)]
mod coverage_pairs;

use std::collections::BTreeMap;
use std::sync::Mutex;

use serde::{Deserialize, Serialize};

pub use pool::Pool;

use super::covariance::{self, Cov3};
use super::repeatability::{self, Repeatability};
use super::uncertain::Interval;
use super::uncertain::{JndVerdict, JND_DE76};
use crate::color::Xyz;

/// The least number of readings of a target: one reading has no scatter of its own.
pub const MIN_READINGS: usize = 2;
/// The confidence of every interval here.
pub const CONFIDENCE: f64 = 0.95;
/// The most looks a rule may take at a target: the box plan's most readings of one thing.
pub const MOST_LOOKS: usize = 100;

/// How many times a target is read.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "rule", rename_all = "kebab-case", deny_unknown_fields)]
pub enum RepeatRule {
    /// Always `repeats` readings.
    Fixed { repeats: usize },
    /// Until the 95 % half-width of the target's CIELAB is at most `half_width_jnd` times
    /// the JND; at most `most` readings.
    Width { half_width_jnd: f64, most: usize },
    /// Until the 95 % interval of ΔE*ab against the reference lies `margin` ΔE*ab or more
    /// beyond the JND; at most `most` readings.
    Verdict { margin: f64, most: usize },
}

impl RepeatRule {
    /// The most readings the rule takes of one target.
    pub fn most(&self) -> usize {
        match *self {
            RepeatRule::Fixed { repeats } => repeats,
            RepeatRule::Width { most, .. } | RepeatRule::Verdict { most, .. } => most,
        }
    }

    /// What is wrong with the rule, if anything, for a plan that allows `max` readings.
    pub fn check(&self, max: usize) -> Result<(), String> {
        let most = self.most();
        let least = match self {
            RepeatRule::Fixed { .. } => 1,
            _ => MIN_READINGS,
        };
        if !(least..=max).contains(&most) {
            return Err(format!(
                "the most readings must be between {least} and {max}, got {most}"
            ));
        }
        match *self {
            RepeatRule::Width { half_width_jnd, .. }
                if !(half_width_jnd.is_finite() && half_width_jnd > 0.0) =>
            {
                Err(format!(
                    "half_width_jnd must be a positive fraction of the JND, got {half_width_jnd}"
                ))
            }
            RepeatRule::Verdict { margin, .. }
                if !(margin.is_finite() && (0.0..JND_DE76).contains(&margin)) =>
            {
                Err(format!(
                    "margin must be from 0 to below the JND ({JND_DE76}) ΔE*ab, got {margin}"
                ))
            }
            _ => Ok(()),
        }
    }

    /// The rule in words: `5 readings`, `2 to 10 readings, until the 95 % half-width is
    /// 0.1 JND`.
    pub fn describe(&self) -> String {
        match *self {
            RepeatRule::Fixed { repeats } => format!("{repeats} readings"),
            RepeatRule::Width {
                half_width_jnd,
                most,
            } => format!(
                "{MIN_READINGS} to {most} readings, until the 95 % half-width in CIELAB is at most {half_width_jnd} × the JND ({:.3} ΔE*ab)",
                half_width_jnd * JND_DE76
            ),
            RepeatRule::Verdict { margin, most } => format!(
                "{MIN_READINGS} to {most} readings, until the 95 % interval of ΔE*ab lies {margin} or more beyond the JND ({JND_DE76})"
            ),
        }
    }
}

/// One reading's noise: the stated repeatability times `scale2`, known (`dof` None) or
/// estimated with `dof` degrees of freedom.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RepeatNoise {
    pub stated: Repeatability,
    pub scale2: f64,
    pub dof: Option<f64>,
}

impl RepeatNoise {
    /// The stated figure, taken as known.
    pub fn stated(stated: Repeatability) -> RepeatNoise {
        RepeatNoise {
            stated,
            scale2: 1.0,
            dof: None,
        }
    }

    /// One reading's XYZ covariance at `xyz`; None without a chromaticity.
    pub fn covariance(&self, xyz: Xyz) -> Option<Cov3> {
        repeatability::covariance(&self.stated, xyz).map(|c| covariance::scaled(&c, self.scale2))
    }

    /// One reading's CIELAB covariance at `xyz` relative to `white`.
    pub fn lab_covariance(&self, xyz: Xyz, white: Xyz) -> Option<Cov3> {
        Some(to_lab_covariance(&self.covariance(xyz)?, xyz, white))
    }
}

/// A covariance of XYZ at `xyz` carried to CIELAB to first order: J C Jᵀ, J by central
/// differences.
pub fn to_lab_covariance(c: &Cov3, xyz: Xyz, white: Xyz) -> Cov3 {
    let mut j = [[0.0; 3]; 3];
    for k in 0..3 {
        let h = 1e-6 * xyz[k].abs().max(1e-6);
        let (mut up, mut down) = (xyz, xyz);
        up[k] += h;
        down[k] -= h;
        let (a, b) = (up.to_lab(white), down.to_lab(white));
        let d = [a.l - b.l, a.a - b.a, a.b - b.b];
        for (i, row) in j.iter_mut().enumerate() {
            row[k] = d[i] / (2.0 * h);
        }
    }
    let mut out = covariance::ZERO;
    for (a, row) in out.iter_mut().enumerate() {
        for (b, v) in row.iter_mut().enumerate() {
            *v = (0..3)
                .map(|k| (0..3).map(|l| j[a][k] * c[k][l] * j[b][l]).sum::<f64>())
                .sum();
        }
    }
    out
}

/// The 95 % quantile of n·(L − L̂)ᵀC⁻¹(L − L̂): χ²₃ for a known figure, 3·F(3, ν) for one
/// estimated with ν degrees of freedom.
pub fn region_quantile(dof: Option<f64>) -> f64 {
    match dof {
        None => distributions::chi2_quantile(CONFIDENCE, 3.0),
        Some(nu) => 3.0 * distributions::f_quantile(CONFIDENCE, 3.0, nu),
    }
}

/// The 95 % half-width in CIELAB of the mean of `n` readings at `level` (the radius of
/// the ball holding the region); None without a chromaticity.
pub fn half_width(level: Xyz, noise: &RepeatNoise, white: Xyz, n: usize) -> Option<f64> {
    let c = noise.lab_covariance(level, white)?;
    let (values, _) = covariance::eigen_decomposition(&c);
    let largest = values.iter().copied().fold(0.0, f64::max);
    Some((region_quantile(noise.dof) * largest / n.max(1) as f64).sqrt())
}

/// Whether the `width` rule has read a target enough: at least [`MIN_READINGS`], then
/// until the half-width at the level of the first two readings is at most
/// `half_width_jnd`·JND, or `most` readings. `noise` is the figure known before the target
/// (stated, or pooled from the targets read before it).
pub fn width_decided(
    half_width_jnd: f64,
    most: usize,
    readings: &[Xyz],
    noise: &RepeatNoise,
    white: Xyz,
) -> bool {
    let n = readings.len();
    if n >= most {
        return true;
    }
    if n < MIN_READINGS {
        return false;
    }
    let (level, _) = covariance::sample(&readings[..MIN_READINGS]);
    let Some(h) = half_width(level, noise, white, n) else {
        return false;
    };
    h <= half_width_jnd * JND_DE76
}

/// The reference side of a verdict: its mean XYZ, the covariance of that mean and the
/// degrees of freedom of that covariance (None: known), and a variance per CIELAB axis it
/// carries beyond it (a renderer's `u_lab`², 0 for a measurement).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reference {
    pub xyz: Xyz,
    pub cov_mean: Cov3,
    pub dof: Option<f64>,
    pub lab_var: f64,
}

/// The verdict rule's look at a target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VerdictLook {
    pub de76: f64,
    /// The repeated 95 % interval of ΔE*ab at this look.
    pub interval: Interval,
    /// The boundary's constant (in units of the standard deviation).
    pub constant: f64,
    pub verdict: JndVerdict,
    /// Whether the rule reads no more of the target.
    pub decided: bool,
}

/// How finely a/b is rounded down before the boundary is computed: 2^¼.
const RATIO_STEPS_PER_OCTAVE: f64 = 4.0;
/// Below this a/b counts as 0 (the reference exact).
const RATIO_FLOOR: f64 = 1.0 / 4096.0;

/// Boundaries computed so far, by (most, rounded log₂ a/b or None for 0).
static BOUNDARIES: Mutex<BTreeMap<(usize, Option<i64>), f64>> = Mutex::new(BTreeMap::new());

/// The constant c of the repeated intervals for looks at 2, …, `most` readings, with the
/// reference's variance along the difference `ratio` times one test reading's. The ratio
/// is rounded down (a smaller ratio makes the looks less alike, and the constant larger).
pub fn verdict_constant(most: usize, ratio: f64) -> f64 {
    let key =
        (ratio >= RATIO_FLOOR).then(|| (ratio.log2() * RATIO_STEPS_PER_OCTAVE).floor() as i64);
    if let Some(c) = BOUNDARIES
        .lock()
        .ok()
        .and_then(|m| m.get(&(most, key)).copied())
    {
        return c;
    }
    let rounded = key.map_or(0.0, |k| (k as f64 / RATIO_STEPS_PER_OCTAVE).exp2());
    let info: Vec<f64> = (MIN_READINGS..=most.max(MIN_READINGS))
        .map(|n| 1.0 / (rounded + 1.0 / n as f64))
        .collect();
    let c = boundary::constant(&info, 1.0 - CONFIDENCE);
    if let Ok(mut m) = BOUNDARIES.lock() {
        m.insert((most, key), c);
    }
    c
}

/// The verdict rule's look after `readings` of the test side against `reference`, both in
/// CIELAB relative to `white`; None before [`MIN_READINGS`] or without a chromaticity.
pub fn verdict(
    margin: f64,
    most: usize,
    reference: &Reference,
    readings: &[Xyz],
    noise: &RepeatNoise,
    white: Xyz,
) -> Option<VerdictLook> {
    let n = readings.len();
    if n < MIN_READINGS {
        return None;
    }
    let (mean, _) = covariance::sample(readings);
    let test = Sequenced {
        mean,
        n,
        reading_lab: noise.lab_covariance(mean, white)?,
        dof: noise.dof,
        most,
    };
    let (de76, interval, constant) = repeated_interval(reference, &test, white)?;
    let verdict = JndVerdict::of(interval);
    let decided = n >= most || interval.hi <= JND_DE76 - margin || interval.lo >= JND_DE76 + margin;
    Some(VerdictLook {
        de76,
        interval,
        constant,
        verdict,
        decided,
    })
}

/// The side a verdict rule read: the mean of its `n` readings, one reading's CIELAB
/// covariance (with its degrees of freedom, None: known) and the most readings the rule
/// could have taken.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sequenced {
    pub mean: Xyz,
    pub n: usize,
    pub reading_lab: Cov3,
    pub dof: Option<f64>,
    pub most: usize,
}

/// ΔE*ab between `reference` and the sequenced side, the repeated 95 % interval at its
/// count (see the module's docs: it holds whatever the rule that chose the count), and the
/// boundary's constant. None where the test side has no noise along the difference.
pub fn repeated_interval(
    reference: &Reference,
    test: &Sequenced,
    white: Xyz,
) -> Option<(f64, Interval, f64)> {
    let n = test.n.max(1);
    let (r, t) = (reference.xyz.to_lab(white), test.mean.to_lab(white));
    let d = [t.l - r.l, t.a - r.a, t.b - r.b];
    let de76 = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let mut c_r = to_lab_covariance(&reference.cov_mean, reference.xyz, white);
    for (i, row) in c_r.iter_mut().enumerate() {
        row[i] += reference.lab_var;
    }
    let c_t = test.reading_lab;
    let u = if de76 > 0.0 {
        d.map(|v| v / de76)
    } else {
        // No direction yet: the one the noise is largest along.
        let (values, vectors) = covariance::eigen_decomposition(&covariance::sum(&c_r, &c_t));
        let k = (0..3).fold(0, |best, k| if values[k] > values[best] { k } else { best });
        [0, 1, 2].map(|i| vectors[i][k])
    };
    let along = |c: &Cov3| -> f64 {
        (0..3)
            .map(|i| (0..3).map(|j| u[i] * c[i][j] * u[j]).sum::<f64>())
            .sum::<f64>()
            .max(0.0)
    };
    let (a, b) = (along(&c_r), along(&c_t));
    if b <= 0.0 {
        return None;
    }
    let mut constant = verdict_constant(test.most.clamp(MIN_READINGS, MOST_LOOKS), a / b);
    let v = a + b / n as f64;
    // Welch–Satterthwaite over the two sides, each known (infinite) or estimated.
    let part = |var: f64, dof: Option<f64>| dof.map_or(0.0, |nu| var * var / nu);
    let denominator = part(a, reference.dof) + part(b / n as f64, test.dof);
    if denominator > 0.0 {
        let nu = v * v / denominator;
        let level = distributions::normal_cdf(constant);
        constant = distributions::t_quantile(level, nu);
    }
    let half = constant * v.sqrt();
    let interval = Interval {
        lo: (de76 - half).max(0.0),
        hi: de76 + half,
    };
    Some((de76, interval, constant))
}

#[cfg(test)]
mod tests {
    use super::*;
    use metamer_drivers::MeasureMode;

    #[test]
    fn rules_read_and_check_as_json() {
        let r: RepeatRule =
            serde_json::from_str(r#"{"rule":"width","half_width_jnd":0.1,"most":8}"#).unwrap();
        assert_eq!(
            r,
            RepeatRule::Width {
                half_width_jnd: 0.1,
                most: 8
            }
        );
        r.check(100).unwrap();
        let e = RepeatRule::Width {
            half_width_jnd: 0.0,
            most: 8,
        }
        .check(100)
        .unwrap_err();
        assert!(e.contains("positive fraction"), "{e}");
        let e = RepeatRule::Verdict {
            margin: 0.1,
            most: 1,
        }
        .check(100)
        .unwrap_err();
        assert!(e.contains("between 2 and 100, got 1"), "{e}");
        assert!(serde_json::from_str::<RepeatRule>(r#"{"rule":"width","most":8}"#).is_err());
    }

    /// The width rule's count by hand: a grey at Y = 20 of a white at Y = 100 read by the
    /// CS-100A. Its noise in CIELAB is mostly a*, b* from x, y (σ 0.0005).
    #[test]
    fn the_width_rule_reads_until_the_half_width_is_reached() {
        let white = Xyz::new(95.047, 100.0, 108.883);
        let grey = Xyz::new(0.95047 * 20.0, 20.0, 1.08883 * 20.0);
        let noise = RepeatNoise::stated(repeatability::stated("cs100a", MeasureMode::Emissive));
        let h1 = half_width(grey, &noise, white, 1).unwrap();
        // The half-width of n readings is h1/√n.
        let h4 = half_width(grey, &noise, white, 4).unwrap();
        assert!((h4 - h1 / 2.0).abs() < 1e-12);
        // A target just above h1/√3 needs 3 readings; its first two decide nothing.
        let target = h1 / 3f64.sqrt() * 1.0001 / JND_DE76;
        let readings = [grey; 5];
        assert!(!width_decided(target, 10, &readings[..2], &noise, white));
        assert!(width_decided(target, 10, &readings[..3], &noise, white));
        // Never before two readings, always at the most.
        assert!(!width_decided(100.0, 10, &readings[..1], &noise, white));
        assert!(width_decided(1e-9, 4, &readings[..4], &noise, white));
    }

    /// With no reference noise the looks are those of a plain sequence of readings, and
    /// the constant is Pocock's for the looks at 2, …, 6 readings; more reference noise
    /// makes the looks alike and the constant smaller, towards 1.96.
    #[test]
    fn the_verdict_constant_falls_as_the_reference_dominates() {
        let info: Vec<f64> = (2..=6).map(|n| n as f64).collect();
        let plain = boundary::constant(&info, 0.05);
        assert!((verdict_constant(6, 0.0) - plain).abs() < 1e-9);
        let mut last = plain;
        for ratio in [0.1, 1.0, 10.0] {
            let c = verdict_constant(6, ratio);
            assert!(c < last && c > 1.96, "{ratio}: {c} after {last}");
            last = c;
        }
    }
}
