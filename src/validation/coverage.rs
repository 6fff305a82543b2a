//! The intervals' coverage, measured: synthetic readings drawn about a known truth with a
//! known covariance, 2000 trials each; a patch's 95 % interval must hold the true colour
//! difference in 95 % ± 2 % of them (the binomial sampling error of 2000 trials is 0.5 %).
//! A summary over patches (mean, max) has a nuisance a single truth cannot pin down (how
//! the difference is shared among the patches): its interval may be conservative, and
//! must hold in 93 %–99 % of 1000 trials.
//! 2000 Monte Carlo draws per trial for a patch, 500 for a summary over six, keep each
//! case to a few seconds; the observed coverage is printed
//! (`cargo test --release --lib validation::coverage -- --nocapture`).

use metamer_drivers::noise::SplitMix64;
use rayon::prelude::*;

use super::covariance::{self, Cov3};
use super::montecarlo::{
    lab_noise, patch_interval, summary_interval, LabNoise, Metric, PatchDraws, Statistic,
};
use super::propagate::{Interval, Uncertain};
use super::repeatability;
use crate::color::{delta_e76, Lab, Xyz};

const TRIALS: u64 = 2000;
/// Trials of a summary, whose band is wider.
const SUMMARY_TRIALS: u64 = 1000;
/// Monte Carlo draws per trial of one patch, and of each patch of a summary.
const DRAWS: usize = 2000;
const SUMMARY_DRAWS: usize = 500;

/// The display's white in the default lab, cd/m².
pub(super) const WHITE: Xyz = Xyz::new(15.573, 16.34, 18.356);

/// One patch's truth: the box's and the display's XYZ and one reading's covariance of
/// each, with the repeats each mean is of.
#[derive(Clone)]
pub(super) struct Truth {
    pub(super) reference: Xyz,
    pub(super) test: Xyz,
    pub(super) cov_reference: Cov3,
    pub(super) cov_test: Cov3,
    k_reference: usize,
    k_test: usize,
}

impl Truth {
    pub(super) fn de76(&self) -> f64 {
        delta_e76(self.reference.to_lab(WHITE), self.test.to_lab(WHITE))
    }
}

/// `k` readings about `mean` with one reading's covariance `cov`.
pub(super) fn readings(mean: Xyz, cov: &Cov3, k: usize, rng: &mut SplitMix64) -> Vec<Xyz> {
    let f = covariance::factors(cov);
    (0..k)
        .map(|_| {
            let mut x = mean;
            for v in &f {
                let z = rng.normal();
                for (i, vi) in v.iter().enumerate() {
                    x[i] += vi * z;
                }
            }
            x
        })
        .collect()
}

/// How a trial's side states its uncertainty.
#[derive(Clone, Copy, PartialEq)]
enum Stated {
    /// The true covariance of the mean (as an instrument's stated repeatability is).
    Known,
    /// The sample covariance of the k repeats, with k − 1 degrees of freedom.
    Estimated,
    /// The sample covariance taken as if it were known (what ignoring the few repeats
    /// would give).
    EstimatedAsKnown,
}

fn side(mean: Xyz, cov: &Cov3, k: usize, how: Stated, rng: &mut SplitMix64) -> Uncertain {
    let r = readings(mean, cov, k, rng);
    let (xyz, sample) = covariance::sample(&r);
    let of_mean = |c: &Cov3| covariance::factors(&covariance::scaled(c, 1.0 / k as f64));
    let (factors, dof) = match how {
        Stated::Known => (of_mean(cov), None),
        Stated::Estimated => (of_mean(&sample), Some(k - 1)),
        Stated::EstimatedAsKnown => (of_mean(&sample), None),
    };
    Uncertain {
        xyz,
        factors,
        dof,
        u_lab: 0.0,
    }
}

/// One trial's readings of `truth`, their CIELAB and `draws` noise draws.
fn trial(truth: &Truth, how: Stated, draws: usize, seed: u64) -> (Lab, Lab, LabNoise) {
    let mut rng = SplitMix64::new(SplitMix64::mix(seed));
    let r = side(
        truth.reference,
        &truth.cov_reference,
        truth.k_reference,
        how,
        &mut rng,
    );
    let t = side(truth.test, &truth.cov_test, truth.k_test, how, &mut rng);
    let noise = lab_noise(&r, &t, WHITE, draws, &mut rng);
    (r.xyz.to_lab(WHITE), t.xyz.to_lab(WHITE), noise)
}

/// The share of trials whose ΔE*ab interval holds the truth; and of the percentile
/// interval of noisy ΔE about the readings, for comparison.
fn coverage(truth: &Truth, how: Stated, seed: u64) -> (f64, f64) {
    let de = truth.de76();
    let (hits, naive): (u64, u64) = (0..TRIALS)
        .into_par_iter()
        .map(|i| {
            let key = seed.wrapping_mul(1_000_003) + i;
            let (r, t, noise) = trial(truth, how, DRAWS, key);
            let held = patch_interval(r, t, &noise, Metric::De76, key).contains(de);
            let mut draws: Vec<f64> = (0..DRAWS)
                .map(|j| {
                    let m = |l: Lab, d: [f64; 3]| Lab::new(l.l + d[0], l.a + d[1], l.b + d[2]);
                    delta_e76(m(r, noise.reference[j]), m(t, noise.test[j]))
                })
                .collect();
            draws.sort_by(f64::total_cmp);
            let pct = Interval {
                lo: draws[DRAWS * 25 / 1000],
                hi: draws[DRAWS * 975 / 1000],
            };
            (u64::from(held), u64::from(pct.contains(de)))
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    (hits as f64 / TRIALS as f64, naive as f64 / TRIALS as f64)
}

/// A colour `de` ΔE*ab from `from` along the unit CIELAB direction `dir`.
pub(super) fn moved(from: Xyz, dir: [f64; 3], de: f64) -> Xyz {
    let l = from.to_lab(WHITE);
    let n = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
    Lab::new(
        l.l + de * dir[0] / n,
        l.a + de * dir[1] / n,
        l.b + de * dir[2] / n,
    )
    .to_xyz(WHITE)
}

/// ColorChecker 16 (yellow) as the default lab's box shows it, and the CS-100A's stated
/// repeatability of one reading of it, scaled by `noise`.
pub(super) fn yellow(de: f64, noise: f64, k_reference: usize, k_test: usize) -> Truth {
    let reference = Xyz::new(9.0356, 9.9766, 1.2852);
    let one = repeatability::covariance(&repeatability::emissive_of("cs100a").unwrap(), reference)
        .unwrap();
    let cov = covariance::scaled(&one, noise * noise);
    Truth {
        reference,
        test: moved(reference, [0.3, -0.4, -1.0], de),
        cov_reference: cov,
        cov_test: cov,
        k_reference,
        k_test,
    }
}

fn check(name: &str, (got, naive): (f64, f64)) {
    let percentiles = if naive.is_nan() {
        String::new()
    } else {
        format!(
            " (percentiles of noisy ΔE about the readings: {:.1} %)",
            100.0 * naive
        )
    };
    eprintln!("coverage of {name}: {:.1} %{percentiles}", 100.0 * got);
    assert!((got - 0.95).abs() <= 0.02, "{name}: {got}");
}

/// The truth's ΔE*ab over the standard deviation of its noise along the difference.
fn signal_to_noise(truth: &Truth) -> f64 {
    let (r, t, noise) = trial(truth, Stated::Known, 20_000, 99);
    let d = [t.l - r.l, t.a - r.a, t.b - r.b];
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let along: Vec<f64> = noise
        .reference
        .iter()
        .zip(&noise.test)
        .map(|(a, b)| (0..3).map(|k| (b[k] - a[k]) * d[k] / n).sum())
        .collect();
    let var = along.iter().map(|v| v * v).sum::<f64>() / along.len() as f64;
    truth.de76() / var.sqrt()
}

/// The JND's neighbourhood with the meter's own noise (box 5 repeats, display 3, as the
/// default lab reads them): far from 0 in units of the noise, the interval is nearly
/// the normal one.
#[test]
fn a_patch_at_the_jnd_with_the_meters_covariance_is_covered() {
    let t = yellow(2.3, 1.0, 5, 3);
    let name = format!("ΔE*ab 2.3, CS-100A noise (ΔE/σ {:.1})", signal_to_noise(&t));
    check(&name, coverage(&t, Stated::Known, 1));
}

/// Differences about as large as the noise along them, or smaller (ΔE*ab 0.8 and 0.3
/// against noise 3 times the meter's), where noise lengthens ΔE by a lot.
#[test]
fn a_difference_comparable_to_the_noise_is_covered() {
    for (de, seed) in [(0.8, 2), (0.3, 4)] {
        let t = yellow(de, 3.0, 5, 3);
        let c = coverage(&t, Stated::Known, seed);
        let name = format!("ΔE*ab {de}, ΔE/σ {:.1}", signal_to_noise(&t));
        check(&name, c);
    }
}

/// With the covariance estimated from the repeats themselves (5 and 3), Student's t
/// keeps the coverage; taken as known, the sample covariance gives too short intervals.
#[test]
fn a_covariance_estimated_from_few_repeats_is_covered() {
    let t = yellow(2.3, 1.0, 5, 3);
    check(
        "ΔE*ab 2.3, covariance from 5 and 3 repeats",
        coverage(&t, Stated::Estimated, 3),
    );
    let (as_known, _) = coverage(&t, Stated::EstimatedAsKnown, 3);
    eprintln!(
        "… the same with the sample covariance taken as known: {:.1} %",
        100.0 * as_known
    );
    assert!(as_known < 0.92, "{as_known}");
}

/// Six patches from 0.2 to 2.0 ΔE*ab, their noise `noise` to 2.5·`noise` times the
/// meter's (at 1, ΔE/σ from about 1 to 8, as in the default lab; at 4, every patch but
/// the last lost in noise).
fn six_patches(noise: f64) -> Vec<Truth> {
    [0.2, 0.4, 0.6, 0.9, 1.4, 2.0]
        .iter()
        .enumerate()
        .map(|(i, &de)| {
            let mut t = yellow(de, noise * (1.0 + 0.3 * i as f64), 5, 3);
            t.test = moved(t.reference, [1.0, 0.2 * i as f64, -0.5], de);
            t
        })
        .collect()
}

fn summary_coverage(patches: &[Truth], summary: Statistic, how: Stated, seed: u64) -> f64 {
    let values: Vec<f64> = patches.iter().map(Truth::de76).collect();
    let truth = summary.of(&values);
    let hits: u64 = (0..SUMMARY_TRIALS)
        .into_par_iter()
        .map(|i| {
            let key = seed * 1_000_000 + 100 * i;
            let trials: Vec<(Lab, Lab, LabNoise)> = patches
                .iter()
                .enumerate()
                .map(|(k, t)| trial(t, how, SUMMARY_DRAWS, key + k as u64))
                .collect();
            let draws: Vec<PatchDraws<'_>> = trials
                .iter()
                .map(|(r, t, n)| PatchDraws {
                    reference_lab: *r,
                    test_lab: *t,
                    noise: Some(n),
                    interval: Some(patch_interval(*r, *t, n, Metric::De76, key)),
                })
                .collect();
            let i = summary_interval(&draws, Metric::De76, summary, key).unwrap();
            u64::from(i.contains(truth))
        })
        .sum();
    hits as f64 / SUMMARY_TRIALS as f64
}

fn check_summary(name: &str, got: f64) {
    eprintln!("coverage of {name}: {:.1} %", 100.0 * got);
    assert!((0.93..=0.99).contains(&got), "{name}: {got}");
}

#[test]
fn the_mean_and_max_over_patches_are_covered() {
    for (summary, seed) in [(Statistic::Mean, 7), (Statistic::Max, 8)] {
        let got = summary_coverage(&six_patches(1.0), summary, Stated::Known, seed);
        check_summary(&format!("the {summary:?} ΔE*ab of 6 patches"), got);
    }
}

/// Covariances from 5 and 3 repeats per patch: pooled, their degrees of freedom make the
/// mean's interval nearly the normal one; the max holds its patches' t intervals.
#[test]
fn the_mean_and_max_with_estimated_covariances_are_covered() {
    for (summary, seed) in [(Statistic::Mean, 9), (Statistic::Max, 12)] {
        let got = summary_coverage(&six_patches(1.0), summary, Stated::Estimated, seed);
        check_summary(
            &format!("the {summary:?} ΔE*ab of 6 patches, covariances from repeats"),
            got,
        );
    }
}

/// Where noise swamps most patches.
#[test]
fn the_mean_and_max_of_patches_lost_in_noise_are_covered() {
    for (summary, seed) in [(Statistic::Mean, 10), (Statistic::Max, 11)] {
        let got = summary_coverage(&six_patches(4.0), summary, Stated::Known, seed);
        check_summary(
            &format!("the {summary:?} ΔE*ab of 6 patches lost in noise"),
            got,
        );
    }
}
