//! Leave-one-out cross-validation over the angles of a half-plane, and the rule by which
//! `auto` picks a model from the scores.

use super::models::{fit_half, fit_plane, HalfPoints, LdcModel};

/// Held-out errors (prediction − reading, relative luminance) of a half-plane `model` in
/// one half-plane: each off-normal angle is left out once, the model fitted to the others,
/// and evaluated at the one left out. `None` when a fit without one angle would have fewer
/// angles than the model needs.
pub fn leave_one_out(model: LdcModel, gamma_deg: &[f64], y: &[f64]) -> Option<Vec<f64>> {
    let n = gamma_deg.len();
    if n == 0 || n - 1 < model.min_angles().0 {
        return None;
    }
    let mut errors = Vec::with_capacity(n);
    for k in 0..n {
        let (g, v) = without(gamma_deg, y, k);
        let p = fit_half(model, &g, &v);
        errors.push(p.eval(gamma_deg[k]) - y[k]);
    }
    Some(errors)
}

/// Held-out errors of `model` over one plane, `pos` half's angles first, then `neg`'s:
/// each off-normal angle of either half is left out once and the model fitted to the rest
/// of the plane (a half-plane model only to the rest of its half). `None` when a fit
/// without one angle would lack angles the model needs.
pub fn leave_one_out_plane(model: LdcModel, pos: HalfPoints, neg: HalfPoints) -> Option<Vec<f64>> {
    if !model.per_plane() {
        let mut e = leave_one_out(model, pos.0, pos.1)?;
        e.extend(leave_one_out(model, neg.0, neg.1)?);
        return Some(e);
    }
    let (half, plane) = model.min_angles();
    let (np, nn) = (pos.0.len(), neg.0.len());
    if np.min(nn) < half + 1 || np + nn < plane + 1 {
        return None;
    }
    let mut errors = Vec::with_capacity(np + nn);
    for (side, (g, y)) in [pos, neg].into_iter().enumerate() {
        for k in 0..g.len() {
            let (g2, y2) = without(g, y, k);
            let p = if side == 0 {
                fit_plane(model, (&g2, &y2), neg)
            } else {
                fit_plane(model, pos, (&g2, &y2))
            };
            errors.push(p[side].eval(g[k]) - y[k]);
        }
    }
    Some(errors)
}

fn without(g: &[f64], y: &[f64], k: usize) -> (Vec<f64>, Vec<f64>) {
    let keep = |i: &usize| *i != k;
    (
        (0..g.len()).filter(keep).map(|i| g[i]).collect(),
        (0..y.len()).filter(keep).map(|i| y[i]).collect(),
    )
}

/// A model is as good as the best when its cross-validated RMS is within this fraction of
/// the lowest…
pub const RELATIVE_TIE: f64 = 0.10;
/// …or this far above it in relative luminance (below a reading's last digit at 2
/// decimals, the resolution of a typical fall-off table).
pub const ABSOLUTE_TIE: f64 = 0.0005;

/// The CV RMS at or below which a model ties the lowest, `best`.
pub fn tie_limit(best: f64) -> f64 {
    best * (1.0 + RELATIVE_TIE) + ABSOLUTE_TIE
}

/// One candidate's score for [`choose`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Score {
    pub model: LdcModel,
    /// Free parameters over both planes.
    pub parameters: usize,
    /// Leave-one-out RMS; `None` = not cross-validated.
    pub cv_rms: Option<f64>,
}

/// The index of the chosen model among `scores` and why: the simplest model (fewest
/// parameters, the earlier on a tie) whose CV RMS ties the lowest, so a richer model has
/// to predict held-out angles clearly better to be chosen.
pub fn choose(scores: &[Score]) -> Option<(usize, String)> {
    let (best_i, best) = scores
        .iter()
        .enumerate()
        .filter_map(|(i, s)| s.cv_rms.map(|v| (i, v)))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let limit = tie_limit(best);
    let (i, chosen) = scores
        .iter()
        .enumerate()
        .filter(|(_, s)| s.cv_rms.is_some_and(|v| v <= limit))
        .min_by_key(|(_, s)| s.parameters)?;
    let (model, score) = (chosen.model, chosen.cv_rms.unwrap_or(best));
    let best_model = scores[best_i].model;
    let why = if i == best_i {
        let runner_up = scores
            .iter()
            .filter(|s| s.model != model && s.cv_rms.is_some())
            .min_by(|a, b| {
                a.cv_rms
                    .unwrap_or(f64::MAX)
                    .total_cmp(&b.cv_rms.unwrap_or(f64::MAX))
            })
            .map(|s| (s.model, s.cv_rms));
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
             lowest ({best_model}, {best:.5}) with fewer parameters ({} vs {})",
            RELATIVE_TIE * 100.0,
            chosen.parameters,
            scores[best_i].parameters
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
        let score = |model: LdcModel, cv_rms| Score {
            model,
            parameters: 2 * model.parameters(4),
            cv_rms,
        };
        let s = [
            score(Lambertian, Some(0.1)),
            score(CosPower, Some(0.0104)),
            score(CosPoly, None),
            score(Lobes, Some(0.01)),
        ];
        let (i, why) = choose(&s).unwrap();
        assert_eq!(s[i].model, CosPower, "{why}");
        let s = [score(CosPower, Some(0.02)), score(Lobes, Some(0.01))];
        assert_eq!(s[choose(&s).unwrap().0].model, Lobes);
        // A series ties lobes with fewer parameters; a spline has to be clearly better.
        let s = [
            score(Lobes, Some(0.0105)),
            score(Series, Some(0.0106)),
            score(Spline, Some(0.01)),
        ];
        let (i, why) = choose(&s).unwrap();
        assert_eq!(s[i].model, Series, "{why}");
        assert!(why.contains("(10 vs 20)"), "{why}");
        assert!(choose(&[score(Lobes, None)]).is_none());
    }

    #[test]
    fn a_plane_model_is_left_out_across_the_whole_plane() {
        // cos^0.8·(1 + 0.1 sin x) is a series: every held-out error is tiny, and there is
        // one per angle of both halves.
        let f = |x: f64| x.to_radians().cos().powf(0.8) * (1.0 + 0.1 * x.to_radians().sin());
        let g: Vec<f64> = (1..=4).map(|k| 20.0 * k as f64).collect();
        let yp: Vec<f64> = g.iter().map(|&g| f(g)).collect();
        let yn: Vec<f64> = g.iter().map(|&g| f(-g)).collect();
        let e = leave_one_out_plane(LdcModel::Series, (&g, &yp), (&g, &yn)).unwrap();
        assert_eq!(e.len(), 8);
        assert!(e.iter().all(|e| e.abs() < 1e-5), "{e:?}");
        // Two angles in a half: the series can be fitted, not cross-validated.
        assert!(leave_one_out_plane(LdcModel::Series, (&g[..2], &yp[..2]), (&g, &yn)).is_none());
    }
}
