//! Leave-one-out cross-validation over the angles of a half-plane, and the rule by which
//! `auto` picks a model from the scores.

use super::models::{fit_half, LdcModel};

/// Held-out errors (prediction − reading, relative luminance) of `model` in one half-plane:
/// each off-normal angle is left out once, the model fitted to the others, and evaluated
/// at the one left out. `None` when a fit without one angle would have fewer angles than
/// parameters.
pub fn leave_one_out(model: LdcModel, gamma_deg: &[f64], y: &[f64]) -> Option<Vec<f64>> {
    let n = gamma_deg.len();
    if n == 0 || n - 1 < model.parameters() {
        return None;
    }
    let mut errors = Vec::with_capacity(n);
    for k in 0..n {
        let g: Vec<f64> = (0..n).filter(|&i| i != k).map(|i| gamma_deg[i]).collect();
        let v: Vec<f64> = (0..n).filter(|&i| i != k).map(|i| y[i]).collect();
        let p = fit_half(model, &g, &v);
        errors.push(p.eval(gamma_deg[k]) - y[k]);
    }
    Some(errors)
}

/// A model is as good as the best when its cross-validated RMS is within this fraction of
/// the lowest…
pub const RELATIVE_TIE: f64 = 0.10;
/// …or this far above it in relative luminance (below a reading's last digit at 2
/// decimals, the resolution of a typical fall-off table).
pub const ABSOLUTE_TIE: f64 = 0.0005;

/// The index of the chosen model among `scores` (model, CV RMS; `None` = not
/// cross-validated) and why: the simplest model (fewest parameters) whose CV RMS ties the
/// lowest, so a richer model has to predict held-out angles clearly better to be chosen.
pub fn choose(scores: &[(LdcModel, Option<f64>)]) -> Option<(usize, String)> {
    let (best_i, best) = scores
        .iter()
        .enumerate()
        .filter_map(|(i, (_, s))| s.map(|s| (i, s)))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let limit = best * (1.0 + RELATIVE_TIE) + ABSOLUTE_TIE;
    let (i, (model, score)) = scores
        .iter()
        .enumerate()
        .filter(|(_, (_, s))| s.is_some_and(|s| s <= limit))
        .min_by_key(|(_, (m, _))| m.parameters())?;
    let score = score.unwrap_or(best);
    let best_model = scores[best_i].0;
    let why = if i == best_i {
        let runner_up = scores
            .iter()
            .filter(|(m, s)| *m != *model && s.is_some())
            .min_by(|a, b| a.1.unwrap_or(f64::MAX).total_cmp(&b.1.unwrap_or(f64::MAX)));
        match runner_up {
            Some((m, Some(s))) => format!(
                "{model}: the lowest leave-one-out RMS ({score:.5}); next {m} ({s:.5}), \
                 no simpler model within {:.0} % + {ABSOLUTE_TIE} of it",
                RELATIVE_TIE * 100.0
            ),
            _ => format!("{model}: the only model that could be cross-validated ({score:.5})"),
        }
    } else {
        format!(
            "{model}: leave-one-out RMS {score:.5} is within {:.0} % + {ABSOLUTE_TIE} of the \
             lowest ({best_model}, {best:.5}) with fewer parameters per half-plane ({} vs {})",
            RELATIVE_TIE * 100.0,
            model.parameters(),
            best_model.parameters()
        )
    };
    Some((i, why))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn held_out_errors_vanish_for_the_generating_model() {
        let g: Vec<f64> = (1..=6).map(|k| 12.0 * k as f64).collect();
        let y: Vec<f64> = g
            .iter()
            .map(|x: &f64| x.to_radians().cos().powf(2.5))
            .collect();
        let e = leave_one_out(LdcModel::CosPower, &g, &y).unwrap();
        assert!(e.iter().all(|e| e.abs() < 1e-6), "{e:?}");
        // Lambertian predicts 1: the held-out error is the fall-off itself.
        let e = leave_one_out(LdcModel::Lambertian, &g, &y).unwrap();
        assert!((e[0] - (1.0 - y[0])).abs() < 1e-12);
        assert!(leave_one_out(LdcModel::Lobes, &g[..3], &y[..3]).is_none());
    }

    #[test]
    fn the_simplest_tying_model_wins() {
        use LdcModel::*;
        let s = [
            (Lambertian, Some(0.1)),
            (CosPower, Some(0.0104)),
            (CosPoly, None),
            (Lobes, Some(0.01)),
        ];
        let (i, why) = choose(&s).unwrap();
        assert_eq!(s[i].0, CosPower, "{why}");
        let s = [(CosPower, Some(0.02)), (Lobes, Some(0.01))];
        assert_eq!(s[choose(&s).unwrap().0].0, Lobes);
        assert!(choose(&[(Lobes, None)]).is_none());
    }
}
