//! Where the fall-off is read next: at the plan's unread angle where the distribution
//! models the fit finds plausible disagree most.
//!
//! Plausible: fitted, and with a leave-one-out RMS at most twice the tie limit of the best
//! ([`cv::tie_limit`]) or too few angles yet to be cross-validated (a model that cannot
//! be judged yet cannot be ruled out): the models `auto` could still come to prefer as
//! angles are added. Where they agree, any of them gives the spots the same light; a
//! reading there cannot change the table the scene carries by more than their spread.

use super::decision::RoundDecision;
use super::rule::AdaptiveRule;
use crate::light::fit::{cv, LdcFit};
use crate::measure_box::falloff::fit_light;
use crate::measure_box::plan::{BoxPlan, BoxStep, Plane, Target};
use crate::session::Entry;

/// The fall-off readings taken: (plane, signed angle, mean luminance) in first-read order.
pub fn falloff_read(taken: &[Entry<BoxStep>]) -> Vec<(Plane, f64, f64)> {
    let mut sums: Vec<(Plane, f64, f64, usize)> = Vec::new();
    for e in taken {
        if let Target::Falloff { plane, angle_deg } = e.data.target {
            match sums.iter_mut().find(|s| s.0 == plane && s.1 == angle_deg) {
                Some(s) => {
                    s.2 += e.reading.xyz[1];
                    s.3 += 1;
                }
                None => sums.push((plane, angle_deg, e.reading.xyz[1], 1)),
            }
        }
    }
    sums.into_iter()
        .map(|(p, a, y, n)| (p, a, y / n as f64))
        .collect()
}

/// The plausible models' relative luminance at (C, γ), each as `fit` would give it had it
/// chosen that model.
fn plausible_values(fit: &LdcFit, c_deg: f64, gamma_deg: f64) -> Vec<f64> {
    let best = fit
        .candidates
        .iter()
        .filter(|c| !c.halves.is_empty())
        .filter_map(|c| c.cv_rms)
        .fold(f64::INFINITY, f64::min);
    if !best.is_finite() {
        return Vec::new();
    }
    let limit = 2.0 * cv::tie_limit(best);
    fit.candidates
        .iter()
        .filter(|c| !c.halves.is_empty() && c.cv_rms.is_none_or(|r| r <= limit))
        .map(|c| {
            let as_chosen = LdcFit {
                halves: c.halves.clone(),
                ..fit.clone()
            };
            as_chosen.relative(c_deg, gamma_deg)
        })
        .collect()
}

/// The largest disagreement of the plausible models at each of `angles` (plane, signed
/// degrees), in the order given.
pub fn disagreement(fit: &LdcFit, angles: &[(Plane, f64)]) -> Vec<f64> {
    angles
        .iter()
        .map(|&(plane, a)| {
            let (c, g) = plane.c_gamma(a);
            let v = plausible_values(fit, c, g);
            let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
            if v.len() < 2 {
                0.0
            } else {
                hi - lo
            }
        })
        .collect()
}

/// The fall-off's next round: the unread angle of the plan where the plausible models
/// disagree most, unless they agree within the rule's figure or the cap is reached.
pub fn choose(plan: &BoxPlan, rule: &AdaptiveRule, taken: &[Entry<BoxStep>]) -> RoundDecision {
    let read = falloff_read(taken);
    let unread: Vec<(Plane, f64)> = [Plane::Horizontal, Plane::Vertical]
        .into_iter()
        .flat_map(|p| plan.falloff_angles_deg.iter().map(move |&a| (p, a)))
        .filter(|&(p, a)| {
            let t = Target::Falloff {
                plane: p,
                angle_deg: a,
            };
            !read.iter().any(|r| {
                t.same_reading(&Target::Falloff {
                    plane: r.0,
                    angle_deg: r.1,
                })
            })
        })
        .collect();
    let fit = match fit_light(&read) {
        Ok(fit) => fit,
        Err(e) => {
            return RoundDecision {
                next: unread
                    .iter()
                    .map(|&(plane, angle_deg)| Target::Falloff { plane, angle_deg })
                    .collect(),
                figure: f64::NAN,
                why: format!(
                    "the fall-off cannot be fitted to the first angles ({e}): every angle is read"
                ),
            }
        }
    };
    let spread = disagreement(&fit, &unread);
    let worst = spread
        .iter()
        .enumerate()
        .fold(None::<(usize, f64)>, |w, (i, &s)| match w {
            Some((_, ws)) if ws >= s => w,
            _ => Some((i, s)),
        });
    let figure = worst.map_or(0.0, |w| w.1);
    let stop = |why: String| RoundDecision {
        next: Vec::new(),
        figure,
        why,
    };
    match worst {
        None => stop("every angle of the plan is read".into()),
        Some(_) if figure <= rule.angle_agreement => stop(format!(
            "the plausible models agree within {figure:.4} of the normal luminance at every unread angle (at most {})",
            rule.angle_agreement
        )),
        Some(_) if read.len() >= rule.max_falloff => stop(format!(
            "{} angles read, the most the rule reads; the plausible models still differ by {figure:.4}",
            read.len()
        )),
        Some((i, _)) => {
            let (plane, angle_deg) = unread[i];
            RoundDecision {
                next: vec![Target::Falloff { plane, angle_deg }],
                figure,
                why: format!(
                    "the plausible models differ by {figure:.4} of the normal luminance (more than {}) most at {angle_deg}° in the {} plane",
                    rule.angle_agreement,
                    plane.name()
                ),
            }
        }
    }
}
