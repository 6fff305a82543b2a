//! The two sides of display vs box read by lean rules, with both stoppings in the loop:
//! the box's spots by a fixed count or the width rule, the display's by the verdict rule
//! against them, each side's figure pooled across its patches, and each patch's interval
//! formed as the validation forms it (the repeated interval at the display's count,
//! Welch–Satterthwaite over the two pooled figures). The observed coverage is printed
//! (`cargo test --release --lib validation::sequential::coverage_pairs -- --nocapture`).

use metamer_drivers::noise::SplitMix64;
use rayon::prelude::*;

use super::super::coverage::{moved, readings, WHITE};
use super::coverage::{colorchecker_spots, cs100a, rng, share, SESSIONS};
use super::*;
use crate::color::delta_e76;

/// Each of `spots` read `repeats` times as `rule` stops it (a fixed count, or a width
/// rule on the figure pooled before), reduced as the readings files state it: each
/// target's mean with the figure pooled over all of them, and its ν.
fn pooled_side(
    spots: &[Xyz],
    rule: &RepeatRule,
    white: Xyz,
    rng: &mut SplitMix64,
) -> (Vec<(Xyz, usize)>, RepeatNoise) {
    let stated = cs100a();
    let mut pool = Pool::default();
    let mut taken = Vec::new();
    for &truth in spots {
        let one = repeatability::covariance(&stated, truth).unwrap();
        let most = rule.most();
        let all = readings(truth, &one, most, rng);
        let n = match *rule {
            RepeatRule::Width {
                half_width_jnd,
                most,
            } => {
                let so_far = RepeatNoise {
                    dof: None,
                    ..pool.noise(stated)
                };
                (MIN_READINGS..=most)
                    .find(|&n| width_decided(half_width_jnd, most, &all[..n], &so_far, white))
                    .unwrap()
            }
            _ => most,
        };
        pool.add(&all[..n], &stated);
        taken.push((covariance::sample(&all[..n]).0, n));
    }
    (taken, pool.noise(stated))
}

/// One lab's display-vs-box comparison as the validation forms it: the box's spots read
/// by `box_rule`, the display's by the verdict rule (`margin`, `most`) against them, each
/// display patch's truth ΔE*ab `de` from its box truth; whether each patch's interval
/// (the repeated interval at the display's count, each side's pooled figure with its ν,
/// Welch–Satterthwaite over both) holds the true ΔE*ab, and the readings taken.
fn lab_session(
    spots: &[Xyz],
    box_rule: &RepeatRule,
    (margin, most): (f64, usize),
    de: f64,
    session: u64,
) -> (Vec<bool>, usize) {
    let mut rng = rng(11, session);
    let (boxed, box_noise) = pooled_side(spots, box_rule, WHITE, &mut rng);
    let stated = cs100a();
    let truths: Vec<Xyz> = spots
        .iter()
        .enumerate()
        .map(|(i, &s)| {
            let a = i as f64 * 2.4;
            moved(s, [0.4, a.cos(), a.sin()], de)
        })
        .collect();
    let references: Vec<Reference> = boxed
        .iter()
        .map(|&(xyz, n)| Reference {
            xyz,
            cov_mean: covariance::scaled(&box_noise.covariance(xyz).unwrap(), 1.0 / n as f64),
            dof: box_noise.dof,
            lab_var: 0.0,
        })
        .collect();
    // The display's rule stops each patch on the figure pooled over the patches before.
    let mut pool = Pool::default();
    let mut taken: Vec<Vec<Xyz>> = Vec::new();
    for (truth, reference) in truths.iter().zip(&references) {
        let one = repeatability::covariance(&stated, *truth).unwrap();
        let all = readings(*truth, &one, most, &mut rng);
        let so_far = pool.noise(stated);
        let n = (MIN_READINGS..=most)
            .find(|&n| {
                verdict(margin, most, reference, &all[..n], &so_far, WHITE)
                    .is_some_and(|l| l.decided)
            })
            .unwrap();
        pool.add(&all[..n], &stated);
        taken.push(all[..n].to_vec());
    }
    let display_noise = pool.noise(stated);
    let held = taken
        .iter()
        .zip(&references)
        .zip(spots.iter().zip(&truths))
        .map(|((r, reference), (&box_truth, &truth))| {
            let (mean, _) = covariance::sample(r);
            let test = Sequenced {
                mean,
                n: r.len(),
                reading_lab: display_noise.lab_covariance(mean, WHITE).unwrap(),
                dof: display_noise.dof,
                most,
            };
            let (_, interval, _) = repeated_interval(reference, &test, WHITE).unwrap();
            interval.contains(delta_e76(box_truth.to_lab(WHITE), truth.to_lab(WHITE)))
        })
        .collect();
    let count =
        boxed.iter().map(|b| b.1).sum::<usize>() + taken.iter().map(Vec::len).sum::<usize>();
    (held, count)
}

/// The lean pairs of rules for the two sides of display vs box, with both stoppings in
/// the loop and every patch's truth on the JND (where a verdict turns): the box's spots
/// three times each or by the width rule at 0.3 JND, the display's twice (the verdict
/// rule with one look), each side's figure pooled. Every
/// patch's display-vs-box interval holds its true ΔE*ab in 95 % ± 2 % of 2000 sessions.
#[test]
fn the_lean_rule_pairs_cover_display_vs_box_at_the_jnd() {
    let spots = colorchecker_spots();
    let pairs = [
        (RepeatRule::Fixed { repeats: 3 }, (0.0, 2)),
        (
            RepeatRule::Width {
                half_width_jnd: 0.3,
                most: 10,
            },
            (0.0, 2),
        ),
    ];
    for (box_rule, display) in pairs {
        let sessions: Vec<(Vec<bool>, usize)> = (0..SESSIONS)
            .into_par_iter()
            .map(|s| lab_session(&spots, &box_rule, display, JND_DE76, s))
            .collect();
        let mean_n = sessions.iter().map(|s| s.1 as f64).sum::<f64>() / SESSIONS as f64;
        let mut worst = (0.95f64, 0usize);
        for j in 0..spots.len() {
            let got = share(sessions.iter().filter(|s| s.0[j]).count() as u64, SESSIONS);
            if (got - 0.95).abs() > (worst.0 - 0.95).abs() {
                worst = (got, j + 1);
            }
        }
        let all = share(
            sessions
                .iter()
                .map(|s| s.0.iter().filter(|&&b| b).count() as u64)
                .sum(),
            SESSIONS * spots.len() as u64,
        );
        eprintln!(
            "display vs box, box {} / display verdict margin {} most {}: {all:.3} of all patches, farthest patch {} at {:.1} %, {mean_n:.1} spot readings a session",
            box_rule.describe(),
            display.0,
            display.1,
            worst.1,
            100.0 * worst.0
        );
        assert!(
            (worst.0 - 0.95).abs() <= 0.02,
            "{box_rule:?} {display:?}: patch {} {}",
            worst.1,
            worst.0
        );
    }
}
