//! The report's measuring-cost section: each measuring stage's budget against what it
//! took (and another run's, when one is compared), and the chart of each side's accuracy
//! against its readings and minutes (`validation::cost_curve`).

use std::fmt::Write;

use super::sections::inline_svg;
use crate::validation::assess::JND_DE76;
use crate::validation::cost_curve::{charts, THIS_RUN};
use crate::validation::figures::esc;
use crate::validation::report_data::{ComparedCost, CostFigures, ReportInput, StageCost};

/// The measuring stages' budgets against what they took, a total row under them (and the
/// compared run's rows after), then the accuracy chart: what the verdict cost at the rig,
/// in readings, the operator's placements and minutes, and what it bought.
pub fn cost_section(h: &mut String, input: &ReportInput) {
    h.push_str(
        "<h2 id=\"cost\">Measuring cost</h2>\n<p>Each measuring stage's budget, made before its \
         first reading, and what it took: the instrument's time at its real pace (a simulated \
         instrument's too, whatever its time scale) and the session's length at the rig \
         (instrument, operator and settle time; what was taken counts the operator's actual \
         waits, none for a simulated operator).</p>\n",
    );
    cost_table(h, &input.measuring_cost, input.compared_cost.as_ref());
    cost_chart(h, input);
}

/// The chart of accuracy against cost, its caption and the curves' last points.
fn cost_chart(h: &mut String, input: &ReportInput) {
    let curves = &input.cost_curves;
    if curves.iter().all(|c| c.points.is_empty()) {
        return;
    }
    let [readings, minutes] = match charts(curves) {
        Ok(svgs) => svgs,
        Err(e) => {
            let _ = writeln!(
                h,
                "<p>(the accuracy chart could not be drawn: {})</p>",
                esc(&e)
            );
            return;
        }
    };
    let compared = input
        .compared_cost
        .as_ref()
        .map(|c| format!(" Solid lines: this run; dashed: {}.", esc(&c.run)))
        .unwrap_or_default();
    let _ = writeln!(
        h,
        "<figure id=\"cost-chart\"><div class=\"scroll\">{}</div><div class=\"scroll\">{}</div>\
         <figcaption><b>Accuracy against measuring cost.</b> Top: against readings; bottom: \
         against the minutes a rig takes for them (each reading at its stage's budgeted \
         instrument and settle time per reading, at the instrument's real pace, and every \
         placement of the stage at the budget's time per placement). Box and display spots: the median over the \
         patches of the 95 % half-width (ΔE*ab) of each patch's mean reading in CIELAB \
         relative to the display's white, had every patch stopped after its first m readings \
         (m = 1, 2, …; the last point is the run as measured); one reading's noise is the \
         meter's stated repeatability scaled by the figure pooled over all of the side's \
         readings. It is that side's share of the verdict intervals, which hold both sides'. \
         Display model: the largest ΔE*ab between the candidate models' predictions at the \
         colours to reproduce, before each batch of an adaptive plan and when it stopped; held \
         out: the largest ΔE*ab between the model and the readings it was not fitted to, at the \
         fit and held-out readings together. The dotted black line is the JND (ΔE*ab {JND_DE76}).{compared}\
         </figcaption></figure>",
        inline_svg(&readings),
        inline_svg(&minutes),
    );
    h.push_str(
        "<div class=\"scroll\"><table id=\"cost-curves\"><tr><th class=\"l\">side</th>\
         <th class=\"l\">plan</th><th class=\"l\">run</th><th>readings</th><th>minutes</th>\
         <th>ΔE*ab</th></tr>",
    );
    for c in curves {
        let Some(last) = c.points.last() else {
            continue;
        };
        let _ = write!(
            h,
            "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td>{:.2}</td><td>{:.3}</td></tr>",
            esc(&c.side),
            esc(&c.plan),
            esc(if c.run == THIS_RUN { THIS_RUN } else { &c.run }),
            last.readings,
            last.minutes,
            last.value
        );
    }
    h.push_str("</table></div>\n");
}

/// The measuring stages' budgets against what they took, a total row under them: what the
/// verdict cost at the rig, in readings, the operator's placements and minutes.
fn cost_table(h: &mut String, stages: &[StageCost], compared: Option<&ComparedCost>) {
    h.push_str(
        "<div class=\"scroll\"><table><tr><th>stage</th><th>readings</th><th>placements</th>\
         <th>calibrations</th><th>instrument</th><th>at the rig</th></tr>",
    );
    stage_rows(h, stages, "");
    if let Some(c) = compared {
        stage_rows(h, &c.stages, &format!(" ({})", c.run));
    }
    h.push_str("</table></div>\n");
}

/// One row per stage of one run and their total, each stage's name followed by `run`.
fn stage_rows(h: &mut String, stages: &[StageCost], run: &str) {
    let minutes = |s: f64| format!("{:.1} min", s / 60.0);
    let pair = |budget: String, taken: Option<String>| match taken {
        Some(t) if t != budget => format!("{} (budget {})", esc(&t), esc(&budget)),
        Some(t) => esc(&t),
        None => format!("budget {} (not run)", esc(&budget)),
    };
    let mut total = StageCost {
        stage: "all".into(),
        taken: stages
            .iter()
            .all(|s| s.taken.is_some())
            .then(CostFigures::default),
        ..StageCost::default()
    };
    for s in stages {
        add(&mut total.budget, &s.budget);
        if let (Some(t), Some(a)) = (&mut total.taken, &s.taken) {
            add(t, a);
        }
    }
    for s in stages.iter().chain(std::iter::once(&total)) {
        let t = s.taken.as_ref();
        let _ = write!(
            h,
            "<tr><td class=\"l\">{}{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&s.stage),
            esc(run),
            pair(s.budget.readings.to_string(), t.map(|t| t.readings.to_string())),
            pair(s.budget.placements.to_string(), t.map(|t| t.placements.to_string())),
            pair(
                s.budget.calibrations.to_string(),
                t.map(|t| t.calibrations.to_string())
            ),
            pair(minutes(s.budget.instrument_s), t.map(|t| minutes(t.instrument_s))),
            pair(minutes(s.budget.rig_s), t.map(|t| minutes(t.rig_s))),
        );
    }
}

fn add(sum: &mut CostFigures, c: &CostFigures) {
    sum.readings += c.readings;
    sum.placements += c.placements;
    sum.calibrations += c.calibrations;
    sum.instrument_s += c.instrument_s;
    sum.rig_s += c.rig_s;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cost table: each stage's figures, what was taken beside a differing budget,
    /// "not run" without a cost taken, and the total of the stages (hand sums).
    #[test]
    fn the_cost_table_sums_the_stages_and_shows_each_budget_beside_what_was_taken() {
        let f = |readings, placements, instrument_s, rig_s| CostFigures {
            readings,
            placements,
            calibrations: 0,
            instrument_s,
            rig_s,
        };
        let stages = [
            StageCost {
                stage: "display".into(),
                budget: f(194, 0, 34.07, 34.07),
                taken: Some(f(194, 0, 34.07, 34.07)),
            },
            StageCost {
                stage: "display-spots".into(),
                budget: f(72, 24, 12.64, 732.64),
                taken: Some(f(56, 24, 9.84, 9.84)),
            },
        ];
        let mut h = String::new();
        cost_table(&mut h, &stages, None);
        assert!(
            h.contains("<td class=\"l\">display</td><td>194</td><td>0</td>"),
            "{h}"
        );
        // 732.64 s is 12.2 min, 9.84 s is 0.2 min; 56 readings of a budget of 72.
        assert!(h.contains("<td>56 (budget 72)</td>"), "{h}");
        assert!(h.contains("<td>0.2 min (budget 12.2 min)</td></tr>"), "{h}");
        // The total: 194 + 56 taken of 194 + 72, 34.07 + 9.84 = 43.91 s of 46.71 s.
        assert!(
            h.contains("<td class=\"l\">all</td><td>250 (budget 266)</td><td>24</td>"),
            "{h}"
        );
        assert!(h.contains("<td>0.7 min (budget 0.8 min)</td>"), "{h}");
        let mut h = String::new();
        let mut not_run = stages[1].clone();
        not_run.taken = None;
        cost_table(&mut h, &[not_run], None);
        assert!(h.contains("budget 72 (not run)"), "{h}");
    }

    /// With a compared run: its stages' rows and total after this run's, the chart drawn
    /// against readings and minutes with a line per run, and each line's last point.
    #[test]
    fn a_compared_run_joins_the_table_and_the_chart() {
        use crate::validation::cost_curve::{CostCurve, CurvePoint, BOX_SPOTS};
        let f = |readings| CostFigures {
            readings,
            ..CostFigures::default()
        };
        let stage = |readings| StageCost {
            stage: "box".into(),
            budget: f(readings),
            taken: Some(f(readings)),
        };
        let point = |readings, minutes, value| CurvePoint {
            readings,
            minutes,
            value,
        };
        let curve = |plan: &str, run: &str, last| CostCurve {
            side: BOX_SPOTS.into(),
            plan: plan.into(),
            run: run.into(),
            measure: String::new(),
            points: vec![point(24, 12.0, 0.6), last],
        };
        let input = ReportInput {
            measuring_cost: vec![stage(72)],
            compared_cost: Some(ComparedCost {
                run: "fixed-run".into(),
                stages: vec![stage(120)],
            }),
            cost_curves: vec![
                curve("until narrow enough", THIS_RUN, point(72, 12.2, 0.35)),
                curve("fixed, 5 readings", "fixed-run", point(120, 12.4, 0.27)),
            ],
            ..ReportInput::default()
        };
        let mut h = String::new();
        cost_section(&mut h, &input);
        assert!(h.contains("<td class=\"l\">all</td><td>72</td>"), "{h}");
        assert!(
            h.contains("<td class=\"l\">all (fixed-run)</td><td>120</td>"),
            "{h}"
        );
        assert!(
            h.contains("id=\"cost\"") && h.contains("id=\"cost-chart\""),
            "{h}"
        );
        assert!(h.contains("dashed: fixed-run."), "{h}");
        for line in [
            "box spots, until narrow enough (this run)",
            "box spots, fixed, 5 readings (fixed-run)",
        ] {
            assert_eq!(h.matches(line).count(), 2, "{line}");
        }
        assert!(h.contains("<td>72</td><td>12.20</td><td>0.350</td>"), "{h}");
        assert!(
            h.contains("<td>120</td><td>12.40</td><td>0.270</td>"),
            "{h}"
        );
    }
}
