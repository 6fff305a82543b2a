//! The adaptive plan's decisions as pure functions of the models fitted so far: the error
//! predicted at a drive value (how far the candidate models' colours lie from the
//! reference model's there), whether the predicted error at the targets is low enough to
//! stop, which drive values the next batch measures, and the held-out patches around the
//! targets. Nothing here measures or reads a file, so a resumed session, which fits the
//! same models to the same readings, makes the same choices.

use crate::color::{delta_e76, Xyz};
use crate::display::{DisplayModel, Sample};

/// Codes (of 255) from a target's drive value to each of its six neighbours, one channel up
/// or down: the colours around a target that a small change of the model moves it to.
pub const NEIGHBOUR_CODES: i32 = 16;
/// Codes by which two patches of one batch differ at least in some channel: a batch spreads
/// over the places of highest disagreement instead of piling onto one.
pub const MIN_SEPARATION_CODES: i32 = 12;
/// Largest offset, in codes per channel, of a held-out patch from its target's drive value.
pub const VERIFY_JITTER_CODES: i32 = 12;

/// Codes (of 255, in every channel) within which a reading is near a drive value: the
/// readings that judge the candidate models there.
pub const NEAR_CODES: f64 = 24.0;

/// The error predicted at drive value `rgb`: the largest ΔE*ab (CIELAB relative to
/// `white`) between the reference model's colour and a candidate's there. Where models
/// fitted to the same readings agree, the readings hold the colour; where they disagree,
/// the reference's colour rests on its assumptions. A candidate that misses the `readings`
/// near `rgb` ([`NEAR_CODES`]) by more than the reference does, plus `slack` (mean ΔE*ab),
/// is contradicted there by measurement and does not count: its disagreement is its own
/// error, which no further reading would remove.
pub fn predicted_error(
    rgb: [f64; 3],
    reference: &dyn DisplayModel,
    candidates: &[&dyn DisplayModel],
    readings: &[Sample],
    slack: f64,
    white: Xyz,
) -> f64 {
    let near: Vec<&Sample> = readings
        .iter()
        .filter(|s| (0..3).all(|k| (s.rgb[k] - rgb[k]).abs() * 255.0 <= NEAR_CODES))
        .collect();
    let miss = |m: &dyn DisplayModel| {
        near.iter()
            .map(|s| delta_e76(m.forward(s.rgb).to_lab(white), s.xyz.to_lab(white)))
            .sum::<f64>()
            / near.len().max(1) as f64
    };
    let allowed = miss(reference) + slack;
    let at = reference.forward(rgb).to_lab(white);
    candidates
        .iter()
        .filter(|m| near.is_empty() || miss(**m) <= allowed)
        .map(|m| delta_e76(m.forward(rgb).to_lab(white), at))
        .filter(|e| e.is_finite())
        .fold(0.0, f64::max)
}

/// What to do after the readings so far.
#[derive(Clone, Debug, PartialEq)]
pub enum Decision {
    /// Measure these drive values next.
    Batch(Vec<[u8; 3]>),
    /// Enough: why.
    Stop(StopReason),
}

/// Why the adaptive plan stopped choosing patches.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The predicted error at every target is below the stopping figure.
    Converged,
    /// The cap on fit readings is reached.
    Cap,
    /// No drive value around the targets is left that is unmeasured and predicted worse
    /// than half the stopping figure.
    NothingLeft,
}

/// The 8-bit code nearest a drive value 0–1.
pub fn code(rgb: [f64; 3]) -> [u8; 3] {
    rgb.map(|d| (d.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// `rgb` moved by `delta` codes in every channel, clamped to the cube.
fn offset(rgb: [u8; 3], delta: [i32; 3]) -> [u8; 3] {
    [0, 1, 2].map(|k| (i32::from(rgb[k]) + delta[k]).clamp(0, 255) as u8)
}

/// The drive values a batch chooses from: each target's, then its six neighbours.
pub fn candidate_codes(target_drives: &[[f64; 3]]) -> Vec<[u8; 3]> {
    let mut out = Vec::with_capacity(7 * target_drives.len());
    for d in target_drives {
        out.push(code(*d));
    }
    for d in target_drives {
        let c = code(*d);
        for k in 0..3 {
            for s in [-NEIGHBOUR_CODES, NEIGHBOUR_CODES] {
                let mut delta = [0; 3];
                delta[k] = s;
                out.push(offset(c, delta));
            }
        }
    }
    out
}

/// Chebyshev distance in codes.
fn distance(a: [u8; 3], b: [u8; 3]) -> i32 {
    (0..3)
        .map(|k| (i32::from(a[k]) - i32::from(b[k])).abs())
        .max()
        .unwrap_or(0)
}

/// The next step: stop when the predicted error at every target's drive value is below
/// `stop_de` or `room` (fit readings left under the cap) is 0; otherwise up to
/// `batch.min(room)` drive values around the targets, highest predicted error first, none
/// already `measured`, none within [`MIN_SEPARATION_CODES`] of another of the batch, none
/// predicted below `stop_de / 2` (there the readings already hold the colour).
pub fn decide(
    target_drives: &[[f64; 3]],
    predicted: &dyn Fn([f64; 3]) -> f64,
    measured: &[[u8; 3]],
    stop_de: f64,
    batch: usize,
    room: usize,
) -> (Decision, f64) {
    let at_targets = target_drives
        .iter()
        .map(|d| predicted(*d))
        .fold(0.0, f64::max);
    if at_targets < stop_de {
        return (Decision::Stop(StopReason::Converged), at_targets);
    }
    if room == 0 {
        return (Decision::Stop(StopReason::Cap), at_targets);
    }
    let mut scored: Vec<(usize, [u8; 3], f64)> = Vec::new();
    for (i, c) in candidate_codes(target_drives).into_iter().enumerate() {
        if measured.contains(&c) || scored.iter().any(|s| s.1 == c) {
            continue;
        }
        let e = predicted(c.map(|v| f64::from(v) / 255.0));
        if e >= stop_de / 2.0 {
            scored.push((i, c, e));
        }
    }
    // Highest first; ties in candidate order, so the choice never depends on a sort's whims.
    scored.sort_by(|a, b| b.2.total_cmp(&a.2).then(a.0.cmp(&b.0)));
    let mut chosen: Vec<[u8; 3]> = Vec::new();
    for (_, c, _) in scored {
        if chosen.len() == batch.min(room) {
            break;
        }
        if chosen
            .iter()
            .all(|o| distance(*o, c) >= MIN_SEPARATION_CODES)
        {
            chosen.push(c);
        }
    }
    if chosen.is_empty() {
        return (Decision::Stop(StopReason::NothingLeft), at_targets);
    }
    (Decision::Batch(chosen), at_targets)
}

/// The targets the held-out set is read near, in target order: every one, or with `count`
/// the `count` whose `predicted` error (the fitted models' disagreement at their drive
/// values) is highest, ties to the earlier target. Where the models disagree most, a model
/// is most likely wrong, so the held-out readings there bound the error at the targets
/// rather than average it away.
pub fn held_out_targets(predicted: &[f64], count: Option<usize>) -> Vec<usize> {
    let mut order: Vec<usize> = (0..predicted.len()).collect();
    if let Some(n) = count.filter(|n| *n < predicted.len()) {
        order.sort_by(|a, b| predicted[*b].total_cmp(&predicted[*a]).then(a.cmp(b)));
        order.truncate(n);
        order.sort_unstable();
    }
    order
}

/// The held-out patches: one per target, at its drive value moved by a seeded offset of at
/// most [`VERIFY_JITTER_CODES`] per channel, drawn again (up to 16 times) while it falls on
/// a fit patch or an earlier held-out one, so the model is judged at and around the
/// targets on readings it was not fitted to.
pub fn verification_codes(target_drives: &[[f64; 3]], fit: &[[u8; 3]], seed: u64) -> Vec<[u8; 3]> {
    let mut rng = metamer_drivers::noise::SplitMix64::new(seed);
    let span = (2 * VERIFY_JITTER_CODES + 1) as u64;
    let mut out: Vec<[u8; 3]> = Vec::with_capacity(target_drives.len());
    for d in target_drives {
        let centre = code(*d);
        let mut pick = centre;
        for _ in 0..16 {
            let r = rng.next_u64();
            let delta = [0, 21, 42].map(|s| ((r >> s) % span) as i32 - VERIFY_JITTER_CODES);
            pick = offset(centre, delta);
            if !fit.contains(&pick) && !out.contains(&pick) {
                break;
            }
        }
        out.push(pick);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::display::Inverse;

    /// An additive display: linear drive times a matrix (the sRGB primaries scaled to a
    /// white of 100 cd/m²), plus `bump` cd/m² of Y added inside a ball of radius 0.15
    /// around `centre` (falling off linearly), so two such models differ only there.
    struct Synthetic {
        bump: f64,
        centre: [f64; 3],
    }

    impl DisplayModel for Synthetic {
        fn name(&self) -> &'static str {
            "synthetic"
        }
        fn forward(&self, rgb: [f64; 3]) -> Xyz {
            let m = [
                [41.24, 35.76, 18.05],
                [21.26, 71.52, 7.22],
                [1.93, 11.92, 95.05],
            ];
            let mut xyz = [0.0; 3];
            for (row, out) in m.iter().zip(&mut xyz) {
                *out = (0..3).map(|k| row[k] * rgb[k]).sum();
            }
            let r = (0..3)
                .map(|k| (rgb[k] - self.centre[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            xyz[1] += self.bump * (1.0 - r / 0.15).max(0.0);
            Xyz::from(xyz)
        }
        fn inverse(&self, _: Xyz) -> Inverse {
            unreachable!("the choice uses forward predictions only")
        }
    }

    const CENTRE: [f64; 3] = [0.75, 0.25, 0.25];

    fn targets() -> Vec<[f64; 3]> {
        // Twelve targets spread over the cube; two of them inside the bump's ball.
        let mut t: Vec<[f64; 3]> = (0..10)
            .map(|i| {
                let f = i as f64 / 9.0;
                [f, 1.0 - f, 0.2 + 0.6 * (i % 3) as f64 / 2.0]
            })
            .collect();
        t.push([0.78, 0.25, 0.22]);
        t.push([0.70, 0.28, 0.26]);
        t
    }

    fn white() -> Xyz {
        Synthetic {
            bump: 0.0,
            centre: CENTRE,
        }
        .forward([1.0; 3])
    }

    /// Two models that differ only around (0.75, 0.25, 0.25): every patch of the batch
    /// goes there (within the ball), the highest-scoring first, all distinct and apart.
    #[test]
    fn the_batch_goes_where_the_models_disagree() {
        let reference = Synthetic {
            bump: 0.0,
            centre: CENTRE,
        };
        let other = Synthetic {
            bump: 3.0,
            centre: CENTRE,
        };
        let w = white();
        let predicted = |rgb| predicted_error(rgb, &reference, &[&other], &[], 0.5, w);
        let t = targets();
        let (decision, worst) = decide(&t, &predicted, &[], 1.0, 8, 100);
        assert!(worst > 1.0, "{worst}");
        let Decision::Batch(codes) = decision else {
            panic!("the models disagree by {worst}: {decision:?}")
        };
        assert!(!codes.is_empty() && codes.len() <= 8, "{codes:?}");
        for c in &codes {
            let r = (0..3)
                .map(|k| (f64::from(c[k]) / 255.0 - CENTRE[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(r < 0.15, "{c:?} is {r:.3} from the disagreement");
        }
        for (i, a) in codes.iter().enumerate() {
            for b in &codes[i + 1..] {
                assert!(distance(*a, *b) >= MIN_SEPARATION_CODES, "{a:?} {b:?}");
            }
        }
        // The first is the candidate of highest disagreement: the target nearest the
        // centre, (0.78, 0.25, 0.22) → codes (199, 64, 56), is 0.042 away; its neighbour
        // one red step down, (183, 64, 56), is 0.041 away and scores higher.
        let best = candidate_codes(&t)
            .into_iter()
            .max_by(|a, b| {
                predicted(a.map(|v| f64::from(v) / 255.0))
                    .total_cmp(&predicted(b.map(|v| f64::from(v) / 255.0)))
            })
            .unwrap();
        assert_eq!(codes[0], best);
        // Once measured, those codes are not chosen again.
        let (again, _) = decide(&t, &predicted, &codes, 1.0, 8, 100);
        if let Decision::Batch(next) = again {
            assert!(next.iter().all(|c| !codes.contains(c)), "{next:?}");
        }
    }

    /// The stopping figure: by hand, a bump of b cd/m² of Y alone (X and Z unchanged) on a
    /// target whose Y is Y_t moves f(Y/Y_w) by about δ = (Y_t/Y_w)^(−2/3)·b/(3·Y_w), so L*
    /// by 116δ, a* by −500δ and b* by 200δ: ΔE*ab ≈ δ·√(116² + 500² + 200²). Models that agree stop at once;
    /// models that disagree above the figure go on, below it stop; a full cap stops.
    #[test]
    fn the_plan_stops_below_the_figure_or_at_the_cap() {
        let reference = Synthetic {
            bump: 0.0,
            centre: CENTRE,
        };
        let w = white();
        let t = vec![CENTRE];
        let y_t = reference.forward(CENTRE)[1];
        let de_per_cd = (116f64.powi(2) + 500f64.powi(2) + 200f64.powi(2)).sqrt() / 3.0
            * (y_t / w[1]).powf(-2.0 / 3.0)
            / w[1];
        for (bump, stop_de, want) in [
            (0.0, 1.0, Some(StopReason::Converged)),
            (1.5 / de_per_cd, 1.0, None),
            (1.5 / de_per_cd, 2.0, Some(StopReason::Converged)),
        ] {
            let other = Synthetic {
                bump,
                centre: CENTRE,
            };
            let predicted = |rgb| predicted_error(rgb, &reference, &[&other], &[], 0.5, w);
            let (decision, at) = decide(&t, &predicted, &[], stop_de, 8, 100);
            // The linearised ΔE: within 2 % of the exact one for this small a step.
            assert!((at - bump * de_per_cd).abs() < 0.02 * 1.5 + 1e-9, "{at}");
            match want {
                Some(reason) => assert_eq!(decision, Decision::Stop(reason)),
                None => assert!(matches!(decision, Decision::Batch(_)), "{decision:?}"),
            }
            if want.is_none() {
                let (capped, _) = decide(&t, &predicted, &[], stop_de, 8, 0);
                assert_eq!(capped, Decision::Stop(StopReason::Cap));
                // Room for 3: a batch of at most 3.
                let (Decision::Batch(b), _) = decide(&t, &predicted, &[], stop_de, 8, 3) else {
                    panic!("room for 3")
                };
                assert!(b.len() <= 3);
                // Every candidate measured: nothing left.
                let all = candidate_codes(&t);
                let (left, _) = decide(&t, &predicted, &all, stop_de, 8, 100);
                assert_eq!(left, Decision::Stop(StopReason::NothingLeft));
            }
        }
    }

    /// A reading near the disagreement that the reference holds and the candidate misses
    /// by 3 cd/m² of Y (ΔE*ab well above the slack) rules the candidate out there: nothing
    /// is predicted; a reading the candidate holds as well keeps it.
    #[test]
    fn a_candidate_the_readings_near_by_contradict_does_not_count() {
        let reference = Synthetic {
            bump: 0.0,
            centre: CENTRE,
        };
        let other = Synthetic {
            bump: 3.0,
            centre: CENTRE,
        };
        let w = white();
        let at = [0.76, 0.25, 0.25];
        let free = predicted_error(at, &reference, &[&other], &[], 0.5, w);
        assert!(free > 1.0, "{free}");
        let truth = |m: &Synthetic, rgb| Sample {
            rgb,
            xyz: m.forward(rgb),
        };
        let held = [truth(&reference, CENTRE)];
        assert_eq!(
            predicted_error(at, &reference, &[&other], &held, 0.5, w),
            0.0
        );
        // The reading is the candidate's: the reference misses it by as much, so both count.
        let theirs = [truth(&other, CENTRE)];
        let both = predicted_error(at, &reference, &[&other], &theirs, 0.5, w);
        assert!((both - free).abs() < 1e-12, "{both} {free}");
        // A reading far away (more than 24 codes) judges nothing here.
        let far = [truth(&reference, [0.2, 0.2, 0.2])];
        assert_eq!(
            predicted_error(at, &reference, &[&other], &far, 0.5, w),
            free
        );
    }

    /// The count keeps the targets of highest predicted error, in target order; a tie goes
    /// to the earlier target; no count, or one above the targets, keeps them all.
    #[test]
    fn the_held_out_set_keeps_the_least_certain_targets() {
        let predicted = [0.5, 3.0, 1.0, 3.0, f64::NAN, 2.0];
        // NaN sorts above every number in total_cmp: a target whose models give no colour
        // is among the least certain.
        assert_eq!(held_out_targets(&predicted, Some(3)), vec![1, 3, 4]);
        assert_eq!(held_out_targets(&predicted[..4], Some(1)), vec![1]);
        assert_eq!(held_out_targets(&predicted, None), vec![0, 1, 2, 3, 4, 5]);
        assert_eq!(
            held_out_targets(&predicted, Some(9)),
            vec![0, 1, 2, 3, 4, 5]
        );
    }

    #[test]
    fn held_out_patches_are_near_their_targets_seeded_and_not_fit_patches() {
        let t = targets();
        let fit = candidate_codes(&t);
        let a = verification_codes(&t, &fit, 7);
        assert_eq!(a, verification_codes(&t, &fit, 7));
        assert_ne!(a, verification_codes(&t, &fit, 8));
        assert_eq!(a.len(), t.len());
        for (v, d) in a.iter().zip(&t) {
            assert!(distance(*v, code(*d)) <= VERIFY_JITTER_CODES, "{v:?} {d:?}");
            assert!(!fit.contains(v), "{v:?} is a fit patch");
        }
    }
}
