//! Monte Carlo intervals: noise draws of each patch's two readings in CIELAB, and the
//! bias-aware interval of a patch's colour difference or of a summary over patches by
//! test inversion ([`super::inversion`]).
//!
//! A covariance estimated from k repeats is itself uncertain. As the GUM does (G.4), the
//! interval then widens by Student's t with the Welch–Satterthwaite effective degrees of
//! freedom ν = V² / Σ(vⱼ²/νⱼ), where vⱼ is each side's variance along the colour difference
//! and νⱼ = kⱼ − 1 (a stated repeatability or a renderer's error counts as known): each
//! draw's noise is scaled by √(ν/χ²_ν). A summary over patches pools their degrees of
//! freedom the same way for a mean, so 24 patches of 3 repeats each are nearly normal
//! while one patch of 3 is t₂; a max, which turns on one patch or two, takes its draws
//! with the covariances as known and then holds every patch's own bounds. Scaling each side on its own instead would give a sum of t's far wider than the
//! estimated covariance warrants (97.9 % coverage where 95 % is asked).
//!
//! The family of truths inverted over is the profile one: for each true length, the
//! difference nearest the observed one in the noise's own metric (Mahalanobis). In the
//! eigenbasis of the difference's noise covariance, with eigenvalues sₖ, the truth at c is
//! c·dₖ / (c + (1 − c)·sₖ/s_max): shrinking (c < 1) takes first what lies along the
//! noisiest axis, growing (c > 1) adds there first; isotropic noise gives plain scaling by
//! c. Plain scaling for a yellow, whose noise lies nearly all along b*, covered 78 %–88 %
//! at ΔE/σ ≈ 1; the profile covers 95 %. A summary over patches goes one step further:
//! for a mean, the patches' lengths nearest the observed ones (in units of each patch's
//! noise along its difference, σᵢ²) that have that mean — each shortened by λσᵢ² and none
//! below 0, so patches lost in noise go to 0 first; for a max, the lengths clipped at it
//! (or, above the observed max, the largest lengthened); each length then the patch's own
//! profile point.

use metamer_drivers::noise::SplitMix64;

use super::covariance::{self, Cov3};
use super::inversion::{invert, PATCH_TOLERANCE};
use super::uncertain::{lab_of, Interval, Uncertain};
use crate::color::{delta_e2000, delta_e76, Lab, Xyz};

/// One patch's Monte Carlo draws: how each draw moves the reference's and the test's
/// CIELAB from their observed values (the covariances taken as they are), and the degrees
/// of freedom each side's covariance has where estimated (None: known).
#[derive(Clone, PartialEq)]
pub struct LabNoise {
    pub reference: Vec<[f64; 3]>,
    pub test: Vec<[f64; 3]>,
    pub dof_reference: Option<usize>,
    pub dof_test: Option<usize>,
}

/// Which colour difference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    De76,
    De00,
}

impl Metric {
    pub fn of(self, a: Lab, b: Lab) -> f64 {
        match self {
            Metric::De76 => delta_e76(a, b),
            Metric::De00 => delta_e2000(a, b),
        }
    }
}

/// A statistic over patches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Statistic {
    Mean,
    Max,
}

impl Statistic {
    pub fn of(self, v: &[f64]) -> f64 {
        match self {
            Statistic::Mean => v.iter().sum::<f64>() / v.len() as f64,
            Statistic::Max => v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

/// One patch's observed CIELAB pair, its noise and its own interval by the summary's
/// metric, as a summary over patches takes them.
pub struct PatchDraws<'a> {
    pub reference_lab: Lab,
    pub test_lab: Lab,
    pub noise: Option<&'a LabNoise>,
    pub interval: Option<Interval>,
}

/// How finely a summary's bounds are found, relative to their scale.
const SUMMARY_TOLERANCE: f64 = 1e-3;

/// One draw of `side`'s CIELAB less its observed `lab`.
fn draw(side: &Uncertain, lab: Lab, white: Xyz, rng: &mut SplitMix64) -> [f64; 3] {
    let z: Vec<f64> = side.factors.iter().map(|_| rng.normal()).collect();
    let zl = [rng.normal(), rng.normal(), rng.normal()];
    let moved = lab_of(side, &z, &zl, white);
    [moved.l - lab.l, moved.a - lab.a, moved.b - lab.b]
}

/// `draws` Monte Carlo draws of how `reference`'s and `test`'s CIELAB (relative to
/// `white`) move with their uncertainty.
pub fn lab_noise(
    reference: &Uncertain,
    test: &Uncertain,
    white: Xyz,
    draws: usize,
    rng: &mut SplitMix64,
) -> LabNoise {
    let (rl, tl) = (reference.xyz.to_lab(white), test.xyz.to_lab(white));
    let mut noise = LabNoise {
        reference: Vec::with_capacity(draws),
        test: Vec::with_capacity(draws),
        dof_reference: reference.dof.filter(|_| !reference.factors.is_empty()),
        dof_test: test.dof.filter(|_| !test.factors.is_empty()),
    };
    for _ in 0..draws {
        noise.reference.push(draw(reference, rl, white, rng));
        noise.test.push(draw(test, tl, white, rng));
    }
    noise
}

fn add(a: Lab, d: [f64; 3]) -> Lab {
    Lab::new(a.l + d[0], a.a + d[1], a.b + d[2])
}

fn sub(a: Lab, b: Lab) -> [f64; 3] {
    [a.l - b.l, a.a - b.a, a.b - b.b]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// The unit vector of the observed difference, or where there is none of L* (any would
/// do: the interval then starts at 0).
fn unit(r: Lab, t: Lab) -> [f64; 3] {
    let d = sub(t, r);
    let n = norm(d);
    if n > 0.0 {
        d.map(|v| v / n)
    } else {
        [1.0, 0.0, 0.0]
    }
}

/// The sample covariance of the draws' differences, test less reference.
fn difference_covariance(noise: &LabNoise) -> Cov3 {
    let d: Vec<[f64; 3]> = noise
        .reference
        .iter()
        .zip(&noise.test)
        .map(|(r, t)| [t[0] - r[0], t[1] - r[1], t[2] - r[2]])
        .collect();
    covariance::spread(&d)
}

/// One patch's family of true differences (module docs): the observed difference `d`
/// in the eigenbasis of its noise covariance, and each axis's share of the largest
/// variance.
struct Family {
    basis: [[f64; 3]; 3],
    d: [f64; 3],
    share: [f64; 3],
}

impl Family {
    fn new(d: [f64; 3], noise: Option<&LabNoise>) -> Family {
        let (values, basis) = match noise {
            Some(n) => covariance::eigen_decomposition(&difference_covariance(n)),
            None => (
                [1.0; 3],
                [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            ),
        };
        let top = values.iter().copied().fold(0.0, f64::max);
        // An axis without noise would keep its component at every c; a floor lets every
        // truth down to 0 (and costs nothing measurable).
        let share = values.map(|v| if top > 0.0 { (v / top).max(1e-6) } else { 1.0 });
        let along = [0, 1, 2].map(|k| (0..3).map(|i| basis[i][k] * d[i]).sum());
        Family {
            basis,
            d: along,
            share,
        }
    }

    /// The true difference at c (0: none; 1: the observed one).
    fn at(&self, c: f64) -> [f64; 3] {
        if c <= 0.0 {
            return [0.0; 3];
        }
        let k = [0, 1, 2].map(|k| c * self.d[k] / (c + (1.0 - c) * self.share[k]));
        [0, 1, 2].map(|i| (0..3).map(|j| self.basis[i][j] * k[j]).sum())
    }

    /// The c at which the truth's length is `len` (|at(c)| grows with c).
    fn c_for(&self, len: f64) -> f64 {
        if len <= 0.0 {
            return 0.0;
        }
        let (mut a, mut b) = (0.0, 1.0);
        while norm(self.at(b)) < len {
            a = b;
            b *= 2.0;
            if b > 1e12 {
                return b;
            }
        }
        for _ in 0..50 {
            let m = 0.5 * (a + b);
            if norm(self.at(m)) < len {
                a = m;
            } else {
                b = m;
            }
        }
        0.5 * (a + b)
    }
}

/// The variance of the draws' component along `u`.
fn variance_along(draws: &[[f64; 3]], u: [f64; 3]) -> f64 {
    let n = draws.len() as f64;
    let (mut s, mut s2) = (0.0, 0.0);
    for d in draws {
        let v = dot(*d, u);
        s += v;
        s2 += v * v;
    }
    ((s2 - s * s / n) / (n - 1.0).max(1.0)).max(0.0)
}

/// One side's variance along `u` and its degrees of freedom (None: known).
type Part = (f64, Option<usize>);

fn parts(noise: &LabNoise, u: [f64; 3]) -> [Part; 2] {
    [
        (variance_along(&noise.reference, u), noise.dof_reference),
        (variance_along(&noise.test, u), noise.dof_test),
    ]
}

/// The Welch–Satterthwaite degrees of freedom of weighted parts, None where every part
/// with variance is known.
fn effective_dof(parts: &[(f64, Part)]) -> Option<f64> {
    let total: f64 = parts.iter().map(|(w, (v, _))| w * v).sum();
    let spread: f64 = parts
        .iter()
        .filter_map(|(w, (v, nu))| nu.map(|nu| (w * v).powi(2) / nu as f64))
        .sum();
    (spread > 0.0).then(|| total * total / spread)
}

/// A Gamma(shape, 1) draw (Marsaglia and Tsang, 2000; below shape 1 by their boost
/// Gamma(a) = Gamma(a + 1)·U^(1/a)).
fn gamma(shape: f64, rng: &mut SplitMix64) -> f64 {
    if shape < 1.0 {
        return gamma(shape + 1.0, rng) * rng.uniform().powf(1.0 / shape);
    }
    let d = shape - 1.0 / 3.0;
    let c = 1.0 / (9.0 * d).sqrt();
    loop {
        let x = rng.normal();
        let v = (1.0 + c * x).powi(3);
        if v <= 0.0 {
            continue;
        }
        let u = rng.uniform();
        if u.ln() < 0.5 * x * x + d - d * v + d * v.ln() {
            return d * v;
        }
    }
}

/// Degrees of freedom beyond which Student's t is taken as the normal (t's 97.5th
/// percentile is then within 0.02 % of 1.96).
const NORMAL_DOF: f64 = 1e4;

/// Each draw's factor √(ν/χ²_ν) for `nu` effective degrees of freedom; 1 where known.
fn t_scales(nu: Option<f64>, draws: usize, seed: u64) -> Vec<f64> {
    match nu {
        Some(nu) if nu < NORMAL_DOF => {
            let mut rng = SplitMix64::new(SplitMix64::mix(seed ^ 0x7475_6465_6e74));
            (0..draws)
                .map(|_| (nu / (2.0 * gamma(nu / 2.0, &mut rng))).sqrt())
                .collect()
        }
        _ => vec![1.0; draws],
    }
}

/// The bias-aware 95 % interval of `metric` between one patch's readings, CIELAB `r` and
/// `t`, from their noise draws; `seed` keys the draws of Student's t where a covariance
/// was estimated.
pub fn patch_interval(r: Lab, t: Lab, noise: &LabNoise, metric: Metric, seed: u64) -> Interval {
    let u = unit(r, t);
    let n = noise.reference.len();
    let scale = t_scales(effective_dof(&parts(noise, u).map(|p| (1.0, p))), n, seed);
    // The truths: the observed difference's profile family (an L* step where none).
    let d = if r == t { u } else { sub(t, r) };
    let family = Family::new(d, Some(noise));
    let at = |c: f64| add(r, family.at(c));
    invert(
        metric.of(r, t),
        n,
        |c, i| {
            let s = scale[i];
            metric.of(
                add(r, noise.reference[i].map(|v| s * v)),
                add(at(c), noise.test[i].map(|v| s * v)),
            )
        },
        |c| metric.of(r, at(c)),
        PATCH_TOLERANCE,
    )
}

/// The bias-aware 95 % interval of `summary` of the patches' colour differences by
/// `metric`, over the profile family of truths (module docs). None where no patch has
/// noise draws. `seed` keys the draws of Student's t.
pub fn summary_interval(
    patches: &[PatchDraws<'_>],
    metric: Metric,
    summary: Statistic,
    seed: u64,
) -> Option<Interval> {
    let n = patches
        .iter()
        .filter_map(|p| p.noise.map(|d| d.reference.len()))
        .max()?;
    let units: Vec<[f64; 3]> = patches
        .iter()
        .map(|p| unit(p.reference_lab, p.test_lab))
        .collect();
    let lengths: Vec<f64> = patches
        .iter()
        .map(|p| norm(sub(p.test_lab, p.reference_lab)))
        .collect();
    let parts: Vec<[Part; 2]> = patches
        .iter()
        .zip(&units)
        .map(|(p, u)| p.noise.map_or([(0.0, None); 2], |d| parts(d, *u)))
        .collect();
    let sigma2: Vec<f64> = parts
        .iter()
        .map(|p| (p[0].0 + p[1].0).max(f64::MIN_POSITIVE))
        .collect();
    let scale = t_scales(summary_dof(summary, &parts), n, seed);
    // The patches' true lengths at c (c = 1: the observed ones).
    let family = |c: f64| true_lengths(summary, &lengths, &sigma2, c);
    let families: Vec<Family> = patches
        .iter()
        .zip(&units)
        .zip(&lengths)
        .map(|((p, u), l)| Family::new(if *l > 0.0 { u.map(|v| v * l) } else { *u }, p.noise))
        .collect();
    // The patches' true CIELAB at c: each length its family's point.
    let truths = |c: f64| -> Vec<Lab> {
        family(c)
            .iter()
            .zip(&families)
            .zip(patches)
            .map(|((len, f), p)| add(p.reference_lab, f.at(f.c_for(*len))))
            .collect()
    };
    // One buffer for the values: the statistic is evaluated millions of times.
    let buffer = std::cell::RefCell::new(vec![0.0; patches.len()]);
    let value = |truth: &[Lab], i: Option<usize>| -> f64 {
        let mut v = buffer.borrow_mut();
        for ((p, t), out) in patches.iter().zip(truth).zip(v.iter_mut()) {
            *out = match (i, p.noise) {
                (Some(i), Some(d)) => {
                    let s = scale[i];
                    metric.of(
                        add(p.reference_lab, d.reference[i].map(|x| s * x)),
                        add(*t, d.test[i].map(|x| s * x)),
                    )
                }
                _ => metric.of(p.reference_lab, *t),
            };
        }
        summary.of(&v)
    };
    let observed: Vec<f64> = patches
        .iter()
        .map(|p| metric.of(p.reference_lab, p.test_lab))
        .collect();
    // The truths are found once per c, not per draw.
    let cache = std::cell::RefCell::new((f64::NAN, Vec::new()));
    let mut interval = invert(
        summary.of(&observed),
        n,
        |c, i| {
            let mut k = cache.borrow_mut();
            if k.0 != c {
                *k = (c, truths(c));
            }
            value(&k.1, Some(i))
        },
        |c| value(&truths(c), None),
        SUMMARY_TOLERANCE,
    );
    if summary == Statistic::Max {
        for i in patches.iter().filter_map(|p| p.interval) {
            interval.lo = interval.lo.max(i.lo);
            interval.hi = interval.hi.max(i.hi);
        }
    }
    Some(interval)
}

/// The degrees of freedom of `summary`'s draws. A mean pools the patches' (Welch–
/// Satterthwaite over all of them: nearly normal for many patches). A max turns on one
/// patch or two, whose own intervals carry their t: its draws take the covariances as
/// known (None), and its bounds then hold every patch's own (the max is at least each
/// patch's difference).
fn summary_dof(summary: Statistic, parts: &[[Part; 2]]) -> Option<f64> {
    match summary {
        Statistic::Mean => effective_dof(
            &parts
                .iter()
                .flat_map(|p| [(1.0, p[0]), (1.0, p[1])])
                .collect::<Vec<_>>(),
        ),
        Statistic::Max => None,
    }
}

/// The patches' true lengths at `c` of the profile family of `summary` (c = 1: the
/// observed `lengths`; `sigma2` each patch's variance along its difference).
fn true_lengths(summary: Statistic, lengths: &[f64], sigma2: &[f64], c: f64) -> Vec<f64> {
    let top = lengths.iter().copied().fold(0.0, f64::max);
    if top == 0.0 {
        // No difference anywhere: every patch an L* step of c.
        return vec![c; lengths.len()];
    }
    match summary {
        Statistic::Mean => {
            let most = lengths
                .iter()
                .zip(sigma2)
                .map(|(l, s)| l / s)
                .fold(0.0, f64::max);
            let lambda = most * (1.0 - c);
            lengths
                .iter()
                .zip(sigma2)
                .map(|(l, s)| (l - lambda * s).max(0.0))
                .collect()
        }
        Statistic::Max => {
            let cap = c * top;
            let mut v: Vec<f64> = lengths.iter().map(|l| l.min(cap)).collect();
            if c > 1.0 {
                if let Some(k) = lengths.iter().position(|l| *l == top) {
                    v[k] = cap;
                }
            }
            v
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean of Gamma(a) draws is a and their variance a (both shapes, each side of
    /// the boost).
    #[test]
    fn gamma_draws_have_their_mean_and_variance() {
        let mut rng = SplitMix64::new(11);
        for a in [0.5, 1.0, 2.5, 24.0] {
            let v: Vec<f64> = (0..200_000).map(|_| gamma(a, &mut rng)).collect();
            let m = v.iter().sum::<f64>() / v.len() as f64;
            let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64;
            assert!((m / a - 1.0).abs() < 0.01, "{a}: mean {m}");
            assert!((var / a - 1.0).abs() < 0.03, "{a}: variance {var}");
        }
    }

    /// Welch–Satterthwaite by hand: variances 1 (4 dof) and 3 (2 dof) give
    /// 16 / (1/4 + 9/2) = 3.3684; a known part adds variance only.
    #[test]
    fn effective_degrees_of_freedom_by_hand() {
        let nu = effective_dof(&[(1.0, (1.0, Some(4))), (1.0, (3.0, Some(2)))]).unwrap();
        assert!((nu - 16.0 / 4.75).abs() < 1e-12, "{nu}");
        let nu = effective_dof(&[(1.0, (1.0, Some(4))), (1.0, (3.0, None))]).unwrap();
        assert!((nu - 64.0).abs() < 1e-12, "{nu}");
        assert_eq!(effective_dof(&[(1.0, (1.0, None))]), None);
    }
}
