//! The rules' intervals with the stopping rule in the loop: 2000 synthetic sessions per
//! case, each reading a target until its rule stops, drawn about a known truth with the
//! readings' generator of [`super::super::coverage`]; an interval must hold the truth in
//! 95 % ± 2 % of them where the rule is tight, and in at least 93 % elsewhere. The same
//! stopping with the fixed-count interval, and the stated figure taken as known where the
//! readings scatter more, are shown to under-cover. The observed figures are printed
//! (`cargo test --release --lib validation::sequential -- --nocapture`).

use metamer_drivers::noise::SplitMix64;
use metamer_drivers::MeasureMode;
use rayon::prelude::*;

use super::super::covariance::{self, Cov3};
use super::super::coverage::{moved, readings, yellow, Truth, WHITE};
use super::*;
use crate::color::Lab;

pub(super) const SESSIONS: u64 = 2000;

pub(super) fn cs100a() -> Repeatability {
    repeatability::stated("cs100a", MeasureMode::Emissive)
}

pub(super) fn rng(case: u64, session: u64) -> SplitMix64 {
    SplitMix64::new(SplitMix64::mix(case.wrapping_mul(1_000_003) + session))
}

fn quadratic(d: [f64; 3], inverse: &Cov3) -> f64 {
    (0..3)
        .map(|i| (0..3).map(|j| d[i] * inverse[i][j] * d[j]).sum::<f64>())
        .sum()
}

fn inverse(c: &Cov3) -> Cov3 {
    let m = nalgebra::Matrix3::from_fn(|i, j| c[i][j]);
    let inv = m.try_inverse().expect("a covariance of full rank");
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| inv[(i, j)]))
}

fn diff(a: Lab, b: Lab) -> [f64; 3] {
    [a.l - b.l, a.a - b.a, a.b - b.b]
}

/// Whether the 95 % region of the mean of `taken` (n readings, one reading's CIELAB
/// covariance from `noise` at their mean) holds `truth`.
fn region_holds(taken: &[Xyz], noise: &RepeatNoise, truth: Xyz) -> bool {
    let (mean, _) = covariance::sample(taken);
    let c = noise.lab_covariance(mean, WHITE).unwrap();
    let d = diff(mean.to_lab(WHITE), truth.to_lab(WHITE));
    taken.len() as f64 * quadratic(d, &inverse(&c)) <= region_quantile(noise.dof)
}

pub(super) fn share(hits: u64, of: u64) -> f64 {
    hits as f64 / of as f64
}

fn check(name: &str, got: f64, mean_n: f64) {
    eprintln!(
        "coverage of {name}: {:.1} %, {mean_n:.2} readings per target",
        100.0 * got
    );
    assert!((got - 0.95).abs() <= 0.02, "{name}: {got}");
}

/// The yellow with the CS-100A's stated figure times `scale`, its one-reading
/// covariance and the figure the rule is told.
fn noisy_yellow(scale: f64) -> (Truth, RepeatNoise) {
    let t = yellow(2.3, scale, 5, 3);
    let noise = RepeatNoise {
        stated: cs100a(),
        scale2: scale * scale,
        dof: None,
    };
    (t, noise)
}

/// The width rule told the true figure: the count is set by the level of the first two
/// readings, and the region at the stopping count covers as a fixed count's does. Stopping
/// on the target's own sample scatter instead (Hotelling's region for the readings so far,
/// valid for a fixed count) is printed for comparison: it stops when the scatter happens
/// to be small, which Hotelling's wide quantile at few readings mostly absorbs here.
#[test]
fn the_width_rule_is_covered_and_stopping_on_the_own_scatter_is_not() {
    let (t, noise) = noisy_yellow(1.0);
    let (half_width_jnd, most) = (0.1, 30);
    let results: Vec<(bool, usize, bool)> = (0..SESSIONS)
        .into_par_iter()
        .map(|s| {
            let mut rng = rng(1, s);
            let all = readings(t.reference, &t.cov_reference, most, &mut rng);
            let n = (MIN_READINGS..=most)
                .find(|&n| width_decided(half_width_jnd, most, &all[..n], &noise, WHITE))
                .unwrap();
            let held = region_holds(&all[..n], &noise, t.reference);
            // Own scatter: from 4 readings (Hotelling needs n > 3), the sample covariance
            // in CIELAB and q = 3(n − 1)/(n − 3)·F(3, n − 3).
            let labs: Vec<[f64; 3]> = all.iter().map(|x| x.to_lab(WHITE).to_array()).collect();
            let own = (4..=most)
                .find(|&n| {
                    let s = covariance::spread(&labs[..n]);
                    let (values, _) = covariance::eigen_decomposition(&s);
                    let q = hotelling(n);
                    let largest = values.iter().copied().fold(0.0, f64::max);
                    (q * largest / n as f64).sqrt() <= half_width_jnd * JND_DE76
                })
                .unwrap_or(most);
            let s = covariance::spread(&labs[..own]);
            let m = mean_of(&labs[..own]);
            let truth = t.reference.to_lab(WHITE).to_array();
            let d = [0, 1, 2].map(|i| m[i] - truth[i]);
            let own_held = own as f64 * quadratic(d, &inverse(&s)) <= hotelling(own);
            (held, n, own_held)
        })
        .collect();
    let hits = results.iter().filter(|r| r.0).count() as u64;
    let mean_n = results.iter().map(|r| r.1 as f64).sum::<f64>() / SESSIONS as f64;
    check(
        "the width rule (0.1 JND, the stated figure)",
        share(hits, SESSIONS),
        mean_n,
    );
    let own = share(results.iter().filter(|r| r.2).count() as u64, SESSIONS);
    eprintln!(
        "… stopping on the target's own scatter instead: {:.1} %",
        100.0 * own
    );
}

fn hotelling(n: usize) -> f64 {
    let n = n as f64;
    3.0 * (n - 1.0) / (n - 3.0) * distributions::f_quantile(CONFIDENCE, 3.0, n - 3.0)
}

fn mean_of(rows: &[[f64; 3]]) -> [f64; 3] {
    let k = rows.len() as f64;
    [0, 1, 2].map(|i| rows.iter().map(|r| r[i]).sum::<f64>() / k)
}

/// Six targets of different level and hue, as a session reads them.
fn six_targets() -> Vec<Xyz> {
    let base = yellow(0.0, 1.0, 1, 1).reference;
    [0.0, 0.8, 1.6, 2.4, 3.2, 4.0]
        .iter()
        .enumerate()
        .map(|(i, &de)| {
            let hue = [1.0, -0.5 + 0.3 * i as f64, 0.2 * i as f64 - 1.0];
            moved(base, hue, 10.0 * de)
        })
        .collect()
}

/// One session of the width rule over `targets` with the pool: each target's count from
/// the pool of the targets before it; at the end each target's region with the pool of
/// all, and its degrees of freedom. True noise `scale` times the stated figure.
fn pooled_session(targets: &[Xyz], scale: f64, session: u64) -> (Pool, Vec<bool>, usize) {
    let stated = cs100a();
    let mut rng = rng(3, session);
    let mut pool = Pool::default();
    let mut taken: Vec<Vec<Xyz>> = Vec::new();
    let (half_width_jnd, most) = (0.3, 12);
    for &truth in targets {
        let one = covariance::scaled(
            &repeatability::covariance(&stated, truth).unwrap(),
            scale * scale,
        );
        let all = readings(truth, &one, most, &mut rng);
        // The stopping figure: the pool's point estimate, taken as known.
        let so_far = RepeatNoise {
            dof: None,
            ..pool.noise(stated)
        };
        let n = (MIN_READINGS..=most)
            .find(|&n| width_decided(half_width_jnd, most, &all[..n], &so_far, WHITE))
            .unwrap();
        pool.add(&all[..n], &stated);
        taken.push(all[..n].to_vec());
    }
    let noise = pool.noise(stated);
    let held = taken
        .iter()
        .zip(targets)
        .map(|(r, &truth)| region_holds(r, &noise, truth))
        .collect();
    let count = taken.iter().map(Vec::len).sum();
    (pool, held, count)
}

/// The pooled figure is honest: with readings scattering twice the stated figure, the
/// pooled factor's χ² interval holds the true factor 4 in 95 % ± 2 % of the sessions, and
/// the regions with the pooled figure cover at 95 % ± 2 %, where the stated figure taken
/// as known does not.
#[test]
fn the_pooled_figure_is_honest_and_its_regions_are_covered() {
    let targets = six_targets();
    let scale = 2.0;
    let sessions: Vec<(Pool, Vec<bool>, usize)> = (0..SESSIONS)
        .into_par_iter()
        .map(|s| pooled_session(&targets, scale, s))
        .collect();
    let factor_held = sessions
        .iter()
        .filter(|(pool, _, _)| {
            let nu = pool.dof as f64;
            let lo = pool.sum / distributions::chi2_quantile(0.975, nu);
            let hi = pool.sum / distributions::chi2_quantile(0.025, nu);
            (lo..=hi).contains(&(scale * scale))
        })
        .count() as u64;
    let factor = share(factor_held, SESSIONS);
    let mean_scale = sessions
        .iter()
        .map(|(p, _, _)| (p.sum / p.dof as f64).sqrt())
        .sum::<f64>()
        / SESSIONS as f64;
    eprintln!(
        "the pooled factor's interval holds the truth in {:.1} % (mean pooled scale {mean_scale:.3}, true 2)",
        100.0 * factor
    );
    assert!((factor - 0.95).abs() <= 0.02, "{factor}");
    let targets_read = SESSIONS * targets.len() as u64;
    let hits = sessions
        .iter()
        .map(|(_, h, _)| h.iter().filter(|&&b| b).count() as u64)
        .sum();
    let mean_n = sessions.iter().map(|s| s.2 as f64).sum::<f64>() / targets_read as f64;
    check(
        "the width rule with the pooled figure (6 targets, noise ×2)",
        share(hits, targets_read),
        mean_n,
    );
    // The same readings' regions with the stated figure taken as known.
    let stated = sessions
        .iter()
        .enumerate()
        .map(|(s, _)| {
            let mut rng = rng(3, s as u64);
            let truth = targets[0];
            let one = covariance::scaled(
                &repeatability::covariance(&cs100a(), truth).unwrap(),
                scale * scale,
            );
            let all = readings(truth, &one, 3, &mut rng);
            u64::from(region_holds(&all, &RepeatNoise::stated(cs100a()), truth))
        })
        .sum::<u64>();
    let stated = share(stated, SESSIONS);
    eprintln!(
        "… the stated figure taken as known for readings scattering twice it: {:.1} %",
        100.0 * stated
    );
    assert!(stated < 0.8, "{stated}");
}

/// One verdict session: the reference read 5 times (its mean's covariance known), the test
/// side read until the rule stops; whether the interval at the stop holds the true ΔE,
/// the count, and whether the fixed-count interval (1.96 σ) at the same rule's stop would.
fn verdict_session(
    t: &Truth,
    noise: &RepeatNoise,
    margin: f64,
    most: usize,
    s: u64,
) -> (bool, usize, bool) {
    let mut rng = rng(5, s);
    let box_readings = readings(t.reference, &t.cov_reference, 5, &mut rng);
    let (r, _) = covariance::sample(&box_readings);
    let reference = Reference {
        xyz: r,
        cov_mean: covariance::scaled(&t.cov_reference, 1.0 / 5.0),
        dof: None,
        lab_var: 0.0,
    };
    let all = readings(t.test, &t.cov_test, most, &mut rng);
    let truth = t.de76();
    let look = (MIN_READINGS..=most)
        .map(|n| verdict(margin, most, &reference, &all[..n], noise, WHITE).unwrap())
        .enumerate()
        .find(|(_, l)| l.decided)
        .unwrap();
    let n = look.0 + MIN_READINGS;
    // Naive: the same looks with the fixed-count constant 1.96, stopping where it decides.
    let naive = (MIN_READINGS..=most)
        .map(|n| {
            let l = verdict(margin, most, &reference, &all[..n], noise, WHITE).unwrap();
            let half =
                (l.interval.hi - l.de76) / l.constant * distributions::normal_quantile(0.975);
            Interval {
                lo: (l.de76 - half).max(0.0),
                hi: l.de76 + half,
            }
        })
        .enumerate()
        .find(|(i, iv)| {
            i + MIN_READINGS >= most || iv.hi <= JND_DE76 - margin || iv.lo >= JND_DE76 + margin
        })
        .unwrap()
        .1;
    (look.1.interval.contains(truth), n, naive.contains(truth))
}

/// The verdict rule at a true ΔE*ab on the JND, where it stops early only by mistake: the
/// repeated intervals cover at 95 % ± 2 %; the fixed-count interval with the same stopping
/// does not. Off the JND it stops sooner and covers at least as well.
#[test]
fn the_verdict_rule_is_covered_at_the_jnd_and_beyond() {
    let stated = cs100a();
    // The meter's own noise: the first-order interval's domain (see the module's notes).
    let scale = 1.0;
    let noise = RepeatNoise {
        stated,
        scale2: scale * scale,
        dof: None,
    };
    let most = 10;
    for (de, tight) in [(JND_DE76, true), (1.6, false), (3.2, false)] {
        let mut t = yellow(de, scale, 5, 1);
        t.test = moved(t.reference, [0.3, -0.4, -1.0], de);
        t.cov_test = covariance::scaled(
            &repeatability::covariance(&stated, t.test).unwrap(),
            scale * scale,
        );
        let results: Vec<(bool, usize, bool)> = (0..SESSIONS)
            .into_par_iter()
            .map(|s| verdict_session(&t, &noise, 0.0, most, s + 10_000 * de as u64))
            .collect();
        let hits = results.iter().filter(|r| r.0).count() as u64;
        let got = share(hits, SESSIONS);
        let mean_n = results.iter().map(|r| r.1 as f64).sum::<f64>() / SESSIONS as f64;
        let naive = share(results.iter().filter(|r| r.2).count() as u64, SESSIONS);
        let name = format!("the verdict rule at ΔE*ab {de} (up to {most} readings)");
        if tight {
            check(&name, got, mean_n);
            eprintln!(
                "… the fixed-count interval with the same stopping: {:.1} %",
                100.0 * naive
            );
            assert!(naive < 0.93, "{naive}");
        } else {
            eprintln!(
                "coverage of {name}: {:.1} %, {mean_n:.2} readings per target (fixed-count interval {:.1} %)",
                100.0 * got,
                100.0 * naive
            );
            assert!(got >= 0.93, "{name}: {got}");
        }
    }
}

/// The 24 ColorChecker spots (BabelColor average under D65) as the box shows them: a
/// white reflector at half the white's luminance, as the spots lie below the light.
pub(super) fn colorchecker_spots() -> Vec<Xyz> {
    use crate::color::{colorchecker, reflectance_to_xyz, ColorCheckerSet, Illuminant};
    let d65 = Illuminant::D65.spectrum();
    colorchecker(ColorCheckerSet::BabelColorAverage)
        .iter()
        .map(|s| {
            let xyz = reflectance_to_xyz(s, &d65, crate::color::ObserverKind::Cie1931);
            let k = 0.5 * WHITE.y / 100.0;
            Xyz::new(xyz.x * k, xyz.y * k, xyz.z * k)
        })
        .collect()
}

/// One box session as the spots stage reads it (`measure_box::spot_rule`): each spot read
/// until the width rule stops it, its count from the figure pooled over the spots before;
/// then, with the figure pooled over every spot's readings and its ν, whether each spot's
/// 95 % region holds its truth, and whether its L* and b* intervals (Student's t with the
/// pooled ν, as the validation takes them) do. Readings scatter `scale` times the stated
/// figure.
fn box_session(spots: &[Xyz], scale: f64, session: u64) -> (Vec<[bool; 3]>, usize, usize) {
    let stated = cs100a();
    let mut rng = rng(7 + (10.0 * scale) as u64, session);
    let mut pool = Pool::default();
    let mut taken: Vec<Vec<Xyz>> = Vec::new();
    let (half_width_jnd, most) = (0.2, 10);
    for &truth in spots {
        let one = covariance::scaled(
            &repeatability::covariance(&stated, truth).unwrap(),
            scale * scale,
        );
        let all = readings(truth, &one, most, &mut rng);
        let so_far = RepeatNoise {
            dof: None,
            ..pool.noise(stated)
        };
        let n = (MIN_READINGS..=most)
            .find(|&n| width_decided(half_width_jnd, most, &all[..n], &so_far, WHITE))
            .unwrap();
        pool.add(&all[..n], &stated);
        taken.push(all[..n].to_vec());
    }
    let noise = pool.noise(stated);
    let t = distributions::t_quantile(0.975, pool.dof as f64);
    let held = taken
        .iter()
        .zip(spots)
        .map(|(r, &truth)| {
            let (mean, _) = covariance::sample(r);
            let c = noise.lab_covariance(mean, WHITE).unwrap();
            let d = diff(mean.to_lab(WHITE), truth.to_lab(WHITE));
            let k = r.len() as f64;
            let axis = |i: usize| d[i].abs() <= t * (c[i][i] / k).sqrt();
            [region_holds(r, &noise, truth), axis(0), axis(2)]
        })
        .collect();
    let count = taken.iter().map(Vec::len).sum();
    (held, count, pool.dof)
}

/// The pool and the rule together, as the box reads its 24 spots: the width rule stops
/// each spot on the figure pooled before it, and the validation's intervals take the
/// figure pooled over the same readings with its ν. Every spot's 95 % region, and its L*
/// and b* intervals, hold the truth in 95 % ± 2 % of 2000 sessions.
#[test]
fn the_pooled_figure_at_the_width_rules_count_covers_each_of_24_spots() {
    let spots = colorchecker_spots();
    assert_eq!(spots.len(), 24);
    // The meter's own scatter: the simulated box's (twice it covers too, at three times
    // the readings and the time).
    let scale = 1.0;
    let sessions: Vec<(Vec<[bool; 3]>, usize, usize)> = (0..SESSIONS)
        .into_par_iter()
        .map(|s| box_session(&spots, scale, s))
        .collect();
    let mean_n = sessions.iter().map(|s| s.1 as f64).sum::<f64>() / SESSIONS as f64;
    let mean_dof = sessions.iter().map(|s| s.2 as f64).sum::<f64>() / SESSIONS as f64;
    let mut worst = [(0.95f64, 0usize); 3];
    for (j, _) in spots.iter().enumerate() {
        for (w, what) in ["95 % region", "L* interval", "b* interval"]
            .iter()
            .enumerate()
        {
            let hits = sessions.iter().filter(|s| s.0[j][w]).count() as u64;
            let got = share(hits, SESSIONS);
            assert!(
                (got - 0.95).abs() <= 0.02,
                "spot {}, {what}, noise ×{scale}: {got}",
                j + 1
            );
            if (got - 0.95).abs() > (worst[w].0 - 0.95).abs() {
                worst[w] = (got, j + 1);
            }
        }
    }
    eprintln!(
        "24 spots by the width rule (0.2 JND, at most 10) with the pooled figure, noise ×{scale}: {:.1} readings a session, ν {:.0}; farthest from 95 %: region {:.1} % (spot {}), L* {:.1} % (spot {}), b* {:.1} % (spot {})",
        mean_n,
        mean_dof,
        100.0 * worst[0].0,
        worst[0].1,
        100.0 * worst[1].0,
        worst[1].1,
        100.0 * worst[2].0,
        worst[2].1
    );
}
